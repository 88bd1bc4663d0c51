"""The NumPy rasteriser (`reference_cpu.rasterise`): the top-left fill rule draws each pixel
of a shared edge once, perspective-correct interpolation gives the texture coordinates of
the exact ray-plane intersection (and screen-linear interpolation does not), clipping at the
near plane keeps a floor that runs behind the eye, the guard band keeps a 10 km floor exact,
and the picture of a mesh is the picture Embree's ray casts of the same triangles give
(tests/truth: `test_rasterise_against_embree`). The batched rasteriser
(`reference_cpu.rasterise_batched`) gives the textbook loop's picture to the last bit: same
depth, normals, uvs, ids and coverage.
"""

from __future__ import annotations

import numpy as np
import pytest

import marchlab
import reference_cpu.rasterise as R
import reference_cpu.rasterise_batched as RB
import mesh_scenes
from reference_cpu.rasterise import NEAR, draw_triangle, is_top_left, rasterise
from reference_cpu.rasterise_batched import draw_triangles
from scene_model.camera import Camera, camera_rays
from scene_model.geometry import dot
from scene_model.mesh_world import scene_meshes
from scene_model.meshes import cube, merged, plane, transformed, uv_sphere

CAMERA = Camera(position=(0.0, 1.5, 4.0), look_at=(0.0, 0.0, 0.0), fov=50.0)


def coverage_of(triangles, size=(16, 12)):
    """How many of ``triangles`` (each (3, 2) image corners) cover each pixel (H, W)."""
    width, height = size
    count = np.zeros((height, width), int)
    for corners in triangles:
        drawn = draw_triangle(np.asarray(corners, float), np.ones(3), size=size)
        if drawn is not None:
            (x0, y0), inside, _ = drawn
            h, w = inside.shape
            count[y0:y0 + h, x0:x0 + w] += inside
    return count


def test_shared_diagonal_through_pixel_centres_is_drawn_once():
    """A square split along a diagonal that passes exactly through pixel centres: every
    centre inside the square is drawn once, none twice, whichever way the square is split."""
    a, b, c, d = (2.5, 1.5), (12.5, 1.5), (12.5, 11.5), (2.5, 11.5)      # centres on the sides
    for split in ([(a, b, c), (a, c, d)], [(a, b, d), (b, c, d)]):
        count = coverage_of(split)
        assert count.max() == 1
        # Centres on the square's top and left sides are drawn, on its bottom and right not.
        expected = np.zeros_like(count)
        expected[1:11, 2:12] = 1
        np.testing.assert_array_equal(count, expected)


def test_fan_of_triangles_around_a_pixel_centre_draws_it_once():
    """Eight triangles meeting at a pixel centre (every edge through it): exactly one draws
    it, as every pixel on their shared edges."""
    centre = np.array([8.5, 6.5])
    angles = np.arange(8) * np.pi / 4
    ring = centre + 5 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    ring = np.round(ring * 2) / 2                  # on half-pixels: many centres on edges
    fan = [(centre, ring[k], ring[(k + 1) % 8]) for k in range(8)]
    count = coverage_of(fan)
    assert count[6, 8] == 1
    assert count.max() == 1


def test_closed_mesh_front_faces_cover_its_image_once():
    raster = rasterise([uv_sphere(1.0, 24, 12)], CAMERA, 80, 60, cull_back_faces=True)
    assert raster.coverage.max() == 1
    assert raster.hit.sum() > 400
    # Without culling the back faces cover the same pixels again: twice each.
    both = rasterise([uv_sphere(1.0, 24, 12)], CAMERA, 80, 60)
    assert set(np.unique(both.coverage)) <= {0, 2}
    np.testing.assert_array_equal(both.depth, raster.depth)


def test_perspective_correct_uv_on_a_plane_is_the_ray_plane_intersections():
    """A large floor seen at a slant: each pixel's uv is where its ray meets the plane (to
    1e-9), while interpolating uv linearly in the image would be off by up to a tenth."""
    size, width, height = 8.0, 64, 48
    raster = rasterise([plane(size, size)], CAMERA, width, height)
    origin, directions = camera_rays(CAMERA, width, height)
    t = -origin[1] / directions[..., 1]
    point = origin + t[..., None] * directions
    inside = raster.hit & (np.abs(point[..., 0]) < size / 2) & (np.abs(point[..., 2]) < size / 2)
    assert inside.sum() > 1000
    u, v = point[..., 0] / size + 0.5, 0.5 - point[..., 2] / size
    np.testing.assert_allclose(raster.uv[..., 0][inside], u[inside], atol=1e-9)
    np.testing.assert_allclose(raster.uv[..., 1][inside], v[inside], atol=1e-9)
    np.testing.assert_allclose(raster.depth[inside], t[inside], rtol=1e-12)
    # The mistake it avoids: barycentrics of the image used as they are.
    assert affine_uv_error(plane(size, size), width, height, u, v, inside) > 0.05


def affine_uv_error(mesh, width, height, u, v, inside):
    """Largest |uv error| of screen-linear (not perspective-correct) interpolation."""
    from scene_model.camera import project
    image = project(CAMERA, mesh.positions, width, height)[:, :2]
    worst = 0.0
    ys, xs = np.nonzero(inside)
    p = np.stack([xs + 0.5, ys + 0.5], axis=1)
    for tri in mesh.triangles:
        a, b, c = image[tri]
        m = np.array([b - a, c - a]).T
        coords = np.linalg.solve(m, (p - a).T).T                    # (P, 2): beta, gamma
        w = np.column_stack([1 - coords.sum(1), coords])
        mine = np.all(w >= -1e-9, axis=1)
        uv = w[mine] @ mesh.uvs[tri]
        error = np.abs(uv - np.column_stack([u[inside][mine], v[inside][mine]]))
        worst = max(worst, float(error.max(initial=0.0)))
    return worst


def test_near_plane_clips_a_floor_that_runs_behind_the_eye():
    """A floor far larger than the view passes under and behind the camera: clipped at the
    near plane, every pixel looking down sees it at the exact ray-plane distance."""
    width, height = 48, 36
    floor = plane(200.0, 200.0)
    raster = rasterise([floor], CAMERA, width, height)
    origin, directions = camera_rays(CAMERA, width, height)
    down = directions[..., 1] < -1e-6
    t = -origin[1] / directions[..., 1]
    np.testing.assert_array_equal(raster.hit, down & (t < 400))
    np.testing.assert_allclose(raster.depth[raster.hit], t[raster.hit], rtol=1e-10)
    assert NEAR > 0


@pytest.mark.parametrize("camera, subdivisions", [
    (Camera(position=(0.0, 2.0, 0.0), look_at=(3.0, -1.0, -3.0), up=(0.8, 1.0, -1.6),
            fov=40.0), 1),
    (Camera(position=(0.3, 1.6, 0.2), look_at=(2.0, 0.0, -6.0), up=(0.3, 1.0, 0.0),
            fov=60.0), 4)], ids=["looking down, rolled", "towards the horizon, rolled"])
def test_ten_km_floor_through_the_near_plane_is_the_exact_ray_plane_answer(camera,
                                                                        subdivisions):
    """A 10 km floor under the eye, rolled in the picture: its triangles cross the near plane,
    where cut corners project up to 2^40 subpixels off screen, in x and y at once. Cut again
    at the guard band (`clip_planes`), every pixel whose ray meets the floor is drawn, at the
    ray-plane distance within 1e-9 relative, and none that looks up. (Without the guard band
    the int64 edge functions overflowed: the first camera lost 3456 of its 6912 pixels, the
    second's depths were off by 4e-8.) Pixels whose rays meet the plane beyond 4 km, within a
    hundredth of a pixel of the floor's far edge, are left out: closer than a snap resolves."""
    size, width, height = 10_000.0, 96, 72
    floor = plane(size, size, subdivisions=subdivisions)
    index, corners = RB.clipped_triangle_batch(floor, camera)     # near plane alone
    image, _, _, _ = RB.project_corner_batch(corners, camera, width, height)
    assert np.abs(image).min(axis=2).max() * R.SUBPIXELS > 2**31   # far off in x and y
    raster = rasterise([floor], camera, width, height)
    origin, directions = camera_rays(camera, width, height)
    down = directions[..., 1] < 0
    t = -origin[1] / directions[..., 1]
    point = origin + t[..., None] * directions
    near = down & (np.abs(point[..., 0]) < 0.4 * size) & (np.abs(point[..., 2]) < 0.4 * size)
    assert near.sum() > 0.9 * down.sum()
    assert raster.hit[near].all() and not raster.hit[~down].any()
    np.testing.assert_allclose(raster.depth[near], t[near], rtol=1e-9)
    for cull in (False, True):
        assert_same_bits(rasterise([floor], camera, width, height, cull),
                         rasterise([floor], camera, width, height, cull, textbook=True))


def test_clipped_corners_stay_inside_the_guard_band():
    """Every corner `clipped_triangle_batch` gives, projected, lies within `GUARD_BAND` pixels
    of the image (up to rounding), so snapped it stays below 2^25 subpixels: the bound the
    int64 edge functions need (`clip_planes`)."""
    camera = Camera(position=(0.0, 2.0, 0.0), look_at=(3.0, -1.0, -3.0), up=(0.8, 1.0, -1.6),
                    fov=40.0)
    width, height = 96, 72
    meshes = [plane(10_000.0, 10_000.0, subdivisions=3), cube(1.0), uv_sphere(1e4, 24, 12)]
    for mesh in meshes:
        index, corners = RB.clipped_triangle_batch(mesh, camera, (width, height))
        image, z, _, _ = RB.project_corner_batch(corners, camera, width, height)
        assert z.min() >= NEAR * (1 - 1e-12)
        band = R.GUARD_BAND * (1 + 1e-9)
        assert np.all(image >= -band) and np.all(image <= np.array([width, height]) + band)
        assert np.abs(np.round(image * R.SUBPIXELS)).max() < 2**25
    assert len(np.unique(index)) < len(index)                  # the sphere around the eye: cut


def test_nearer_triangle_wins_the_depth_test_whatever_the_order():
    near_box = transformed(cube(1.0), np.array([[1, 0, 0, 0], [0, 1, 0, 0.3], [0, 0, 1, 1.0],
                                                [0, 0, 0, 1.0]]))
    far_box = cube(2.0)
    one = rasterise([far_box, near_box], CAMERA, 40, 30)
    other = rasterise([near_box, far_box], CAMERA, 40, 30)
    np.testing.assert_array_equal(one.depth, other.depth)
    np.testing.assert_array_equal(one.object_id == 1, other.object_id == 0)    # the near box
    np.testing.assert_array_equal(one.object_id == 0, other.object_id == 1)
    assert (one.object_id == 1).sum() > 50 and (one.object_id == 0).sum() > 50


def test_interpolated_normals_are_unit_and_face_the_eye():
    raster = rasterise([uv_sphere(1.0, 24, 12)], CAMERA, 64, 48, cull_back_faces=True)
    n = raster.normal[raster.hit]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    _, directions = camera_rays(CAMERA, 64, 48)
    assert np.all(dot(n, directions[raster.hit]) < 0.2)   # facing the eye, up to the facets


@pytest.mark.parametrize("corners", [
    [(1.0, 1.0), (1.0, 1.0), (5.0, 5.0)],           # two corners at one point
    [(1.0, 1.0), (3.0, 3.0), (5.0, 5.0)],           # on one line
])
def test_triangle_without_area_draws_nothing(corners):
    assert draw_triangle(np.array(corners), np.ones(3), size=(16, 12)) is None


# --- The batched rasteriser against the textbook loop -------------------------------------

def assert_same_bits(fast, loop):
    """Every plane of two Rasters equal bit for bit (floats compared as their bytes, so a
    -0.0 for a 0.0 or another NaN would show)."""
    for name in ("depth", "normal", "uv", "object_id", "triangle", "coverage"):
        a, b = getattr(fast, name), getattr(loop, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert a.tobytes() == b.tobytes(), f"{name}: {np.sum(a != b)} pixels differ"


@pytest.mark.parametrize("cull", [False, True], ids=["all faces", "back faces culled"])
@pytest.mark.parametrize("name", sorted(mesh_scenes.SCENES))
def test_batched_rasteriser_is_the_loop_bit_for_bit(name, cull):
    meshes, camera = mesh_scenes.SCENES[name], mesh_scenes.CAMERA
    size = (mesh_scenes.WIDTH, mesh_scenes.HEIGHT)
    fast = rasterise(meshes, camera, *size, cull)
    assert fast.hit.sum() > 1000
    assert_same_bits(fast, rasterise(meshes, camera, *size, cull, textbook=True))


@pytest.mark.parametrize("cull", [False, True], ids=["all faces", "back faces culled"])
def test_batched_rasteriser_is_the_loop_bit_for_bit_on_the_museum(cull):
    scene = marchlab.load_scene("museum")
    meshes, _ = scene_meshes(scene)
    fast = rasterise(meshes, scene.camera, 64, 48, cull)
    assert fast.hit.sum() > 1500
    assert_same_bits(fast, rasterise(meshes, scene.camera, 64, 48, cull, textbook=True))


@pytest.mark.parametrize("camera", [CAMERA, Camera(position=(0.0, 0.3, 0.0),
                                                   look_at=(1.0, 0.1, -3.0), fov=70.0)],
                         ids=["above", "just over the floor"])
def test_batched_rasteriser_clips_at_the_near_plane_as_the_loop_does(camera):
    """A floor far larger than the view and a cube the eye stands in: their triangles cross
    the near plane, are cut into one or two pieces each, and the cut corners land thousands
    of pictures away."""
    meshes = [plane(200.0, 200.0, subdivisions=3), cube(1.0)]
    index, corners = RB.clipped_triangle_batch(meshes[0], camera)
    assert len(index) > len(np.unique(index))                 # some cut in two
    image, _, _, _ = RB.project_corner_batch(corners, camera, 48, 36)
    assert np.abs(image).max() > 1e5
    for cull in (False, True):
        assert_same_bits(rasterise(meshes, camera, 48, 36, cull),
                         rasterise(meshes, camera, 48, 36, cull, textbook=True))


def test_equal_depths_go_to_the_first_triangle_drawn_across_batches(monkeypatch):
    """The floor drawn twice (two meshes, and within one mesh): the loop keeps the first copy
    on every pixel, a later one being no nearer. So does the batched rasteriser, with
    batches so small that the copies fall in different ones."""
    floor = plane(4.0, 4.0, subdivisions=2)
    meshes = [floor, merged(floor, floor)]
    monkeypatch.setattr(RB, "CHUNK", 37)
    fast = rasterise(meshes, CAMERA, 40, 30)
    assert fast.hit.sum() > 300 and np.all(fast.object_id[fast.hit] == 0)
    assert np.all(fast.coverage[fast.hit] == 3)
    assert_same_bits(fast, rasterise(meshes, CAMERA, 40, 30, textbook=True))


def test_draw_triangles_gives_draw_triangle_s_pixels_and_weights():
    """Random triangles, of every size and both windings, some edge-on or with a corner far
    outside (beyond 2^30 subpixels, where `winding` turns to Python's integers and
    `row_spans` to whole boxes): the same covered pixels and the same weights, bit for bit,
    in small chunks."""
    rng = np.random.default_rng(7)
    size = (40, 30)
    image = rng.uniform(-10, 50, (300, 3, 2))
    image[:20] = np.round(image[:20])                      # corners on pixel corners
    image[20:30, 2] = image[20:30, 0]                      # edge-on: two corners at one point
    image[30:40, 1] *= 1e7                                 # beyond 2^30 subpixels
    z = rng.uniform(0.5, 5.0, (300, 3))
    for cull in (False, True):
        got = [np.concatenate(column) for column in
               zip(*draw_triangles(image, z, cull, size, chunk=500))]
        expected = [[], [], [], []]
        for i in range(len(image)):
            drawn = draw_triangle(image[i], z[i], cull, size)
            if drawn is not None:
                (x0, y0), inside, weights = drawn
                rows, cols = np.nonzero(inside)
                for column, value in zip(expected, (np.full(len(rows), i), rows + y0,
                                                    cols + x0, weights[inside])):
                    column.append(value)
        expected = [np.concatenate(column) for column in expected]
        assert len(expected[0]) > 5000
        for a, b in zip(got, expected):
            assert a.tobytes() == b.tobytes()


def test_top_left_rule_takes_numbers_and_arrays_alike():
    edges = [(0, 0, 5, 0), (5, 0, 0, 0), (0, 5, 0, 0), (0, 0, 0, 5), (0, 0, 5, 5), (5, 5, 0, 0)]
    one_by_one = [is_top_left(*e) for e in edges]
    assert one_by_one == [True, False, True, False, False, True]
    np.testing.assert_array_equal(is_top_left(*np.array(edges).T), one_by_one)
