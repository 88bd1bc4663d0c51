"""Shadow volumes in NumPy (`reference_cpu.shadow_volumes`) against analytic answers.

The volume of a cube lit from straight above is a square prism whose size is known; the
shadow of a floating cube on a floor is a square, the occluder's rim projected from the
light; with the eye inside a cube's shadow, depth-fail still finds it and depth-pass is off
by one everywhere. The comparison with Embree's shadow rays on a bigger scene is in
tests/truth/test_raster_shadows_against_embree.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import marchlab
from marchlab.compare import boundary, dilate
from reference_cpu.rasterise import rasterise
from reference_cpu.shadow_map import surface_points
from reference_cpu.shadow_volumes import (facing_light, neighbours, shadow_volume_visibility,
                                          silhouette_edges, stencil_counts,
                                          volume_sides_and_back_cap)
from reference_cpu.transparency import is_transparent, keep_only
from scene_model.mesh_world import scene_meshes
from scene_model.meshes import PRIMITIVES, TriangleMesh, cube, disk, merged, plane
from scene_model.scene import Camera, DirectionalLight, PointLight

WIDTH, HEIGHT = 96, 72
OVERHEAD = DirectionalLight(direction=(0.0, -1.0, 0.0))


def moved(mesh: TriangleMesh, offset) -> TriangleMesh:
    return TriangleMesh(mesh.positions + np.asarray(offset, np.float64), mesh.normals,
                        mesh.uvs, mesh.triangles)


def signed_volume(mesh: TriangleMesh) -> float:
    """The volume a closed mesh wound outward encloses (divergence theorem: sum of
    det(v0, v1, v2) / 6)."""
    p = mesh.positions[mesh.triangles]
    return float(np.sum(np.linalg.det(p)) / 6)


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
def test_only_open_primitives_have_no_neighbours(name):
    """A cone's rim is computed twice (side and base) and still matches, by position."""
    closed = neighbours(PRIMITIVES[name]()) is not None
    assert closed == (name not in ("plane", "disk"))


def test_silhouette_of_a_cube_lit_from_above_is_its_top_rim():
    edges = silhouette_edges(cube(1.0), OVERHEAD)
    ends = cube(1.0).positions[edges]                                # (S, 2, 3)
    assert len(edges) == 4                                           # sides are edge-on: dark
    np.testing.assert_array_equal(ends[..., 1], 0.5)
    # Wound as the lit top face goes round: the four edges make one loop.
    assert np.allclose(np.sort(ends[:, 0], axis=0), np.sort(ends[:, 1], axis=0))


@pytest.mark.parametrize("reach", [1.0, 7.5])
def test_volume_of_a_cube_lit_from_above_is_a_square_prism(reach):
    """Front cap (the top) + sides + back cap (the dark faces moved down by reach) close a
    prism 1 x 1 x (1 + reach), wound outward: its signed volume is exactly that."""
    mesh = cube(1.0)
    rest = volume_sides_and_back_cap(mesh, OVERHEAD, reach)
    front = TriangleMesh(mesh.positions, mesh.normals, mesh.uvs,
                         mesh.triangles[facing_light(mesh, OVERHEAD)])
    volume = merged(front, rest)
    assert neighbours(volume) is not None
    assert signed_volume(volume) == pytest.approx(1.0 + reach, rel=1e-12)


def inside_box(points, towards, low, high):
    """Whether the ray from each point (N, 3) along ``towards`` ((3,) or (N, 3)) meets the
    box [low, high] ahead of it (the slab method: Kay and Kajiya 1986)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (np.asarray(low, np.float64) - points) / towards
        b = (np.asarray(high, np.float64) - points) / towards
    near = np.max(np.minimum(a, b), axis=-1)
    far = np.min(np.maximum(a, b), axis=-1)
    return (far >= np.maximum(near, 0.0)) & (far > 0)


@pytest.mark.parametrize("light", [DirectionalLight(direction=(0.2, -1.0, 0.6)),
                                   PointLight(position=(0.3, 4.5, -1.0))],
                         ids=["directional", "point"])
def test_shadow_of_a_floating_cube_is_where_rays_to_the_light_meet_the_box(light):
    """The floor is in shadow exactly where the segment to the light meets the cube, found
    here by the slab method; every floor pixel agrees but beside an edge."""
    low, high = np.array([-0.5, 1.5, -0.5]), np.array([0.5, 2.5, 0.5])
    camera = Camera(position=(0.5, 4.0, 5.0), look_at=(0.0, 0.0, 0.5), fov=50.0)
    meshes = [moved(cube(1.0), (low + high) / 2), plane(8.0, 8.0, subdivisions=4)]
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    points = surface_points(raster, camera)
    towards = (-np.asarray(light.direction) if isinstance(light, DirectionalLight)
               else np.asarray(light.position) - points)
    floor = raster.object_id == 1
    inside = floor & inside_box(points, towards, low, high)
    away = floor & ~dilate(boundary(inside) | boundary(raster.object_id), 1)
    assert (inside & away).sum() > 100 and (~inside & away).sum() > 1000
    visibility = shadow_volume_visibility(meshes, raster, camera, light)
    np.testing.assert_array_equal(visibility[away], np.where(inside, 0.0, 1.0)[away])


def test_front_cap_keeps_the_lit_faces_of_the_caster_lit():
    """Where the cube's own lit faces are the surface drawn, the front cap lands on their
    very depth and is counted (depth-fail's test fails on equal depth): they stay lit."""
    light = DirectionalLight(direction=(0.2, -1.0, -0.6))
    camera = Camera(position=(0.5, 4.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=50.0)
    meshes = [moved(cube(1.0), (0.0, 2.0, 0.0)), plane(8.0, 8.0, subdivisions=4)]
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    lit_face = (raster.object_id == 0) & (raster.normal @ -np.asarray(light.direction) > 0)
    assert lit_face.sum() > 100
    assert np.all(shadow_volume_visibility(meshes, raster, camera, light)[lit_face] == 1)


def test_eye_inside_a_cubes_shadow_depth_fail_counts_right_and_depth_pass_does_not():
    """Light skims the floor along +x past a cube; the eye sits in its shadow looking on."""
    light = DirectionalLight(direction=(1.0, -0.3, 0.0))
    camera = Camera(position=(2.0, 0.3, 0.0), look_at=(4.0, 0.0, 1.0), fov=60.0)
    meshes = [moved(cube(1.0), (0.0, 0.5, 0.0)), plane(8.0, 8.0, subdivisions=4)]
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    towards = -np.asarray(light.direction)
    assert inside_box(np.array([camera.position]), towards, [-0.5, 0, -0.5], [0.5, 1, 0.5])[0]
    shadowed = raster.hit & inside_box(surface_points(raster, camera), towards,
                                       [-0.5, 0, -0.5], [0.5, 1.0, 0.5])
    expected = np.where(shadowed, 0.0, 1.0)
    edge = dilate(boundary(shadowed) | boundary(raster.object_id), 1)
    assert shadowed.sum() > 1000 and (raster.hit & ~shadowed).sum() > 500
    depth_fail = stencil_counts(meshes, raster, camera, light, "depth-fail")
    depth_pass = stencil_counts(meshes, raster, camera, light, "depth-pass")
    visibility = np.where(raster.hit & (depth_fail != 0), 0.0, 1.0)
    assert np.array_equal(visibility[~edge], expected[~edge])
    # Counting in front of the surface misses the volume the eye starts in: off by one.
    np.testing.assert_array_equal(depth_pass[raster.hit], depth_fail[raster.hit] - 1)


def test_an_open_mesh_casts_no_volume_but_receives_shadows():
    """A disk between the light and the floor has no inside to bound: it casts nothing,
    while a cube beside it shadows both the floor and the disk (documented behaviour)."""
    camera = Camera(position=(0.0, 6.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=50.0)
    meshes = [moved(disk(0.8), (1.2, 1.0, 0.0)), moved(cube(1.0), (-0.8, 2.0, 0.0)),
              plane(8.0, 8.0, subdivisions=4)]
    light = DirectionalLight(direction=(1.0, -1.0, 0.0))
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    visibility = shadow_volume_visibility(meshes, raster, camera, light)
    # The disk's shadow would fall round (2.2, 0, 0); the cube's reaches x = 2.2 only.
    points = surface_points(raster, camera)
    below_disk = (raster.object_id == 2) & (np.hypot(points[..., 0] - 2.6, points[..., 2]) < 0.4)
    assert below_disk.sum() > 30 and np.all(visibility[below_disk] == 1)
    assert np.any(visibility[raster.object_id == 0] == 0)         # the cube shadows the disk


def test_unknown_counting_method_is_refused():
    camera = Camera(position=(0.0, 2.0, 5.0), look_at=(0.0, 0.0, 0.0))
    meshes = [cube(1.0)]
    raster = rasterise(meshes, camera, 8, 6)
    with pytest.raises(ValueError, match="depth-fail"):
        stencil_counts(meshes, raster, camera, OVERHEAD, method="z-fail")


@pytest.mark.parametrize("method", ["depth-fail", "depth-pass"])
def test_batched_stencil_counts_are_the_loop_s_on_the_museum(method):
    """Every light of the museum (directional, point, spot), its opaque closed meshes
    casting: the same count on every pixel, drawn many triangles at once or one by one."""
    scene = marchlab.load_scene("museum")
    meshes, materials = scene_meshes(scene)
    opaque = keep_only(meshes, ~is_transparent(materials))
    casters = [m if neighbours(m) is not None else keep_only([m], [False])[0] for m in opaque]
    raster = rasterise(opaque, scene.camera, 64, 48)
    for light in scene.lights:
        fast = stencil_counts(casters, raster, scene.camera, light, method)
        assert (fast != 0).sum() > 20
        np.testing.assert_array_equal(
            fast, stencil_counts(casters, raster, scene.camera, light, method, textbook=True))


def test_batched_stencil_counts_are_the_loop_s_with_the_eye_in_the_shadow():
    """The volume the eye stands in crosses the near plane: its faces are clipped, and the
    counts (depth-pass off by one) are still the loop's."""
    light = DirectionalLight(direction=(1.0, -0.3, 0.0))
    camera = Camera(position=(2.0, 0.3, 0.0), look_at=(4.0, 0.0, 1.0), fov=60.0)
    meshes = [moved(cube(1.0), (0.0, 0.5, 0.0)), plane(8.0, 8.0, subdivisions=4)]
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    for method in ("depth-fail", "depth-pass"):
        fast = stencil_counts(meshes, raster, camera, light, method)
        assert (fast != 0).sum() > 1000
        np.testing.assert_array_equal(
            fast, stencil_counts(meshes, raster, camera, light, method, textbook=True))
