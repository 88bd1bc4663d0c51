"""The raster pipeline on the GPU (`gpu_shader.raster`) against the NumPy rasteriser
(`reference_cpu.rasterise`), pixel by pixel: the same object at every pixel but beside an
edge between objects, the same triangle but beside an edge between triangles, and where both
drew the same triangle, its depth, normal and texture coordinates within float32's rounding
(the GPU computes in float32, the NumPy rasteriser in float64). Measured on llvmpipe: no
pixel showed another object, one pixel of 6,912 another triangle (a front and a back face
tied at a silhouette), depth within 2.1e-6 relative, normals within 1.4e-5, uv within 2.5e-6.
On a hardware GPU each value is measured from the range of the NumPy rasteriser's around the
pixel's centre (tests/subpixel.py): an NVIDIA H100 interpolates from vertices snapped to
1/256 of a pixel, which moved depths by up to 1.1e-3 relative on a floor 91 m away.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.raster import rasterise as gpu_rasterise
from marchlab.compare import boundary, dilate, outside_range
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu.rasterise import rasterise
from scene_model.camera import camera_rays, turned
from scene_model.meshes import plane, uv_sphere
from subpixel import around, steady

DEPTH_RTOL = 1e-5           # float32 against float64: a few ulps of t
NORMAL_ATOL = 1e-4
UV_ATOL = 1e-5


@pytest.mark.parametrize("cull", [False, True], ids=["both faces", "front faces"])
@pytest.mark.parametrize("name", SCENES)
def test_gpu_draws_the_numpy_rasteriser_picture(gpu, name, cull):
    meshes = SCENES[name]
    reference = rasterise(meshes, CAMERA, WIDTH, HEIGHT, cull)
    candidate = gpu_rasterise(meshes, CAMERA, WIDTH, HEIGHT, cull)
    assert candidate.coverage is None and reference.hit.sum() > 1000

    other_object = reference.object_id != candidate.object_id
    assert not (other_object & ~dilate(boundary(reference.object_id), 1)).any()
    faces = np.where(reference.hit, reference.object_id * 100_000 + reference.triangle, -1)
    other_face = ~other_object & (reference.triangle != candidate.triangle)
    assert not (other_face & ~dilate(boundary(faces), 1)).any()
    assert (other_object | other_face).sum() <= 0.001 * WIDTH * HEIGHT

    same = reference.hit & ~other_object & ~other_face
    references = [reference, *around(lambda dx, dy: rasterise(
        meshes, turned(CAMERA, dx, dy, WIDTH, HEIGHT), WIDTH, HEIGHT, cull))]
    same &= steady(references)
    assert_within(candidate.depth[same], [r.depth[same] for r in references],
                  DEPTH_RTOL * reference.depth[same])
    assert_within(candidate.normal[same], [r.normal[same] for r in references], NORMAL_ATOL)
    assert_within(candidate.uv[same], [r.uv[same] for r in references], UV_ATOL)
    assert np.all(np.isinf(candidate.depth[~candidate.hit]))


def assert_within(values, references, tolerance):
    """Each value within ``tolerance`` of the range the references span there."""
    error = outside_range(np.asarray(values, np.float64), references)
    if np.ndim(tolerance):
        tolerance = np.reshape(tolerance, np.shape(tolerance) + (1,) * (error.ndim - 1))
    excess = error - tolerance
    assert excess.max(initial=0.0) <= 0, f"{(excess > 0).sum()} values off by {error.max():.3g}"


def test_gpu_clips_a_floor_that_runs_behind_the_eye_at_the_near_plane(gpu):
    width, height = 48, 36
    raster = gpu_rasterise([plane(200.0, 200.0)], CAMERA, width, height)

    def floor_distance(dx=0.0, dy=0.0):
        origin, directions = camera_rays(turned(CAMERA, dx, dy, width, height), width, height)
        return directions[..., 1] < -1e-6, -origin[1] / directions[..., 1]

    down, t = floor_distance()
    np.testing.assert_array_equal(raster.hit, down & (t < 400))
    hit = raster.hit
    assert_within(raster.depth[hit], [t[hit]] + [r[1][hit] for r in around(floor_distance)],
                  DEPTH_RTOL * t[hit])


def test_gpu_leaves_the_context_as_it_found_it(gpu):
    """The sphere tracer draws on the same context after the raster pipeline, unlit and lit
    with a skybox: no depth test, depth function or face culling left changed, nothing left
    bound that changes its frame."""
    import marchlab
    from gpu_shader.raster_lit import draw
    from scene_model.scene import Material, PointLight, StudioBackground
    from scene_model.scenefile import load_scene
    scene = load_scene("classroom")
    before = marchlab.render(scene, 32, 24, backend="gpu")
    gpu_rasterise([uv_sphere(1.0, 16, 8)], CAMERA, 32, 24, cull_back_faces=True)
    draw([uv_sphere(1.0, 16, 8)], [Material()], [PointLight()], CAMERA, 32, 24,
         background=StudioBackground(size=8), cull_back_faces=True)
    after = marchlab.render(scene, 32, 24, backend="gpu")
    np.testing.assert_array_equal(after.color, before.color)
    np.testing.assert_array_equal(after.depth, before.depth)
