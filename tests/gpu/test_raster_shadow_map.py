"""Shadow maps on the GPU (`gpu_shader.raster_shadow_map`) against the NumPy shadow map
(`reference_cpu.shadow_map`), texel by texel and pixel by pixel.

Both take the light's view from `reference_cpu.shadow_map.light_view`, so they draw the same
map: OpenGL in float32 arithmetic, NumPy in float64 rounded to float32 when stored. They may
differ where a pixel's depth is within float32 rounding of the stored depth plus the bias
(`ROUNDING`), or where its point falls within `EDGE` of a texel's edge; at most
`HANDFUL_PIXELS` pixels. Measured on llvmpipe on "cube and cone on a floor" at 96 x 72 with
a 1024 map, bias 1 mm and slope bias 1.5: no pixel differs for the point and directional
lights, and one (within 1.5e-7 m of the threshold) for the point light with 5 x 5 PCF.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gpu_shader import raster_shadow_map as gpu_map
from marchlab.compare import outside_range
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu import shadow_map as numpy_map
from reference_cpu.rasterise import rasterise
from reference_cpu.shadow_volumes import shadow_volume_visibility
from scene_model.camera import turned
from scene_model.geometry import normalize
from scene_model.scene import DirectionalLight, PointLight
from subpixel import around

MESHES = SCENES["cube and cone on a floor"]
LIGHTS = {"point": PointLight(position=(-1.0, 3.0, -2.5)),
          "directional": DirectionalLight(direction=(0.5, -1.0, 0.9))}
SIZE = 1024
GOOD_BIAS, GOOD_SLOPE = 1e-3, 1.5
HANDFUL_PIXELS = 3
ROUNDING = 1e-5         # m: a few float32 steps of a depth of 1 to 7 m (one is 4.8e-7 at 4 m)
EDGE = 1e-2             # texels
# On a hardware GPU the map itself is drawn from vertices snapped to 1/256 of a texel, which
# moves its depths and its triangles' edges a little (measured on an H100: one pixel of 6,912
# went the other way, 5.7e-5 m from the threshold and 0.022 texels from an edge).
ROUNDING_HARDWARE = 1e-4
EDGE_HARDWARE = 5e-2


def test_gpu_depth_map_is_the_numpy_depth_map(gpu):
    """The map itself: the same texels drawn, each holding the same depth to float32
    rounding. Measured at 1024: no texel drawn by one and not the other; 99.9% of depths
    within 3.4e-6 m, the worst 7.2e-6 m (point) and 9.5e-5 m (directional, on a cube face
    nearly edge-on to the light, whose depth changes 0.25 m across one texel)."""
    for light in LIGHTS.values():
        view = numpy_map.light_view(MESHES, light, SIZE)
        reference = numpy_map.depth_map(MESHES, view)
        assert np.isfinite(reference).sum() > 0.1 * SIZE * SIZE     # the map sees the scene
        assert_same_map(view, reference)


def assert_same_map(view, reference):
    """The GPU's map of ``view`` holds the NumPy map's texels (on a hardware GPU, within the
    range of the NumPy maps around each texel's centre) to float32 rounding."""
    candidate = gpu_map.depth_map(MESHES, view)
    drawn = np.isfinite(reference)
    assert (drawn != np.isfinite(candidate)).sum() <= 10
    maps = [reference, *around(lambda dx, dy: numpy_map.depth_map(
        MESHES, turned_view(view, dx, dy)))]
    both = drawn & np.isfinite(candidate) & np.all(np.isfinite(maps), axis=0)
    error = outside_range(candidate[both], [m[both] for m in maps])
    assert np.quantile(error, 0.999) < 4e-6
    assert error.max() < 2e-4


def turned_view(view, dx, dy):
    """The light's view with its map moved by (dx, dy) texels (x right, y down), as
    `scene_model.camera.turned` moves a picture: a perspective one turned, an orthographic
    one shifted."""
    if view.camera is not None:
        return dataclasses.replace(view, camera=turned(view.camera, dx, dy, view.size,
                                                       view.size))
    return dataclasses.replace(view, low=view.low + np.array([dx, -dy]) * view.texel)


@pytest.mark.parametrize("pcf", [1, 5])
@pytest.mark.parametrize("name", LIGHTS)
def test_gpu_shadow_map_is_the_numpy_shadow_map_but_at_rounding(gpu, name, pcf):
    light = LIGHTS[name]

    def numpy_visibility(dx=0.0, dy=0.0):
        camera = turned(CAMERA, dx, dy, WIDTH, HEIGHT)
        raster = rasterise(MESHES, camera, WIDTH, HEIGHT)
        return raster, numpy_map.shadow_map_visibility(MESHES, raster, camera, light, SIZE,
                                                       GOOD_BIAS, GOOD_SLOPE, pcf)

    raster, reference = numpy_visibility()
    candidate, = gpu_map.shadow_map_visibility(MESHES, [light], CAMERA, WIDTH, HEIGHT, SIZE,
                                           GOOD_BIAS, GOOD_SLOPE, pcf)
    assert candidate.shape == (HEIGHT, WIDTH)
    assert (reference < 1).sum() > 1000                             # the test sees a shadow
    # PCF's fractions k / pcf^2 round differently in float32 and float64: compare k, on a
    # hardware GPU from the range of the NumPy ones around each pixel's centre.
    turned_visibility = around(numpy_visibility)
    counts = [np.round(v * pcf ** 2) for v in [reference] + [v for _, v in turned_visibility]]
    differ = outside_range(np.round(candidate * pcf ** 2), counts) > 0
    assert differ.sum() <= HANDFUL_PIXELS
    margin, edge = _closeness(raster, light, GOOD_BIAS, GOOD_SLOPE, pcf)
    rounding, near_edge = (ROUNDING_HARDWARE, EDGE_HARDWARE) if turned_visibility else (
        ROUNDING, EDGE)
    assert np.all((margin[differ] < rounding) | (edge[differ] < near_edge))


def test_gpu_cube_map_is_the_numpy_cube_map_but_at_rounding(gpu):
    """A point light among the objects: six faces, each drawn as the NumPy face, and the
    lookup in the face each pixel's point leans towards, over 3 x 3 texels. Measured on
    llvmpipe at 96 x 72 with 512-texel faces: no pixel differs."""
    light = PointLight(position=(0.2, 0.45, 0.4))
    faces = numpy_map.light_views(MESHES, light, 512)
    assert len(faces) == 6
    for view in faces[::2]:
        assert_same_map(view, numpy_map.depth_map(MESHES, view))

    def numpy_visibility(dx=0.0, dy=0.0):
        camera = turned(CAMERA, dx, dy, WIDTH, HEIGHT)
        raster = rasterise(MESHES, camera, WIDTH, HEIGHT)
        return numpy_map.shadow_map_visibility(MESHES, raster, camera, light, 512, GOOD_BIAS,
                                               GOOD_SLOPE, 3)

    reference = numpy_visibility()
    candidate, = gpu_map.shadow_map_visibility(MESHES, [light], CAMERA, WIDTH, HEIGHT, 512,
                                           GOOD_BIAS, GOOD_SLOPE, 3)
    assert (reference == 0).sum() > 300 and (reference == 1).sum() > 2000
    counts = [np.round(v * 9) for v in [reference, *around(numpy_visibility)]]
    assert (outside_range(np.round(candidate * 9), counts) > 0).sum() <= HANDFUL_PIXELS


@pytest.mark.parametrize("name", LIGHTS)
def test_gpu_shadow_map_with_no_bias_makes_lit_surfaces_shadow_themselves(gpu, name):
    """Acne on the GPU too: of the pixels the exact shadows (shadow volumes) light, the map
    shadows 50% (point) and 49% (directional) at bias 0, 0.5% and 0.2% with the good bias."""
    light = LIGHTS[name]
    raster = rasterise(MESHES, CAMERA, WIDTH, HEIGHT)
    lit = raster.hit & (shadow_volume_visibility(MESHES, raster, CAMERA, light) == 1)
    acne = {}
    for bias, slope in [(0.0, 0.0), (GOOD_BIAS, GOOD_SLOPE)]:
        visibility, = gpu_map.shadow_map_visibility(MESHES, [light], CAMERA, WIDTH, HEIGHT, SIZE,
                                                bias, slope)
        acne[bias] = (lit & (visibility < 1)).sum() / lit.sum()
    assert acne[0.0] > 0.3 and acne[GOOD_BIAS] < 0.01


def test_gpu_shadow_map_textures_feed_the_lit_pipeline(gpu):
    """One float texture per light, rows as the image's: the lit pipeline shades the same
    picture from the textures as from the same visibility read back into arrays."""
    from gpu_shader.context import gl_context
    from gpu_shader.raster_lit import draw
    from scene_model.scene import Material
    lights = list(LIGHTS.values())
    materials = [Material(color=(0.8, 0.7, 0.6))] * len(MESHES)
    ctx = gl_context()
    with ctx:
        textures = gpu_map.shadow_map_textures(ctx, MESHES, lights, CAMERA, WIDTH, HEIGHT, SIZE,
                                           GOOD_BIAS, GOOD_SLOPE)
        try:
            assert [t.size for t in textures] == [(WIDTH, HEIGHT)] * 2
            assert all(t.dtype == "f4" and t.components == 1 for t in textures)
            planes = [np.frombuffer(t.read(), np.float32).reshape(HEIGHT, WIDTH).copy()
                      for t in textures]
            from_textures, _ = draw(MESHES, materials, lights, CAMERA, WIDTH, HEIGHT,
                                    visibility=textures)
        finally:
            for texture in textures:
                texture.release()
    from_arrays, _ = draw(MESHES, materials, lights, CAMERA, WIDTH, HEIGHT, visibility=planes)
    unshadowed, _ = draw(MESHES, materials, lights, CAMERA, WIDTH, HEIGHT)
    assert min((p == 0).sum() for p in planes) > 1000
    np.testing.assert_array_equal(from_textures, from_arrays)
    assert (np.abs(from_textures - unshadowed).max(axis=-1) > 1e-3).sum() > 1000


def test_gpu_shadow_map_leaves_the_context_as_it_found_it(gpu):
    """Blending (MIN in the depth pass) and depth testing are put back: the raster pipeline
    draws the same planes after a shadow map as before it (left blending, it would not).
    moderngl cannot read GL's state back, so the test starts from GL's defaults itself
    rather than from whatever an earlier test left."""
    from gpu_shader.context import gl_context
    from gpu_shader.raster import rasterise as gpu_rasterise
    ctx = gl_context()
    with ctx:
        ctx.disable(ctx.BLEND | ctx.DEPTH_TEST | ctx.CULL_FACE)
        ctx.blend_equation = ctx.FUNC_ADD
        ctx.blend_func = ctx.DEFAULT_BLENDING
        ctx.depth_func = "<"
    before = gpu_rasterise(MESHES, CAMERA, 48, 36, cull_back_faces=True)
    gpu_map.shadow_map_visibility(MESHES, list(LIGHTS.values()), CAMERA, 48, 36, 256, GOOD_BIAS,
                              GOOD_SLOPE, 3)
    after = gpu_rasterise(MESHES, CAMERA, 48, 36, cull_back_faces=True)
    np.testing.assert_array_equal(after.depth, before.depth)
    np.testing.assert_array_equal(after.normal, before.normal)
    np.testing.assert_array_equal(after.triangle, before.triangle)


@pytest.mark.parametrize("pcf", [0, 2])
def test_gpu_shadow_map_refuses_an_even_filter(gpu, pcf):
    with pytest.raises(ValueError, match="odd"):
        gpu_map.shadow_map_visibility(MESHES, [LIGHTS["point"]], CAMERA, WIDTH, HEIGHT, 64, 0.0,
                                  pcf=pcf)


def _closeness(raster, light, bias, slope_bias, pcf):
    """Per pixel, how near the NumPy test is to going the other way: the smallest
    |depth - (stored + allowed)| over the filter's texels (m), and how near the point falls
    to a texel's edge (texels). The arithmetic of `numpy_map.shadow_map_visibility`."""
    view = numpy_map.light_view(MESHES, light, SIZE)
    stored = numpy_map.depth_map(MESHES, view)
    points = numpy_map.surface_points(raster, CAMERA)[raster.hit]
    image, depth = numpy_map.map_coordinates(view, points)
    if isinstance(light, DirectionalLight):
        to_light = -normalize(np.asarray(light.direction, np.float64))
    else:
        to_light = normalize(np.asarray(light.position, np.float64) - points)
    cosine = np.clip(np.abs(np.sum(raster.normal[raster.hit] * to_light, -1)), 1e-12, 1.0)
    tilt = np.minimum(np.sqrt(1 - cosine ** 2) / cosine, numpy_map.MAX_TILT)
    allowed = bias + slope_bias * numpy_map.texel_width(view, depth) * tilt
    column, row = (np.floor(image[:, k]).astype(np.int64) for k in (0, 1))
    margin = np.full(len(points), np.inf)
    reach = pcf // 2
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            texel = stored[np.clip(row + dy, 0, SIZE - 1), np.clip(column + dx, 0, SIZE - 1)]
            margin = np.minimum(margin, np.abs(depth - (texel + allowed)))
    margins, edges = np.full(raster.hit.shape, np.inf), np.full(raster.hit.shape, np.inf)
    margins[raster.hit] = margin
    edges[raster.hit] = np.min(np.abs(image - np.round(image)), axis=-1)
    return margins, edges
