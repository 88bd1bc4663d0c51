"""The meshes of the Embree ground truth (reference_cpu.truth.mesh) against closed forms."""

import math

import numpy as np
import pytest

from reference_cpu.truth.mesh import (box_mesh, face_normals, icosphere, orient_outward, plane_mesh,
                                      sdf_mesh, sphere_mesh)


def signed_volume(vertices, faces):
    """Volume enclosed by a closed mesh (divergence theorem): positive when wound outward."""
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    return float(np.sum(v0 * np.cross(v1, v2)) / 6)


def unit_sphere_sdf(p):
    return np.linalg.norm(p, axis=1) - 1.0


@pytest.mark.parametrize("level", range(4))
def test_icosphere_has_unit_vertices_outward_faces_and_the_expected_counts(level):
    vertices, faces = icosphere(level)
    assert len(faces) == 20 * 4 ** level
    assert len(vertices) == 10 * 4 ** level + 2                 # Euler: V - E + F = 2
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), 1, atol=1e-15)
    outward = np.sum(face_normals(vertices, faces) * vertices[faces].mean(axis=1), axis=1)
    assert np.all(outward > 0)


def test_sphere_mesh_bound_is_the_largest_distance_of_a_facet_from_the_sphere():
    # Sample every facet on a barycentric grid of 11 points per side: no sample may lie
    # farther inside than the stated bound, and the farthest comes within 2% of it (the
    # deepest point of a near-equilateral facet, its circumcentre, is near the centroid).
    mesh = sphere_mesh(2.0, max_error=0.01)
    assert 0 < mesh.bound <= 0.01
    steps = np.array([(i, j) for i in range(11) for j in range(11 - i)]) / 10
    weights = np.column_stack([steps, 1 - steps.sum(axis=1)])
    points = np.einsum("sk,fkd->fsd", weights, mesh.vertices[mesh.faces])
    depth = 2.0 - np.linalg.norm(points, axis=-1)
    assert depth.min() >= -1e-12
    assert 0.98 * mesh.bound <= depth.max() <= mesh.bound + 1e-12


def test_box_and_plane_meshes_are_exact_and_wound_outward():
    mesh = box_mesh((1.0, 2.0, 3.0))
    assert signed_volume(mesh.vertices, mesh.faces) == pytest.approx(48.0, rel=1e-15)
    assert mesh.bound == 0
    plane = plane_mesh((0.0, 2.0, 0.0), 0.5, np.array([3.0, 7.0, -1.0]), 10.0)
    normals = face_normals(plane.vertices, plane.faces)
    np.testing.assert_allclose(normals / np.linalg.norm(normals, axis=1, keepdims=True),
                               [[0, 1, 0], [0, 1, 0]], atol=1e-15)
    np.testing.assert_allclose(plane.vertices[:, 1], 0.5, atol=1e-15)   # on y = 0.5
    np.testing.assert_allclose(plane.vertices.mean(axis=0), [3.0, 0.5, -1.0], atol=1e-12)


def test_marching_cubes_sphere_is_wound_outward_with_the_sphere_volume_within_1_percent():
    # 32 cells across the diameter: marching cubes cuts the sphere's curvature by O(h^2),
    # h = 1/16, a fraction of a percent of the volume.
    pytest.importorskip("skimage")
    mesh = sdf_mesh(unit_sphere_sdf, np.zeros(3), 1.0, 32)
    assert signed_volume(mesh.vertices, mesh.faces) == pytest.approx(4 / 3 * math.pi, rel=0.01)
    assert mesh.cell == pytest.approx(2 / 32)
    assert mesh.bound == pytest.approx(math.sqrt(3) / 32)
    # Every vertex lies on a grid edge where the sampled SDF changes sign: within a cell of
    # the surface, and here (a smooth sphere) far closer.
    assert np.abs(unit_sphere_sdf(mesh.vertices)).max() < mesh.bound


def test_winding_check_turns_either_scikit_image_convention_outward():
    # scikit-image winds its faces by its gradient_direction ("descent" or "ascent"), so one
    # of the two comes out inward for an SDF. orient_outward compares the faces with the
    # SDF's gradient and must return both wound outward, and leave an outward one alone.
    marching_cubes = pytest.importorskip("skimage.measure").marching_cubes
    axis = np.linspace(-1.5, 1.5, 25)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    volume = unit_sphere_sdf(grid).reshape(25, 25, 25)
    signs = []
    for direction in ("descent", "ascent"):
        vertices, faces, _, _ = marching_cubes(volume, 0.0, spacing=(axis[1] - axis[0],) * 3,
                                               gradient_direction=direction)
        vertices = vertices + axis[0]
        signs.append(np.sign(signed_volume(vertices, faces)))
        fixed = orient_outward(vertices, faces, unit_sphere_sdf, axis[1] - axis[0])
        assert signed_volume(vertices, fixed) == pytest.approx(4 / 3 * math.pi, rel=0.02)
    assert sorted(signs) == [-1, 1]                      # one of them did need turning
