"""The raster pipeline on the GPU (`gpu_shader.raster`) against the NumPy rasteriser
(`reference_cpu.rasterise`), pixel by pixel: the same object at every pixel but beside an
edge between objects, the same triangle but beside an edge between triangles, and where both
drew the same triangle, its depth, normal and texture coordinates within float32's rounding
(the GPU computes in float32, the NumPy rasteriser in float64). Measured on llvmpipe: no
pixel showed another object, one pixel of 6,912 another triangle (a front and a back face
tied at a silhouette), depth within 2.1e-6 relative, normals within 1.4e-5, uv within 2.5e-6.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.raster import rasterise as gpu_rasterise
from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu.rasterise import rasterise
from scene_model.camera import camera_rays
from scene_model.meshes import plane, uv_sphere

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
    np.testing.assert_allclose(candidate.depth[same], reference.depth[same], rtol=DEPTH_RTOL)
    np.testing.assert_allclose(candidate.normal[same], reference.normal[same],
                               atol=NORMAL_ATOL)
    np.testing.assert_allclose(candidate.uv[same], reference.uv[same], atol=UV_ATOL)
    assert np.all(np.isinf(candidate.depth[~candidate.hit]))


def test_gpu_clips_a_floor_that_runs_behind_the_eye_at_the_near_plane(gpu):
    width, height = 48, 36
    raster = gpu_rasterise([plane(200.0, 200.0)], CAMERA, width, height)
    origin, directions = camera_rays(CAMERA, width, height)
    down = directions[..., 1] < -1e-6
    t = -origin[1] / directions[..., 1]
    np.testing.assert_array_equal(raster.hit, down & (t < 400))
    np.testing.assert_allclose(raster.depth[raster.hit], t[raster.hit], rtol=DEPTH_RTOL)


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
