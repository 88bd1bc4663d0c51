"""The CSG operators of reference_cpu/sdf.py against exact answers.

The hard union, intersection and subtraction of two overlapping shapes are checked with set
identities on the closest-point distances of tests/sdf_reference.py; the smooth ones against
Quilez's polynomial smooth minimum in closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
from sdf_reference import EXACT, box_distance, sphere_distance

from reference_cpu import sdf as S


# Two overlapping shapes A (sphere of radius 1 at the origin) and B (box of half-size 0.6 at
# (0.9, 0.3, 0)). Set identities give exact answers: outside both, the distance to A u B is the
# distance to the nearer; inside both, the depth in A n B is the depth to the nearer boundary;
# inside A and outside B, the depth in A - B is the distance to A's surface or to B, if nearer.

B_CENTRE, B_HALF = np.array([0.9, 0.3, 0.0]), np.array([0.6, 0.6, 0.6])


def two_shapes(seed, n=20000):
    p = np.random.default_rng(seed).uniform(-2, 2, (n, 3))
    return p, sphere_distance(p, 1.0), box_distance(p - B_CENTRE, B_HALF)


def test_union_outside_both_is_distance_to_nearer_shape_within_1e_12():
    p, d_a, d_b = two_shapes(7)
    outside = (d_a > 0) & (d_b > 0)
    union = S.op_union(S.sdf_sphere(p, 1.0), S.sdf_box(p - B_CENTRE, B_HALF))
    np.testing.assert_allclose(union[outside], np.where(d_a < d_b, d_a, d_b)[outside],
                               rtol=0, atol=EXACT)
    # Inside either the sign says so: the union's distance is negative exactly there.
    np.testing.assert_array_equal(union < 0, (d_a < 0) | (d_b < 0))


def test_intersection_inside_both_is_depth_to_nearer_boundary_within_1e_12():
    p, d_a, d_b = two_shapes(8)
    inside = (d_a < 0) & (d_b < 0)
    assert inside.sum() > 100
    meet = S.op_intersection(S.sdf_sphere(p, 1.0), S.sdf_box(p - B_CENTRE, B_HALF))
    depth = np.where(-d_a < -d_b, -d_a, -d_b)
    np.testing.assert_allclose(meet[inside], -depth[inside], rtol=0, atol=EXACT)
    np.testing.assert_array_equal(meet < 0, inside)


def test_subtraction_inside_result_is_exact_within_1e_12():
    p, d_a, d_b = two_shapes(9)
    inside = (d_a < 0) & (d_b > 0)
    assert inside.sum() > 100
    cut = S.op_subtraction(S.sdf_sphere(p, 1.0), S.sdf_box(p - B_CENTRE, B_HALF))
    depth = np.where(-d_a < d_b, -d_a, d_b)          # to A's surface, or to B if that is nearer
    np.testing.assert_allclose(cut[inside], -depth[inside], rtol=0, atol=EXACT)
    np.testing.assert_array_equal(cut < 0, inside)


# Quilez's polynomial smooth minimum in closed form ("Smooth minimum", iquilezles.org/articles/
# smin): smin(a, b) = min(a, b) - max(k - |a - b|, 0)^2 / (4 k). The blend digs at most k / 4, and
# nothing where the two distances differ by k or more.

def blend_depth(gap, k):
    return np.maximum(k - np.abs(gap), 0) ** 2 / (4 * k)


def random_distance_pairs(seed, n=5000):
    rng = np.random.default_rng(seed)
    return rng.uniform(-3, 3, n), rng.uniform(-3, 3, n)


@pytest.mark.parametrize("k", [0.05, 0.5, 2.0])
def test_smooth_union_is_hard_union_minus_blend_depth_within_1e_12(k):
    """Equal to min(d1, d2) where |d1 - d2| >= k, never above it, at most k / 4 below."""
    d1, d2 = random_distance_pairs(10)
    smooth, hard = S.op_smooth_union(d1, d2, k), np.where(d1 < d2, d1, d2)
    far_apart = np.abs(d1 - d2) >= k
    np.testing.assert_allclose(smooth[far_apart], hard[far_apart], rtol=0, atol=EXACT)
    assert np.all(smooth <= hard + EXACT) and np.all(hard - smooth <= k / 4 + EXACT)
    np.testing.assert_allclose(smooth, hard - blend_depth(d1 - d2, k), rtol=0, atol=EXACT)


@pytest.mark.parametrize("k", [0.05, 0.5, 2.0])
def test_smooth_intersection_is_hard_intersection_plus_blend_depth_within_1e_12(k):
    """Equal to max(d1, d2) where |d1 - d2| >= k, never below it, at most k / 4 above."""
    d1, d2 = random_distance_pairs(11)
    smooth, hard = S.op_smooth_intersection(d1, d2, k), np.where(d1 > d2, d1, d2)
    far_apart = np.abs(d1 - d2) >= k
    np.testing.assert_allclose(smooth[far_apart], hard[far_apart], rtol=0, atol=EXACT)
    assert np.all(smooth >= hard - EXACT) and np.all(smooth - hard <= k / 4 + EXACT)
    np.testing.assert_allclose(smooth, hard + blend_depth(d1 - d2, k), rtol=0, atol=EXACT)


@pytest.mark.parametrize("k", [0.05, 0.5, 2.0])
def test_smooth_subtraction_is_hard_subtraction_plus_blend_depth_within_1e_12(k):
    """Equal to max(d1, -d2) where |d1 + d2| >= k, never below it, at most k / 4 above."""
    d1, d2 = random_distance_pairs(12)
    smooth, hard = S.op_smooth_subtraction(d1, d2, k), np.where(d1 > -d2, d1, -d2)
    far_apart = np.abs(d1 + d2) >= k
    np.testing.assert_allclose(smooth[far_apart], hard[far_apart], rtol=0, atol=EXACT)
    assert np.all(smooth >= hard - EXACT) and np.all(smooth - hard <= k / 4 + EXACT)
    np.testing.assert_allclose(smooth, hard + blend_depth(d1 + d2, k), rtol=0, atol=EXACT)
