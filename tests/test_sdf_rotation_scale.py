"""Rotation and scale of SDF nodes against rotations built by hand and closest-point distances.

``rotation_matrix`` must be Rz Ry Rx (Rodrigues' formula about each axis), orthonormal and
right-handed; a rotated or scaled shape must be the plain shape of tests/sdf_reference.py at
rotated points, or with scaled sizes.
"""

from __future__ import annotations

import numpy as np
import pytest
from sdf_reference import EXACT, box_distance, cone_distance, sphere_distance, torus_distance, unit

from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.geometry import rotation_matrix
from scene_model.shapes import Box, Cone, Sphere, Torus


def axis_rotation(axis, degrees):
    """Rodrigues' formula R = I + sin(t) K + (1 - cos(t)) K^2, K the cross-product matrix of the
    unit axis: for the coordinate axes it gives the textbook Rx, Ry, Rz."""
    k = unit(np.asarray(axis, dtype=np.float64))
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    t = np.radians(degrees)
    return np.eye(3) + np.sin(t) * cross + (1 - np.cos(t)) * cross @ cross


def euler_by_hand(x, y, z):
    return axis_rotation((0, 0, 1), z) @ axis_rotation((0, 1, 0), y) @ axis_rotation((1, 0, 0), x)


ANGLES = np.random.default_rng(17).uniform(-360, 360, (20, 3))


def test_rotation_matrix_is_rz_ry_rx_within_1e_12():
    for angles in ANGLES:
        np.testing.assert_allclose(rotation_matrix(angles), euler_by_hand(*angles),
                                   rtol=0, atol=EXACT)


def test_rotation_matrix_turns_axes_by_right_hand_rule_within_1e_12():
    """90 degrees about z takes x to y; about x takes y to z; about y takes z to x."""
    e = np.eye(3)
    np.testing.assert_allclose(rotation_matrix((0, 0, 90)) @ e[0], e[1], atol=EXACT)
    np.testing.assert_allclose(rotation_matrix((90, 0, 0)) @ e[1], e[2], atol=EXACT)
    np.testing.assert_allclose(rotation_matrix((0, 90, 0)) @ e[2], e[0], atol=EXACT)


def test_rotation_matrix_is_orthonormal_with_determinant_1_within_1e_12():
    for angles in ANGLES:
        r = rotation_matrix(angles)
        np.testing.assert_allclose(r.T @ r, np.eye(3), rtol=0, atol=EXACT)
        assert abs(np.linalg.det(r) - 1.0) <= EXACT


def test_box_rotated_90_about_y_has_half_extents_swapped_within_1e_12():
    """Ry(90) takes x to -z and z to x, so half-extents (1, 0.5, 0.25) become (0.25, 0.5, 1)."""
    sdf = build_scene_sdf([Box((1.0, 0.5, 0.25)).rotate(0, 90, 0)])
    t = np.array([-3.0, -1.5, -0.1, 0.0, 0.2, 2.0])
    zeros = np.zeros_like(t)
    along = {0: np.column_stack([t, zeros, zeros]), 1: np.column_stack([zeros, t, zeros]),
             2: np.column_stack([zeros, zeros, t])}
    # On an axis outside the box: |t| minus that half-extent; inside: minus the nearest face.
    np.testing.assert_allclose(sdf(along[0])[0], [2.75, 1.25, -0.15, -0.25, -0.05, 1.75], atol=EXACT)
    np.testing.assert_allclose(sdf(along[1])[0], [2.5, 1.0, -0.25, -0.25, -0.25, 1.5], atol=EXACT)
    np.testing.assert_allclose(sdf(along[2])[0], [2.0, 0.5, -0.25, -0.25, -0.25, 1.0], atol=EXACT)
    p = np.random.default_rng(18).uniform(-3, 3, (2000, 3))
    np.testing.assert_allclose(sdf(p)[0], box_distance(p, np.array([0.25, 0.5, 1.0])),
                               rtol=0, atol=EXACT)


def test_rotated_cone_at_rotated_points_equals_unrotated_within_1e_12():
    """Rotating the shape by R = Rz Ry Rx and the points by the same R leaves distances alone."""
    p = np.random.default_rng(19).uniform(-3, 3, (1000, 3))
    for angles in ANGLES[:5]:
        sdf = build_scene_sdf([Cone(0.7, 1.4).rotate(*angles)])
        np.testing.assert_allclose(sdf(p @ euler_by_hand(*angles).T)[0], cone_distance(p, 0.7, 1.4),
                                   rtol=0, atol=EXACT)


@pytest.mark.parametrize("factor", [0.3, 1.0, 2.5])
def test_scaled_sphere_is_sphere_of_scaled_radius_within_1e_12(factor):
    p = np.random.default_rng(20).uniform(-4, 4, (2000, 3))
    sdf = build_scene_sdf([Sphere(0.8).scale(factor)])
    np.testing.assert_allclose(sdf(p)[0], sphere_distance(p, 0.8 * factor), rtol=0, atol=EXACT)


@pytest.mark.parametrize("factor", [0.3, 2.5])
def test_scaled_moved_torus_is_torus_of_scaled_radii_within_1e_12(factor):
    """Scale about the origin, then translate: a torus of radii (s R, s r) at the offset."""
    p = np.random.default_rng(21).uniform(-4, 4, (2000, 3))
    sdf = build_scene_sdf([Torus(1.0, 0.3).scale(factor).at(0.5, -1.0, 0.2)])
    expected = torus_distance(p - (0.5, -1.0, 0.2), 1.0 * factor, 0.3 * factor)
    np.testing.assert_allclose(sdf(p)[0], expected, rtol=0, atol=EXACT)
