"""Procedural triangle meshes (`scene_model.meshes`): wound outward, closed where they should
be, with unit normals, texture coordinates in the unit square, and the volumes of the
polyhedra they are (exact for the flat-faced ones, within the inscribed polygon's deficit for
the round ones). Transforms keep normals perpendicular and winding outward."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from scene_model.geometry import dot
from scene_model.meshes import (PRIMITIVES, MeshNode, TriangleMesh, cone, cube, cube_sphere,
                                cylinder, flipped, local_matrix, merged, plane, pyramid, torus,
                                transformed, uv_sphere, world_meshes)

CLOSED = ("cube", "cube_sphere", "uv_sphere", "cylinder", "cone", "pyramid", "torus")


def volume(mesh: TriangleMesh) -> float:
    """The enclosed volume by the divergence theorem: sum of v0 . (v1 x v2) / 6."""
    p = mesh.positions[mesh.triangles]
    return float(dot(p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6)


def directed_edges(mesh: TriangleMesh) -> Counter:
    """Each directed edge of the mesh, by its end points' positions (seams and split corners
    have several vertices at one position)."""
    p = np.round(mesh.positions, 12)
    edges = Counter()
    for tri in mesh.triangles:
        for k in range(3):
            edges[(tuple(p[tri[k]]), tuple(p[tri[(k + 1) % 3]]))] += 1
    return edges


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
def test_every_triangle_is_wound_towards_its_vertex_normals(name):
    mesh = PRIMITIVES[name]()
    along = dot(mesh.face_normals(), mesh.normals[mesh.triangles].mean(axis=1))
    assert len(mesh.triangles) > 0 and np.all(along > 0)


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
def test_normals_are_unit_and_uvs_lie_in_the_unit_square(name):
    mesh = PRIMITIVES[name]()
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    assert mesh.uvs.min() >= 0.0 and mesh.uvs.max() <= 1.0


@pytest.mark.parametrize("name", CLOSED)
def test_closed_primitive_uses_every_edge_once_each_way(name):
    """Watertight: no crack (an edge used once) and no fold (an edge used twice one way)."""
    edges = directed_edges(PRIMITIVES[name]())
    assert all(count == 1 for count in edges.values())
    assert all((b, a) in edges for a, b in edges)


def test_flat_faced_primitives_enclose_their_exact_volumes():
    n = 24
    polygon = n / 2 * math.sin(2 * math.pi / n)       # area of the n-gon in the unit circle
    assert volume(cube(2.0)) == pytest.approx(8.0, rel=1e-12)
    assert volume(cube(2.0, subdivisions=5)) == pytest.approx(8.0, rel=1e-12)
    assert volume(pyramid(2.0, 3.0)) == pytest.approx(4.0 * 3.0 / 3, rel=1e-12)
    assert volume(cylinder(0.5, 2.0, n)) == pytest.approx(polygon * 0.25 * 2.0, rel=1e-12)
    assert volume(cone(0.5, 2.0, n)) == pytest.approx(polygon * 0.25 * 2.0 / 3, rel=1e-12)


@pytest.mark.parametrize("make, exact", [
    (lambda k: uv_sphere(1.0, 4 * k, 2 * k), 4 / 3 * math.pi),
    (lambda k: cube_sphere(1.0, k), 4 / 3 * math.pi),
    (lambda k: torus(1.0, 0.3, 4 * k, 2 * k), 2 * math.pi ** 2 * 1.0 * 0.3 ** 2),
])
def test_round_primitives_converge_to_their_volumes_from_inside(make, exact):
    """Vertices on the surface, flat triangles inside it: the volume is short, by a deficit
    that falls like the square of the segment size (a quarter each time it halves)."""
    deficits = [exact - volume(make(k)) for k in (4, 8, 16)]
    assert all(d > 0 for d in deficits)
    assert deficits[-1] / exact < 0.01
    for coarse, fine in zip(deficits, deficits[1:]):
        assert fine / coarse == pytest.approx(0.25, abs=0.05)


def test_plane_faces_up_and_its_uv_runs_along_x_and_minus_z():
    mesh = plane(2.0, 4.0, subdivisions=3)
    np.testing.assert_array_equal(mesh.normals, np.tile([0.0, 1.0, 0.0], (16, 1)))
    np.testing.assert_allclose(mesh.positions[:, 0], (mesh.uvs[:, 0] - 0.5) * 2.0)
    np.testing.assert_allclose(mesh.positions[:, 2], (0.5 - mesh.uvs[:, 1]) * 4.0)
    assert len(mesh.triangles) == 18


def test_sphere_seam_and_poles_have_no_gap():
    mesh = uv_sphere(1.0, 8, 4)
    seam = mesh.uvs[:, 0] == 1.0
    first = mesh.uvs[:, 0] == 0.0
    np.testing.assert_array_equal(mesh.positions[seam], mesh.positions[first])
    assert len(mesh.triangles) == 2 * 8 * 4 - 2 * 8            # no triangle at a pole's point


def test_non_uniform_scale_keeps_normals_perpendicular_to_the_surface():
    """Normals go by the inverse transpose: a sphere squashed into an ellipsoid still has
    normals along the gradient of (x/a)^2 + (y/b)^2 + (z/c)^2 at each vertex."""
    a, b, c = 2.0, 0.5, 1.0
    mesh = transformed(uv_sphere(1.0, 16, 8), np.diag([a, b, c, 1.0]))
    p = mesh.positions
    gradient = p / np.array([a * a, b * b, c * c])
    expected = gradient / np.linalg.norm(gradient, axis=1, keepdims=True)
    np.testing.assert_allclose(mesh.normals, expected, atol=1e-12)
    assert np.all(dot(mesh.face_normals(), mesh.normals[mesh.triangles].mean(axis=1)) > 0)


def test_mirror_keeps_the_winding_outward():
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    mirror[:3, 3] = (0.5, 0.0, 0.0)
    mesh = transformed(cube(1.0), mirror)
    assert volume(mesh) == pytest.approx(1.0, rel=1e-12)         # not -1
    assert np.all(dot(mesh.face_normals(), mesh.normals[mesh.triangles].mean(axis=1)) > 0)


def test_merged_and_flipped_meshes():
    both = merged(cube(1.0), transformed(cube(1.0), np.array(
        [[1, 0, 0, 3.0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])))
    assert volume(both) == pytest.approx(2.0, rel=1e-12)
    assert volume(flipped(cube(1.0))) == pytest.approx(-1.0, rel=1e-12)


# --- the transform hierarchy ---------------------------------------------------------------

def test_child_is_placed_in_its_parents_frame():
    """An arm turned 90 degrees about y carries a child 1 m along its x axis to world -z
    (Ry(90) (1, 0, 0) = (0, 0, -1)), scaled by the arm's scale."""
    child = MeshNode(cube(0.2), translate=(1.0, 0.0, 0.0))
    arm = MeshNode(None, translate=(0.0, 2.0, 0.0), rotate=(0.0, 90.0, 0.0), scale=0.5,
                   children=(child,))
    (mesh,) = world_meshes(arm)
    centre = mesh.positions.mean(axis=0)
    np.testing.assert_allclose(centre, (0.0, 2.0, -0.5), atol=1e-12)
    assert volume(mesh) == pytest.approx((0.2 * 0.5) ** 3, rel=1e-12)


def test_world_matrix_is_the_product_down_the_tree():
    leaf = MeshNode(uv_sphere(0.3, 8, 4), translate=(0.4, 0.1, 0.0), rotate=(10, 20, 30),
                    scale=(1.0, 2.0, 0.5))
    middle = MeshNode(cube(0.5), translate=(1.0, 0.0, 0.0), rotate=(0, 45, 0),
                      children=(leaf,))
    root = MeshNode(None, translate=(0.0, 1.0, 0.0), rotate=(15, 0, 0), scale=2.0,
                    children=(middle,))
    own, nested = world_meshes(root)
    expected = transformed(leaf.mesh, local_matrix(root) @ local_matrix(middle)
                           @ local_matrix(leaf))
    np.testing.assert_allclose(nested.positions, expected.positions, atol=1e-12)
    np.testing.assert_allclose(nested.normals, expected.normals, atol=1e-12)
    np.testing.assert_allclose(own.positions, transformed(
        middle.mesh, local_matrix(root) @ local_matrix(middle)).positions, atol=1e-12)


def test_turning_the_parent_turns_the_whole_mobile_rigidly():
    """Distances between the parts of a mobile do not change as its top turns."""
    def mobile(angle):
        arm = MeshNode(cube(0.2), translate=(1.0, -0.5, 0.0), children=(
            MeshNode(cube(0.1), translate=(0.5, -0.5, 0.0)),))
        return MeshNode(None, rotate=(0.0, angle, 0.0), children=(arm,))
    for angle in (0.0, 37.0, 180.0):
        big, small = world_meshes(mobile(angle))
        gap = small.positions.mean(axis=0) - big.positions.mean(axis=0)
        assert np.linalg.norm(gap) == pytest.approx(np.hypot(0.5, 0.5), rel=1e-12)
