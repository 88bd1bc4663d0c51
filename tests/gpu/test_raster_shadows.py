"""Shadow volumes on the GPU (`gpu_shader.raster_shadows`) against the NumPy reference
(`reference_cpu.shadow_volumes`), pixel by pixel.

OpenGL extrudes to infinity (w = 0) and counts by additive blending behind its own depth
buffer; NumPy extrudes to a finite reach and counts in float64 behind the rasteriser's
depth. They may differ only where a pixel centre lies within rounding of a volume's edge:
at most `BOUNDARY_PIXELS` pixels, each within a pixel of a shadow's edge or a silhouette.
Measured on llvmpipe at 96 x 72: no pixel differed, for the point, directional and spot
lights on "cube and cone on a floor", and with the eye inside a cube's shadow.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.raster_shadows import draw_shadow_counts, shadow_volume_visibility
from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu.rasterise import rasterise
from reference_cpu.shadow_volumes import shadow_volume_visibility as numpy_visibility
from scene_model.meshes import cube, plane, transformed
from scene_model.scene import Camera, DirectionalLight, PointLight, SpotLight

LIGHTS = [PointLight(position=(-1.0, 3.0, -2.5)), DirectionalLight(direction=(0.5, -1.0, 0.9)),
          SpotLight(position=(-1.0, 3.0, -2.5), direction=(0.3, -1.0, 0.8))]
BOUNDARY_PIXELS = 5


def assert_same_shadows(meshes, camera, lights):
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    candidates = shadow_volume_visibility(meshes, lights, camera, WIDTH, HEIGHT)
    assert len(candidates) == len(lights)
    for light, candidate in zip(lights, candidates):
        reference = numpy_visibility(meshes, raster, camera, light)
        assert (reference == 0).sum() > 500                        # the test sees a shadow
        differ = reference != candidate
        near = dilate(boundary(reference) | boundary(raster.object_id), 1)
        assert not (differ & ~near).any()
        assert differ.sum() <= BOUNDARY_PIXELS


def test_gpu_shadow_volumes_are_the_numpy_shadow_volumes(gpu):
    assert_same_shadows(SCENES["cube and cone on a floor"], CAMERA, LIGHTS)


def test_gpu_depth_fail_works_with_the_eye_inside_a_shadow(gpu):
    meshes = [transformed(cube(1.0), np.array([[1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, 1, 0],
                                               [0, 0, 0, 1.0]])), plane(8.0, 8.0, 4)]
    camera = Camera(position=(2.0, 0.3, 0.0), look_at=(4.0, 0.0, 1.0), fov=60.0)
    assert_same_shadows(meshes, camera, [DirectionalLight(direction=(1.0, -0.3, 0.0))])


def test_gpu_counts_stay_on_the_gpu_one_texture_per_light(gpu):
    """The lower-level call leaves a float count texture per light for a lit pass to
    sample; its nonzero texels are the shadowed pixels."""
    from gpu_shader.context import gl_context
    meshes = SCENES["cube and cone on a floor"]
    ctx = gl_context()
    with ctx:
        drawn = draw_shadow_counts(ctx, meshes, LIGHTS[:2], CAMERA, WIDTH, HEIGHT)
        try:
            assert [c.size for c in drawn.counts] == [(WIDTH, HEIGHT)] * 2
            assert all(c.dtype == "f4" and c.components == 1 for c in drawn.counts)
            counts = np.frombuffer(drawn.counts[1].read(), np.float32).reshape(HEIGHT, WIDTH)
        finally:
            drawn.release()
    raster = rasterise(meshes, CAMERA, WIDTH, HEIGHT)
    shadowed = numpy_visibility(meshes, raster, CAMERA, LIGHTS[1]) == 0
    assert np.array_equal(raster.hit & (counts != 0), shadowed)


def test_gpu_shadows_leave_the_context_as_they_found_it(gpu):
    """Depth function, blending and winding are put back: the raster pipeline draws the same
    picture after a shadow pass as before it."""
    from gpu_shader.raster import rasterise as gpu_rasterise
    meshes = SCENES["cube and cone on a floor"]
    before = gpu_rasterise(meshes, CAMERA, 48, 36, cull_back_faces=True)
    shadow_volume_visibility(meshes, LIGHTS, CAMERA, 48, 36)
    after = gpu_rasterise(meshes, CAMERA, 48, 36, cull_back_faces=True)
    np.testing.assert_array_equal(after.depth, before.depth)
    np.testing.assert_array_equal(after.triangle, before.triangle)


@pytest.mark.parametrize("light", LIGHTS[:2], ids=["point", "directional"])
def test_an_open_floor_alone_casts_no_shadow(gpu, light):
    """Open meshes cast no volume: a floor alone is lit everywhere."""
    meshes = [plane(8.0, 8.0, 4)]
    visibility = shadow_volume_visibility(meshes, [light], CAMERA, WIDTH, HEIGHT)[0]
    assert np.all(visibility == 1)


def test_z_pass_without_caps_counts_as_depth_fail_with_caps(gpu):
    """Where `needs_depth_fail` allows z-pass, its counts equal depth-fail's on every pixel
    that shows a surface (integers, exactly), for the museum's three lights, from its camera
    and from one low among the plinths where 16 of the 48 volumes keep depth-fail. Where no
    surface is drawn the count means nothing (no fragment reads it): there a volume's far
    side ties the cleared depth, which an NVIDIA H100 counted differently in the two ways
    (9 of 4,800 background pixels)."""
    from gpu_shader.context import gl_context
    from gpu_shader.raster import rasterise as gpu_rasterise
    from gpu_shader.raster_shadows import ShadowVolumes, bounding_sphere, needs_depth_fail
    from marchlab import load_scene
    from reference_cpu.transparency import is_transparent, keep_only
    from scene_model.mesh_world import scene_meshes
    scene = load_scene("museum")
    meshes, materials = scene_meshes(scene)
    opaque = [m for m in keep_only(meshes, ~is_transparent(materials)) if len(m.triangles)]
    inside = Camera(position=(-0.3, 0.9, -1.4), look_at=(0.0, 0.6, 3.0), fov=60.0)
    ctx = gl_context()
    for camera in (scene.camera, inside):
        chosen = [needs_depth_fail(bounding_sphere(m), light, camera, 80, 60)
                  for m in opaque for light in scene.lights]
        assert not all(chosen)                       # some volumes are counted by z-pass
        counted = []
        for z_pass in (True, False):
            with ctx:
                volumes = ShadowVolumes(opaque, ctx, z_pass=z_pass)
                try:
                    drawn = volumes.draw(scene.lights, camera, 80, 60)
                    counted.append([np.frombuffer(c.read(), np.float32) for c in drawn.counts])
                finally:
                    volumes.release()
        assert any((c != 0).sum() > 100 for c in counted[1])      # shadows are drawn
        surface = gpu_rasterise(opaque, camera, 80, 60).hit.ravel()
        assert surface.sum() > 1000
        for fast, textbook in zip(*counted):
            np.testing.assert_array_equal(fast[surface], textbook[surface])
