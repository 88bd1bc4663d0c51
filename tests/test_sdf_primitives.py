"""Each SDF of reference_cpu/sdf.py against a distance derived independently, from closest points.

The reference answers here do not reuse Quilez's formulas. Each finds the nearest point of the
shape from its geometry (clamping to a box, the nearest point of a circle or a segment, a 2-D
cross-section for shapes of revolution) and measures the distance to it; the sign says whether
the point is inside. Three kinds of points are checked: random points far outside, random points
inside, and points built on the surface and pushed along the outward normal by a known amount,
whose distance must be that amount.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest

from reference_cpu import sdf as S
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.geometry import rotation_matrix
from scene_model.shapes import Box, Cone, Repeat, Sphere, Torus

EXACT = 1e-12   # float64: the formulas lose a few ulps of numbers of size ~10
SINGLE = 1e-5   # float32: ~100 ulps of numbers of size ~10 (float32 eps is 1.2e-7)

# Signed pushes along the outward normal. Every surface sampler below keeps a margin of at least
# 0.05 to other parts of the surface, so inward pushes up to 1e-3 keep the same nearest point,
# and its shapes are convex enough that outward pushes up to 0.1 do too.
PUSHES = np.array([-1e-3, -1e-6, -1e-9, 0.0, 1e-9, 1e-6, 1e-3, 1e-1])


# --- Reference distances, from the nearest point of each shape ------------------------------------

def unit(v):
    """v : (..., k) scaled to unit length along the last axis."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def box_distance(p, half):
    """Signed distance to the box [-half, half] in any dimension; p : (N, k), half : (k,).

    Outside, the nearest point of the box is p clamped into it. Inside, the nearest surface
    point lies on the nearest face, at distance min(half - |p|).
    """
    nearest = np.clip(p, -half, half)
    outside = np.linalg.norm(p - nearest, axis=-1)
    to_nearest_face = np.min(half - np.abs(p), axis=-1)
    is_inside = np.all(np.abs(p) <= half, axis=-1)
    return np.where(is_inside, -to_nearest_face, outside)


def sphere_distance(p, radius):
    """The nearest point of the sphere is radius * p / |p|; negative inside."""
    nearest = radius * unit(p)
    sign = np.where(np.linalg.norm(p, axis=-1) < radius, -1.0, 1.0)
    return sign * np.linalg.norm(p - nearest, axis=-1)


def plane_frame(normal):
    """An orthonormal frame (t1, t2, n) whose last vector is the unit normal; (3, 3) rows."""
    n = unit(np.asarray(normal, dtype=np.float64))
    # QR of a matrix whose first column is n gives two further orthonormal columns.
    q, _ = np.linalg.qr(np.column_stack([n, np.eye(3)[:, :2]]))
    return np.array([q[:, 1], q[:, 2], n])


def plane_distance(p, normal, offset):
    """Coordinate of p along the unit normal, measured from the plane's point offset * n."""
    frame = plane_frame(normal)
    return (p - offset * frame[2]) @ frame[2]


def azimuth_frame(p):
    """Distance from the y axis and the unit radial direction in the xz-plane; p : (N, 3)."""
    rho = np.hypot(p[:, 0], p[:, 2])
    radial = np.column_stack([p[:, 0], np.zeros(len(p)), p[:, 2]]) / rho[:, None]
    return rho, radial


def torus_distance(p, major, minor):
    """Distance to the nearest point of the centre circle (radius ``major`` in the xz-plane), minus
    the tube radius."""
    _, radial = azimuth_frame(p)
    nearest_on_circle = major * radial
    return np.linalg.norm(p - nearest_on_circle, axis=-1) - minor


def capped_cylinder_distance(p, radius, half_height):
    """In the (rho, y) half-plane the cylinder is the rectangle [0, R] x [-h, h]; measuring to
    [-R, R] x [-h, h] instead keeps the axis rho = 0 from counting as a boundary."""
    rho, _ = azimuth_frame(p)
    return box_distance(np.column_stack([rho, p[:, 1]]), np.array([radius, half_height]))


def capsule_distance_brute_force(p, a, b, radius, samples=20001):
    """Distance to the nearest of ``samples`` evenly spaced points of the segment a-b, minus r.

    The true nearest point of the segment is within half a spacing, |b - a| / (2 (samples - 1)),
    of a sample, so this overestimates the exact distance by at most that step, never less.
    """
    segment = a + np.linspace(0.0, 1.0, samples)[:, None] * (b - a)
    nearest_squared = np.empty(len(p))
    for start in range(0, len(p), 64):                     # (64, samples, 3) at a time
        offsets = p[start:start + 64, None, :] - segment[None, :, :]
        nearest_squared[start:start + 64] = np.einsum("nsk,nsk->ns", offsets, offsets).min(axis=1)
    return np.sqrt(nearest_squared) - radius


def capsule_sampling_step(a, b, samples=20001):
    return np.linalg.norm(np.subtract(b, a)) / (2 * (samples - 1))


def segment_distance_2d(p, a, b):
    """Distance from points p : (N, 2) to the segment a-b, by clamped projection (Ericson,
    Real-Time Collision Detection, section 5.1.2)."""
    ab = b - a
    t = np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=-1)


def cone_distance(p, radius, height):
    """In the (rho, y) half-plane the cone is the triangle (0, 0), (R, 0), (0, H).

    Its boundary there is the base [(0,0), (R,0)] and the slant [(R,0), (0,H)]; the edge on the
    axis is not a surface of the solid. Inside: above the base and below the slant line
    rho / R + y / H = 1.
    """
    rho, _ = azimuth_frame(p)
    q = np.column_stack([rho, p[:, 1]])
    origin, rim, apex = np.array([0.0, 0.0]), np.array([radius, 0.0]), np.array([0.0, height])
    distance = np.minimum(segment_distance_2d(q, origin, rim), segment_distance_2d(q, rim, apex))
    is_inside = (q[:, 1] >= 0) & (q[:, 0] / radius + q[:, 1] / height <= 1)
    return np.where(is_inside, -distance, distance)


# --- Points on each surface, with their outward normals ---------------------------------------

def random_units(rng, n, k=3):
    return unit(rng.normal(size=(n, k)))


def from_half_plane(rng, rho_y, normal_rho_y):
    """Revolve (rho, y) points and (rho, y) normals, each (N, 2), to random azimuths in 3-D."""
    phi = rng.uniform(0, 2 * np.pi, len(rho_y))
    radial = np.column_stack([np.cos(phi), np.zeros_like(phi), np.sin(phi)])
    up = np.array([0.0, 1.0, 0.0])
    points = rho_y[:, :1] * radial + rho_y[:, 1:] * up
    normals = normal_rho_y[:, :1] * radial + normal_rho_y[:, 1:] * up
    return points, normals


def sphere_surface(radius):
    def sample(rng, n):
        u = random_units(rng, n)
        return radius * u, u
    return sample


def box_faces(half, margin=0.05):
    """Points on the faces, at least ``margin`` from every edge; normals along the axes."""
    half = np.asarray(half)

    def sample(rng, n):
        points = rng.uniform(-(half - margin), half - margin, size=(n, 3))
        axis, side = rng.integers(0, 3, n), rng.choice([-1.0, 1.0], n)
        points[np.arange(n), axis] = side * half[axis]
        normals = np.zeros((n, 3))
        normals[np.arange(n), axis] = side
        return points, normals
    return sample


def round_box_surface(half, radius):
    """Faces, rounded edges and corners alike: a point z outside the inner box (half - radius)
    has nearest inner point c = clamp(z); c + radius * unit(z - c) is on the rounded surface."""
    inner = np.asarray(half) - radius

    def sample(rng, n):
        z = rng.uniform(-3, 3, size=(n, 3)) * np.asarray(half)
        z = z[box_distance(z, inner) > 0.05][:n]
        nearest = np.clip(z, -inner, inner)
        normals = unit(z - nearest)
        return nearest + radius * normals, normals
    return sample


def plane_surface(normal, offset):
    frame = plane_frame(normal)

    def sample(rng, n):
        a, b = rng.uniform(-5, 5, size=(2, n, 1))
        return offset * frame[2] + a * frame[0] + b * frame[1], np.tile(frame[2], (n, 1))
    return sample


def torus_surface(major, minor):
    """Centre-circle point c, then ``minor`` along a direction u in the tube's cross-section."""
    def sample(rng, n):
        theta = rng.uniform(0, 2 * np.pi, n)
        u = np.column_stack([np.cos(theta), np.sin(theta)])             # (rho, y)
        return from_half_plane(rng, np.array([major, 0.0]) + minor * u, u)
    return sample


def capped_cylinder_surface(radius, half_height, margin=0.05):
    """Side points away from the rims, and cap points away from the rim."""
    def sample(rng, n):
        side = n // 2
        y = rng.uniform(-(half_height - margin), half_height - margin, side)
        side_points = np.column_stack([np.full(side, radius), y])
        side_normals = np.tile([1.0, 0.0], (side, 1))
        up = rng.choice([-1.0, 1.0], n - side)
        cap_points = np.column_stack([rng.uniform(0, radius - margin, n - side), up * half_height])
        cap_normals = np.column_stack([np.zeros(n - side), up])
        return from_half_plane(rng, np.vstack([side_points, cap_points]),
                               np.vstack([side_normals, cap_normals]))
    return sample


def capsule_surface(a, b, radius):
    """Body: a point of the segment plus radius times a unit vector across it. Caps: an end plus
    radius times a unit vector pointing away from the segment."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    axis = unit(b - a)

    def sample(rng, n):
        u = random_units(rng, n)
        along = u @ axis
        body = np.arange(n) < n // 2
        u[body] = unit(u[body] - along[body, None] * axis)              # across the segment
        foot = a + rng.uniform(0, 1, (n, 1)) * (b - a)
        foot[~body] = np.where((along[~body] >= 0)[:, None], b, a)       # the cap facing u
        return foot + radius * u, u
    return sample


def cone_surface(radius, height, margin=0.1):
    """Base points (normal -y) and slant points (normal (H, R) / |(H, R)| in (rho, y))."""
    slant_normal = unit(np.array([height, radius]))

    def sample(rng, n):
        base = n // 2
        base_points = np.column_stack([rng.uniform(0, (1 - margin) * radius, base), np.zeros(base)])
        t = rng.uniform(margin, 1 - margin, (n - base, 1))
        slant_points = (1 - t) * np.array([radius, 0.0]) + t * np.array([0.0, height])
        normals = np.vstack([np.tile([0.0, -1.0], (base, 1)), np.tile(slant_normal, (n - base, 1))])
        return from_half_plane(rng, np.vstack([base_points, slant_points]), normals)
    return sample


# --- The primitives under test ---------------------------------------------------------------

def cast(p, *values):
    """Parameters in the dtype of the points, as build_scene_sdf passes them."""
    out = [np.asarray(v, dtype=np.float64).astype(p.dtype)[()] for v in values]
    return out if len(out) > 1 else out[0]


@dataclass(frozen=True)
class Case:
    """One primitive with fixed parameters, its independent reference and a surface sampler."""
    name: str
    sdf: Callable[[np.ndarray], np.ndarray]          # reference_cpu.sdf, parameters cast to p
    reference: Callable[[np.ndarray], np.ndarray]    # float64, from the nearest point
    bounds: tuple                                    # (lower, upper) corners around the shape
    surface: Callable                                # surface(rng, n) -> points, outward normals
    tolerance: float = EXACT


def around(x, y, z):
    """The box [-(x, y, z), (x, y, z)] as (lower, upper) corners."""
    return (-np.array([x, y, z]), np.array([x, y, z]))


CAPSULE_A, CAPSULE_B = np.array([-0.6, -0.4, 0.2]), np.array([0.5, 0.7, -0.3])
CAPSULE_BOUNDS = (np.minimum(CAPSULE_A, CAPSULE_B) - 0.4, np.maximum(CAPSULE_A, CAPSULE_B) + 0.4)

CASES = [
    Case("sphere", lambda p: S.sdf_sphere(p, cast(p, 1.3)),
         lambda p: sphere_distance(p, 1.3), around(1.3, 1.3, 1.3), sphere_surface(1.3)),
    Case("box", lambda p: S.sdf_box(p, cast(p, (1.0, 0.5, 0.25))),
         lambda p: box_distance(p, np.array([1.0, 0.5, 0.25])), around(1.0, 0.5, 0.25),
         box_faces((1.0, 0.5, 0.25))),
    Case("round_box", lambda p: S.sdf_round_box(p, *cast(p, (1.0, 0.6, 0.4), 0.3)),
         lambda p: box_distance(p, np.array([0.7, 0.3, 0.1])) - 0.3, around(1.0, 0.6, 0.4),
         round_box_surface((1.0, 0.6, 0.4), 0.3)),
    Case("plane", lambda p: S.sdf_plane(p, *cast(p, (1.0, 2.0, -2.0), 0.7)),
         lambda p: plane_distance(p, (1.0, 2.0, -2.0), 0.7), around(6.0, 6.0, 6.0),
         plane_surface((1.0, 2.0, -2.0), 0.7)),
    Case("torus", lambda p: S.sdf_torus(p, *cast(p, 1.2, 0.35)),
         lambda p: torus_distance(p, 1.2, 0.35), around(1.55, 0.35, 1.55), torus_surface(1.2, 0.35)),
    Case("capped_cylinder", lambda p: S.sdf_capped_cylinder(p, *cast(p, 0.8, 1.1)),
         lambda p: capped_cylinder_distance(p, 0.8, 1.1), around(0.8, 1.1, 0.8),
         capped_cylinder_surface(0.8, 1.1)),
    Case("capsule", lambda p: S.sdf_capsule(p, *cast(p, CAPSULE_A, CAPSULE_B, 0.4)),
         lambda p: capsule_distance_brute_force(p, CAPSULE_A, CAPSULE_B, 0.4), CAPSULE_BOUNDS,
         capsule_surface(CAPSULE_A, CAPSULE_B, 0.4),
         tolerance=capsule_sampling_step(CAPSULE_A, CAPSULE_B) + EXACT),
    Case("cone_wide", lambda p: S.sdf_cone(p, *cast(p, 1.5, 0.8)),
         lambda p: cone_distance(p, 1.5, 0.8), ((-1.5, 0, -1.5), (1.5, 0.8, 1.5)),
         cone_surface(1.5, 0.8)),
    Case("cone_tall", lambda p: S.sdf_cone(p, *cast(p, 0.5, 2.0)),
         lambda p: cone_distance(p, 0.5, 2.0), ((-0.5, 0, -0.5), (0.5, 2.0, 0.5)),
         cone_surface(0.5, 2.0)),
]
CASE_IDS = [case.name for case in CASES]


def far_and_inside_points(rng, bounds, n=1500):
    """Points in [-6, 6]^3 (mostly far outside) and in the shape's bounding box (many inside)."""
    return np.vstack([rng.uniform(-6, 6, (n, 3)), rng.uniform(*bounds, (n, 3))])


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_primitive_matches_closest_point_distance_within_1e_12(case):
    """Far outside and inside, within 1e-12 (capsule: within its brute-force sampling step)."""
    p = far_and_inside_points(np.random.default_rng(1), case.bounds)
    expected = case.reference(p)
    assert (expected < 0).sum() > 100 and (expected > 1).sum() > 100   # both regions sampled
    np.testing.assert_allclose(case.sdf(p), expected, rtol=0, atol=case.tolerance)


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_points_pushed_along_normal_are_at_push_distance_within_1e_12(case):
    """A surface point moved by h along its outward normal has signed distance h."""
    rng = np.random.default_rng(2)
    on_surface, normals = case.surface(rng, 400)
    for h in PUSHES:
        d = case.sdf(on_surface + h * normals)
        np.testing.assert_allclose(d, h, rtol=0, atol=EXACT, err_msg=f"push {h}")


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_float32_points_give_float32_distances_within_1e_5(case):
    """With float32 points and parameters the distance stays float32 and close to the exact one."""
    p = far_and_inside_points(np.random.default_rng(3), case.bounds).astype(np.float32)
    d = case.sdf(p)
    assert d.dtype == np.float32
    np.testing.assert_allclose(d, case.reference(p.astype(np.float64)), rtol=0,
                               atol=SINGLE + case.tolerance)


def test_capsule_never_exceeds_brute_force_distance_and_is_within_its_step():
    """Sampling the segment can only overestimate, by at most half the spacing of the samples:
    0 <= brute force - sdf_capsule <= step (+1e-12)."""
    p = far_and_inside_points(np.random.default_rng(4), CAPSULE_BOUNDS)
    gap = capsule_distance_brute_force(p, CAPSULE_A, CAPSULE_B, 0.4) - S.sdf_capsule(
        p, CAPSULE_A, CAPSULE_B, 0.4)
    assert gap.min() >= -EXACT
    assert gap.max() <= capsule_sampling_step(CAPSULE_A, CAPSULE_B) + EXACT


def test_box_points_off_edges_and_corners_are_at_push_distance_within_1e_12():
    """Outside an edge or corner the nearest point is the clamped point: corner + h u, with u in
    the corner's octant, is at distance h."""
    half = np.array([1.0, 0.5, 0.25])
    rng = np.random.default_rng(5)
    signs = rng.choice([-1.0, 1.0], (300, 3))
    corner_or_edge = signs * half
    u = np.abs(random_units(rng, 300)) * signs
    # A third lie off an edge along x: anywhere along it, pushed across it (u_x = 0).
    corner_or_edge[:100, 0] = rng.uniform(-half[0], half[0], 100)
    u[:100, 0] = 0.0
    u = unit(u)
    for h in [0.0, 1e-9, 1e-6, 1e-3, 0.5, 3.0]:
        np.testing.assert_allclose(S.sdf_box(corner_or_edge + h * u, half), h, rtol=0, atol=EXACT)


def test_cone_points_beyond_apex_and_rim_are_at_distance_to_them_within_1e_12():
    """Above the apex on the axis, and outside the rim between the base's and the slant's
    normals, the nearest point is the apex or the rim circle."""
    radius, height = 1.5, 0.8
    rng = np.random.default_rng(6)
    pushes = np.array([1e-9, 1e-6, 1e-3, 0.1, 2.0])
    apex = np.column_stack([np.zeros(5), height + pushes])
    np.testing.assert_allclose(S.sdf_cone(from_half_plane(rng, apex, apex)[0], radius, height),
                               pushes, rtol=0, atol=EXACT)
    # Directions between the base normal (0, -1) and the slant normal (H, R) / |(H, R)|.
    lowest, highest = -np.pi / 2, np.arctan2(radius, height)
    angle = rng.uniform(lowest, highest, 200)
    u = np.column_stack([np.cos(angle), np.sin(angle)])
    for h in pushes:
        points, _ = from_half_plane(rng, np.array([radius, 0.0]) + h * u, u)
        np.testing.assert_allclose(S.sdf_cone(points, radius, height), h, rtol=0, atol=EXACT)


# --- CSG operators -------------------------------------------------------------------------------
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


# --- Repetition ------------------------------------------------------------------------------------

PERIOD = np.array([2.0, 0.0, 3.0])      # repeat along x and z, leave y alone


def points_in_cells(rng, cells, n=1000, margin=0.01):
    """Offsets u from the cell centre (kept ``margin`` inside the cell) and the points
    u + period * cell for integer cells drawn from -cells..cells; u_y is any value."""
    u = rng.uniform(-0.5, 0.5, (n, 3)) * (PERIOD - 2 * margin)
    u[:, 1] = rng.uniform(-5, 5, n)
    cell = rng.integers(-cells, cells + 1, (n, 3)) * (PERIOD > 0)
    return u, u + PERIOD * cell, cell


def test_repeat_folds_point_to_offset_from_cell_centre_within_1e_10():
    """Along x and z the folded point is the offset from the nearest cell centre, so the field
    is periodic with the period; along y (period 0) the coordinate is returned unchanged.
    Points lie up to 150 from the origin, where one ulp is 3e-14: hence 1e-10, not 1e-12."""
    u, p, _ = points_in_cells(np.random.default_rng(13), cells=50)
    folded = S.op_repeat(p, PERIOD)
    np.testing.assert_allclose(folded, u, rtol=0, atol=1e-10)
    np.testing.assert_array_equal(folded[:, 1], p[:, 1])


def test_repeated_box_field_is_periodic_within_1e_10():
    """An off-centre box repeated every period: moving by whole periods (up to 60 away, hence
    1e-10) leaves the distance unchanged; it is the distance to the box in the point's own cell
    (within 1e-12)."""
    node = Repeat(Box((0.3, 0.4, 0.5)).at(0.2, 0.0, -0.4), tuple(PERIOD))
    sdf = build_scene_sdf([node])
    u, p, _ = points_in_cells(np.random.default_rng(14), cells=20)
    np.testing.assert_allclose(sdf(p)[0], sdf(u)[0], rtol=0, atol=1e-10)
    np.testing.assert_allclose(sdf(u)[0], box_distance(u - (0.2, 0.0, -0.4), np.array([0.3, 0.4, 0.5])),
                               rtol=0, atol=EXACT)


def test_limited_repeat_equals_repeat_inside_kept_cells():
    """Within cells -count..count the limited fold is the infinite fold, bit for bit."""
    count = np.array([2.0, 0.0, 1.0])
    _, p, cell = points_in_cells(np.random.default_rng(15), cells=3)
    kept = np.all(np.abs(cell) <= count, axis=1)
    assert kept.sum() > 100 and (~kept).sum() > 100
    np.testing.assert_array_equal(S.op_repeat_limited(p[kept], PERIOD, count),
                                  S.op_repeat(p[kept], PERIOD))


def test_limited_repeat_of_sphere_is_distance_to_nearest_kept_copy_within_1e_12():
    """The limited field equals the distance to the nearest of the (2 count + 1) copies, found by
    trying all of them; so beyond the last copy it keeps growing instead of repeating."""
    count, radius = np.array([2, 0, 1]), 0.6
    p = np.random.default_rng(16).uniform(-12, 12, (3000, 3))
    centres = np.array([(i * PERIOD[0], 0.0, k * PERIOD[2])
                        for i in range(-count[0], count[0] + 1)
                        for k in range(-count[2], count[2] + 1)])
    expected = np.linalg.norm(p[:, None, :] - centres[None], axis=-1).min(axis=1) - radius
    got = S.sdf_sphere(S.op_repeat_limited(p, PERIOD, count.astype(float)), radius)
    np.testing.assert_allclose(got, expected, rtol=0, atol=EXACT)
    beyond = p[:, 0] > PERIOD[0] * (count[0] + 1)      # past the last copy along +x
    assert np.all(got[beyond] > S.sdf_sphere(S.op_repeat(p[beyond], PERIOD), radius))


# --- Rotation and scale ----------------------------------------------------------------------------

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


# --- The whole scene: object ids ------------------------------------------------------------------

def test_object_id_is_depth_first_index_of_chosen_primitive():
    """Ids in depth-first order: 0 the sphere, 1 the box and 2 the sphere of the intersection,
    3 the torus. A union picks the nearer primitive's id, an intersection the farther one's."""
    left = Sphere(1.0).at(-2.5, 0, 0)
    lens = Box((0.8, 0.8, 0.8)) & Sphere(1.0).at(0.6, 0.0, 0.0)
    ring = Torus(1.0, 0.3).at(2.5, 0, 0)
    p = np.random.default_rng(22).uniform(-4, 4, (5000, 3))
    distance, ids = build_scene_sdf([left, lens, ring], with_ids=True)(p)

    d0 = sphere_distance(p - (-2.5, 0, 0), 1.0)
    d1 = box_distance(p, np.array([0.8, 0.8, 0.8]))
    d2 = sphere_distance(p - (0.6, 0, 0), 1.0)
    d3 = torus_distance(p - (2.5, 0, 0), 1.0, 0.3)
    lens_d, lens_id = np.where(d1 >= d2, d1, d2), np.where(d1 >= d2, 1, 2)
    candidates = np.column_stack([d0, lens_d, d3])
    nearest = np.argmin(candidates, axis=1)
    expected_ids = np.choose(nearest, [np.zeros_like(lens_id), lens_id, np.full_like(lens_id, 3)])

    np.testing.assert_allclose(distance, candidates.min(axis=1), rtol=0, atol=EXACT)
    np.testing.assert_array_equal(ids, expected_ids)
    assert set(np.unique(ids)) == {0, 1, 2, 3}          # every branch was exercised


def test_subtraction_gives_the_cutter_id_where_the_cut_is_nearest():
    """Inside a box's hollow cut by a sphere the nearest surface is the sphere's: id 1."""
    sdf = build_scene_sdf([Box((1.0, 1.0, 1.0)) - Sphere(0.5)], with_ids=True)
    p = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.6], [0.0, 0.0, 0.95], [0.0, 0.0, 3.0]])
    distance, ids = sdf(p)
    np.testing.assert_allclose(distance, [0.5, -0.1, -0.05, 2.0], atol=EXACT)
    np.testing.assert_array_equal(ids, [1, 1, 0, 0])


def test_distances_do_not_depend_on_asking_for_ids():
    objects = [Sphere(1.0).at(-1, 0, 0) | Box((0.5, 0.7, 0.2)).rotate(10, 20, 30), Torus()]
    p = np.random.default_rng(23).uniform(-3, 3, (500, 3))
    with_ids, without = build_scene_sdf(objects, with_ids=True)(p), build_scene_sdf(objects)(p)
    np.testing.assert_array_equal(with_ids[0], without[0])
    assert without[1] is None and with_ids[1].shape == (500,)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_empty_scene_is_infinitely_far_with_id_minus_1(dtype):
    p = np.zeros((4, 3), dtype=dtype)
    distance, ids = build_scene_sdf([], dtype=dtype, with_ids=True)(p)
    assert distance.dtype == dtype and np.all(np.isposinf(distance))
    np.testing.assert_array_equal(ids, [-1, -1, -1, -1])


def test_float32_scene_with_every_node_kind_stays_float32_within_1e_5():
    """build_scene_sdf casts parameters to float32; transforms and operators must keep it."""
    scene = [(Box((0.5, 0.4, 0.3)).rotate(10, 20, 30).scale(1.5) | Cone(0.5, 1.0).at(1, 0, 0))
             - Sphere(0.3),
             Repeat(Torus(0.5, 0.1), (3.0, 0.0, 3.0), (1, 0, 1)).at(0, -2, 0)]
    p = np.random.default_rng(24).uniform(-4, 4, (2000, 3))
    d64 = build_scene_sdf(scene, dtype=np.float64)(p)[0]
    d32 = build_scene_sdf(scene, dtype=np.float32)(p.astype(np.float32))[0]
    assert d32.dtype == np.float32
    np.testing.assert_allclose(d32, d64, rtol=0, atol=SINGLE)
