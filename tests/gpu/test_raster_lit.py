"""The lit raster pipeline on the GPU (`gpu_shader.raster_lit.draw`) against the NumPy shading of
raster pictures (`reference_cpu.raster_shading.shade_raster`), pixel by pixel.

Two comparisons. With the GPU's own planes, shade_raster shades exactly the surfaces the GPU
shaded, so the colours differ only by float32 against float64 arithmetic: every pixel within
`COLOR_ATOL` (toon and stripes within `BAND_ATOL`: their bands are smoothsteps a tenth of a
band wide, whose slope 1.5 x 10 x bands = 60 for 4 bands multiplies a rounding of N.L), and
the 8-bit picture within one level. With the NumPy rasteriser's planes, on the pixels where
both draw the same triangle, the float32 normals and depths (within 1.4e-5 and 2.1e-6
relative, tests/gpu/test_raster_pipeline.py) move the colour a little more (`GEOMETRY_ATOL`).

Measured on llvmpipe at 96 x 72, a uv texture, a triplanar one and a checkerboard, the three
lights of tests/test_raster_shading.py and the studio cube map: against the GPU's own planes
within 3.3e-6 (phong, blinn_phong), 1.2e-6 (normals), 1.9e-5 (toon), 6.2e-5 (stripes);
against the NumPy rasteriser's within 1.4e-5, 1.4e-5, 5.3e-5 and 1.5e-4.

The NumPy side is checked on its own against the sphere tracer: a floor mesh with a
checkerboard, a uv texture or a triplanar one is shaded as the SDF plane of the same
material, a cube mesh with a triplanar texture as the SDF box.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.raster_lit import RasterRenderer, draw
from marchlab import render
from marchlab.compare import boundary, dilate, outside_range
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH, turned
from reference_cpu.raster_shading import shade_raster
from reference_cpu.rasterise import rasterise
from reference_cpu.shading import checker_parity
from scene_model.builder import box, plane as sdf_plane
from scene_model.camera import Camera, camera_rays, turned as turned_camera
from scene_model.frame import to_uint8
from scene_model.meshes import cube, plane
from scene_model.scene import (Checker, DirectionalLight, EquirectBackground, Material,
                               PointLight, RenderSettings, Scene, SkyBackground,
                               SolidBackground, SpotLight, StudioBackground, Texture)
from subpixel import around, steady

COLOR_ATOL = 2e-5           # float32 shading of the same planes against float64
BAND_ATOL = 1e-4            # toon and stripes: a rounding of N.L times the bands' slope 60
GEOMETRY_ATOL = 5e-5        # against the NumPy rasteriser's planes (float64 geometry)
GEOMETRY_BAND_ATOL = 5e-4
# On a hardware GPU, beyond the range of the NumPy pictures around the pixel's centre
# (tests/subpixel.py): that range encloses what changes one way across the square the GPU
# may sample, not a uv texture's texels or a stripe's band seen at a slant. Measured on an
# H100: 9.1e-4 (uv texture), 2.1e-3 (stripes); under one level of the 8-bit picture.
HARDWARE_ATOL = 3e-3
TEXTURE_ATOL = 1e-4         # NumPy raster against the sphere tracer, where it stops 1e-6 short
AMBIENT = (0.1, 0.1, 0.12)
LIGHTS = {
    "point": (PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),),
    "directional": (DirectionalLight(direction=(1.0, -1.0, -0.5), intensity=0.5),),
    "coloured spot": (SpotLight(position=(2.0, 3.0, 2.0), direction=(-1.0, -1.5, -1.0),
                                intensity=0.8, diffuse=(1.0, 0.9, 0.7),
                                specular=(0.5, 0.5, 1.0), ambient=(0.05, 0, 0)),),
}
ALL_LIGHTS = sum(LIGHTS.values(), ())
# The scene "cube and cone on a floor": a uv-textured cube, a triplanar-textured cone and a
# checkered floor; the other scenes take the first materials.
MATERIALS = [Material(color=(0.8, 0.3, 0.2), ks=0.5, shininess=24.0,
                      texture=Texture(mapping="uv", scale=0.5)),
             Material(ks=0.4, texture=Texture(scale=0.7, tint=(1.0, 0.8, 0.6))),
             Material(checker=Checker(scale=0.5))]
MODELS = ["phong", "blinn_phong", "toon", "stripes", "normals"]
BANDED = ("toon", "stripes")


def checker_edges(raster, materials):
    """Pixels within one of an edge of a checkerboard (of side 0.5), where float32 and
    float64 may put the point in different squares."""
    origin, directions = camera_rays(CAMERA, WIDTH, HEIGHT)
    p = origin + np.where(raster.hit, raster.depth, 0)[..., None] * directions
    parity = checker_parity(p.reshape(-1, 3), 0.5).reshape(HEIGHT, WIDTH)
    checkered = np.isin(raster.object_id, [k for k, m in enumerate(materials) if m.checker])
    return dilate(boundary(np.where(checkered, parity, -1)), 1)


def assert_same_picture(color, reference, atol, around=()):
    """Every pixel within ``atol``, and the 8-bit pictures within one level: of
    ``reference``, or of the range it and the pictures ``around`` it span there."""
    if not around:
        np.testing.assert_allclose(color, reference, rtol=0, atol=atol)
    error = outside_range(color, [reference, *around])
    assert error.max(initial=0.0) <= atol, f"{(error > atol).sum()} values off by {error.max()}"
    levels = outside_range(to_uint8(color).astype(int),
                           [to_uint8(c).astype(int) for c in (reference, *around)])
    assert levels.max(initial=0) <= 1


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("name", SCENES)
def test_gpu_colour_equals_shade_raster_of_its_planes(gpu, name, model):
    meshes, background = SCENES[name], StudioBackground(size=16)
    materials = MATERIALS[:len(meshes)]
    color, raster = draw(meshes, materials, ALL_LIGHTS, CAMERA, WIDTH, HEIGHT,
                         ambient=AMBIENT, model=model, background=background)
    reference = shade_raster(raster, CAMERA, materials, ALL_LIGHTS, AMBIENT, model, background)
    assert color.dtype == np.float32 and raster.hit.sum() > 1000
    same = ~checker_edges(raster, materials)
    assert_same_picture(color[same], reference[same],
                        BAND_ATOL if model in BANDED else COLOR_ATOL)

    def numpy_picture(camera):
        numpy_raster = rasterise(meshes, camera, WIDTH, HEIGHT)
        return numpy_raster, shade_raster(numpy_raster, camera, materials, ALL_LIGHTS,
                                          AMBIENT, model, background)

    numpy_raster, numpy_color = numpy_picture(CAMERA)
    # On a hardware GPU, the NumPy picture around each pixel's centre (tests/subpixel.py).
    turned_pictures = around(lambda dx, dy: numpy_picture(
        turned_camera(CAMERA, dx, dy, WIDTH, HEIGHT)))
    same &= ((numpy_raster.object_id == raster.object_id)
             & (numpy_raster.triangle == raster.triangle)
             & ~checker_edges(numpy_raster, materials)
             & steady([numpy_raster] + [r for r, _ in turned_pictures]))
    assert (same & raster.hit).sum() > 1000
    atol = GEOMETRY_BAND_ATOL if model in BANDED else GEOMETRY_ATOL
    assert_same_picture(color[same], numpy_color[same],
                        HARDWARE_ATOL if turned_pictures else atol,
                        around=[c[same] for _, c in turned_pictures])


@pytest.mark.parametrize("light", LIGHTS)
def test_each_kind_of_light_shades_as_in_numpy(gpu, light):
    meshes = SCENES["cube and cone on a floor"]
    color, raster = draw(meshes, MATERIALS, LIGHTS[light], CAMERA, WIDTH, HEIGHT,
                         ambient=AMBIENT)
    reference = shade_raster(raster, CAMERA, MATERIALS, LIGHTS[light], AMBIENT)
    same = ~checker_edges(raster, MATERIALS)
    assert_same_picture(color[same], reference[same], COLOR_ATOL)
    # The light reaches the picture: it is not just the ambient term that agrees.
    unlit, _ = draw(meshes, MATERIALS, (), CAMERA, WIDTH, HEIGHT, ambient=AMBIENT)
    assert np.abs(color - unlit).max() > 0.1


@pytest.mark.parametrize("background", [
    SolidBackground(color=(0.2, 0.3, 0.4)), SkyBackground(), StudioBackground(size=16),
    "equirect"], ids=["solid", "sky", "cube map", "equirect"])
def test_pixels_without_a_triangle_show_the_background_of_their_ray(gpu, background,
                                                                     tmp_path):
    if background == "equirect":
        panorama = np.random.default_rng(7).random((16, 32, 3)).astype(np.float32)
        np.save(tmp_path / "panorama.npy", panorama)
        background = EquirectBackground(image=str(tmp_path / "panorama.npy"), rotation=30.0)
    meshes = SCENES["torus"]
    color, raster = draw(meshes, MATERIALS[:1], ALL_LIGHTS, CAMERA, WIDTH, HEIGHT,
                         background=background)
    reference = shade_raster(raster, CAMERA, MATERIALS[:1], ALL_LIGHTS,
                             background=background)
    assert (~raster.hit).sum() > 1000
    assert_same_picture(color, reference, COLOR_ATOL)
    if not isinstance(background, SolidBackground):      # it varies with the ray
        assert np.ptp(color[~raster.hit], axis=0).max() > 0.05


def visibility_planes(seed: int = 3):
    """One plane per light: smooth bands of shadow across the picture, and noise."""
    rng = np.random.default_rng(seed)
    x = np.arange(WIDTH)[None, :] + np.zeros((HEIGHT, 1))
    return [np.clip(0.5 + 0.6 * np.sin(x / (4 + 3 * k) + k), 0, 1) * 0.8
            + 0.2 * rng.random((HEIGHT, WIDTH)) for k in range(len(ALL_LIGHTS))]


@pytest.mark.parametrize("model", ["phong", "toon"])
def test_visibility_planes_scale_each_light_as_in_numpy(gpu, model):
    meshes = SCENES["cube and cone on a floor"]
    planes = visibility_planes()
    planes[1] = None                                      # light 1 reaches everything
    color, raster = draw(meshes, MATERIALS, ALL_LIGHTS, CAMERA, WIDTH, HEIGHT,
                         ambient=AMBIENT, model=model, visibility=planes)
    reference = shade_raster(raster, CAMERA, MATERIALS, ALL_LIGHTS, AMBIENT, model,
                             visibility=planes)
    same = ~checker_edges(raster, MATERIALS)
    assert_same_picture(color[same], reference[same],
                        BAND_ATOL if model in BANDED else COLOR_ATOL)
    unshadowed, _ = draw(meshes, MATERIALS, ALL_LIGHTS, CAMERA, WIDTH, HEIGHT,
                         ambient=AMBIENT, model=model)
    assert np.abs(color - unshadowed).max() > 0.1


def test_visibility_textures_shade_as_the_same_arrays(gpu):
    """A plane handed in as a GL texture (a shadow mask drawn on the GPU) reads the same
    texel per pixel as one handed in as an array: the same picture, bit for bit."""
    from gpu_shader.context import gl_context
    meshes = SCENES["cube and cone on a floor"]
    planes = visibility_planes()
    ctx = gl_context()
    with ctx:
        textures = [ctx.texture((WIDTH, HEIGHT), 1, p.astype(np.float32).tobytes(), dtype="f4")
                    for p in planes]
    try:
        mixed = [planes[0], textures[1], textures[2]]
        from_textures, _ = draw(meshes, MATERIALS, ALL_LIGHTS, CAMERA, WIDTH, HEIGHT,
                                ambient=AMBIENT, visibility=mixed)
    finally:
        with ctx:
            for texture in textures:
                texture.release()
    from_arrays, _ = draw(meshes, MATERIALS, ALL_LIGHTS, CAMERA, WIDTH, HEIGHT,
                          ambient=AMBIENT, visibility=planes)
    np.testing.assert_array_equal(from_textures, from_arrays)


def test_a_renderer_draws_later_frames_as_fresh_draws_do(gpu):
    """The meshes are uploaded once; a frame with another camera, lights, materials and
    background equals a draw from scratch (no setting of the first frame stays behind)."""
    meshes = SCENES["cube and cone on a floor"]
    other_camera = Camera(position=(-2.0, 2.5, 3.5), look_at=(0.0, 0.3, 0.0), fov=50.0)
    other_materials = [Material(color=(0.1, 0.7, 0.3))] * 3
    frames = [(MATERIALS, ALL_LIGHTS, CAMERA, {"background": StudioBackground(size=16)}),
              (other_materials, LIGHTS["point"], other_camera,
               {"ambient": AMBIENT, "model": "blinn_phong"})]
    renderer = RasterRenderer(meshes)
    try:
        for materials, lights, camera, settings in frames + frames:
            color, raster = renderer.draw(materials, lights, camera, WIDTH, HEIGHT, **settings)
            fresh, fresh_raster = draw(meshes, materials, lights, camera, WIDTH, HEIGHT,
                                       **settings)
            np.testing.assert_array_equal(color, fresh)
            np.testing.assert_array_equal(raster.object_id, fresh_raster.object_id)
    finally:
        renderer.release()


def test_bad_arguments_are_refused_in_one_line(gpu):
    meshes = SCENES["sphere"]
    with pytest.raises(ValueError, match="unknown shading model 'steps'"):
        draw(meshes, MATERIALS[:1], ALL_LIGHTS, CAMERA, 16, 12, model="steps")
    with pytest.raises(ValueError, match="expected 3 visibility planes, got 1"):
        draw(meshes, MATERIALS[:1], ALL_LIGHTS, CAMERA, 16, 12, visibility=[None])
    with pytest.raises(ValueError, match=r"must be \(12, 16\) arrays"):
        draw(meshes, MATERIALS[:1], ALL_LIGHTS, CAMERA, 16, 12,
             visibility=[np.ones((3, 4))] * 3)
    with pytest.raises(ValueError, match="a material for each of the 1 meshes, got 2"):
        draw(meshes, MATERIALS[:2], ALL_LIGHTS, CAMERA, 16, 12)


# --- The NumPy side of textures and checkerboards, against the sphere tracer -----------------

FLOOR = plane(4.0, 4.0, subdivisions=2)


@pytest.mark.parametrize("mesh, sdf, mesh_material, sdf_material", [
    (FLOOR, sdf_plane(material="m"), Material(checker=Checker(scale=0.5)),
     Material(checker=Checker(scale=0.5))),
    # The floor's u runs along +x from x = -2 and its v along -z from z = 2, so its image,
    # repeated every 0.5 of uv, is the plane's projection on the +y face repeated every 2 m.
    (FLOOR, sdf_plane(material="m"), Material(texture=Texture(mapping="uv", scale=0.5)),
     Material(texture=Texture(mapping="uv", scale=2.0))),
    (FLOOR, sdf_plane(material="m"), Material(texture=Texture(scale=0.7)),
     Material(texture=Texture(scale=0.7))),
    (turned(cube(1.0), 25, (-0.2, 0.5, 0.0)), box(0.5, material="m").rotate(0, 25, 0).at(
        -0.2, 0.5, 0.0), Material(texture=Texture(scale=0.7, tint=(1.0, 0.8, 0.6))),
     Material(texture=Texture(scale=0.7, tint=(1.0, 0.8, 0.6)))),
], ids=["checker floor", "uv floor", "triplanar floor", "triplanar cube"])
def test_numpy_raster_albedo_is_the_sphere_tracers(mesh, sdf, mesh_material, sdf_material):
    lights = ALL_LIGHTS[:2]
    settings = RenderSettings(shadows="none", reflection_depth=0, epsilon=1e-6,
                              background=SolidBackground(color=(0.0, 0.0, 0.0)))
    scene = Scene(camera=CAMERA, render=settings, materials={"m": sdf_material},
                  lights=lights, objects=(sdf,))
    frame = render(scene, WIDTH, HEIGHT, backend="numpy", precision="float64")
    raster = rasterise([mesh], CAMERA, WIDTH, HEIGHT)
    color = np.clip(shade_raster(raster, CAMERA, [mesh_material], lights, settings.ambient),
                    0, 1)
    faces = np.where(raster.hit, raster.triangle // 2, -1) if mesh is not FLOOR else raster.hit
    inside = (raster.hit & frame.hit & ~dilate(boundary(faces), 1)
              & ~checker_edges(raster, [mesh_material]))
    assert inside.sum() > 250
    assert np.abs(color - frame.color).max(axis=-1)[inside].max() <= TEXTURE_ATOL
    # The pattern shows: the albedo is not the plain colour everywhere.
    assert np.ptp(color[inside], axis=0).max() > 0.1
