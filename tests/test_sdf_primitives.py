"""Each SDF of reference_cpu/sdf.py against a distance derived independently, from closest points.

The reference answers here do not reuse Quilez's formulas. Each finds the nearest point of the
shape from its geometry (clamping to a box, the nearest point of a circle or a segment, a 2-D
cross-section for shapes of revolution, the nearest of the nearest points of the triangles of a
pyramid's or a hexagonal prism's mesh) and measures the distance to it; the sign says whether
the point is inside (tests/sdf_reference.py). Three kinds of points are checked: random points
far outside, random points inside, and points built on the surface and pushed along the outward
normal by a known amount, whose distance must be that amount. Last, the gradient of every
primitive has unit length, as a distance's must.

The CSG operators, repetition, rotation and scale, and whole scenes are checked in
test_sdf_csg.py, test_sdf_repeat.py, test_sdf_rotation_scale.py and test_sdf_scene_ids.py.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest
from sdf_reference import (EXACT, SINGLE, box_distance, capped_cylinder_distance,
                           capsule_distance_brute_force, capsule_sampling_step, cone_distance,
                           disk_distance, hex_prism_distance, plane_distance, plane_frame,
                           pyramid_distance, sphere_distance, torus_distance, unit)

from reference_cpu import sdf as S

# Signed pushes along the outward normal. Every surface sampler below keeps a margin of at least
# 0.05 to other parts of the surface, so inward pushes up to 1e-3 keep the same nearest point,
# and its shapes are convex enough that outward pushes up to 0.1 do too.
PUSHES = np.array([-1e-3, -1e-6, -1e-9, 0.0, 1e-9, 1e-6, 1e-3, 1e-1])


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


def turned_about_y(points, quarter_turns):
    """Each point (N, 3) turned by its own multiple of 90 degrees (N,) about the y axis."""
    angle = quarter_turns * (np.pi / 2)
    c, s = np.round(np.cos(angle)), np.round(np.sin(angle))
    return np.column_stack([c * points[:, 0] + s * points[:, 2], points[:, 1],
                            -s * points[:, 0] + c * points[:, 2]])


def pyramid_surface(base, height, margin=0.05):
    """Base points (normal -y) at least ``margin`` inside the square, and points of the side
    faces at least ``margin`` from the face's edges (normal (h, s, 0) / |(h, s)| on the +x
    face, s = base / 2, turned with the face)."""
    s = base / 2
    normal = unit(np.array([height, s, 0.0]))

    def sample(rng, n):
        base_n = n // 2
        base_points = np.column_stack([rng.uniform(-(s - margin), s - margin, base_n),
                                       np.zeros(base_n),
                                       rng.uniform(-(s - margin), s - margin, base_n)])
        # The +x face: x = s (1 - v), y = h v, z = s (1 - v) u for v in [0, 1], u in [-1, 1];
        # keep the points whose distance to each of its three edges is at least the margin.
        u, v = rng.uniform(-1, 1, 8 * n), rng.uniform(0, 1, 8 * n)
        face = np.column_stack([s * (1 - v), height * v, s * (1 - v) * u])
        apex, corners = np.array([0.0, height, 0.0]), np.array([[s, 0, s], [s, 0, -s]])
        from_edges = np.min([segment_distance_3d(face, a, b) for a, b in
                             [(corners[0], corners[1]), (corners[0], apex), (corners[1], apex)]],
                            axis=0)
        face = face[from_edges >= margin][:n - base_n]
        turns = rng.integers(0, 4, len(face))
        points = np.vstack([base_points, turned_about_y(face, turns)])
        normals = np.vstack([np.tile([0.0, -1.0, 0.0], (base_n, 1)),
                             turned_about_y(np.tile(normal, (len(face), 1)), turns)])
        return points, normals
    return sample


def segment_distance_3d(p, a, b):
    """Distance from the points p (N, 3) to the segment a-b, by clamped projection."""
    t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
    return np.linalg.norm(p - (a + t[:, None] * (b - a)), axis=-1)


def disk_surface(radius, thickness, margin=0.05):
    """Flat faces (normal +-y) at least ``margin`` inside the flat circle of radius
    a = radius - thickness / 2, and the rounded rim: (a, 0) plus thickness / 2 along a unit
    vector (cos phi, sin phi) of the (rho, y) half-plane that points outward, its normal."""
    a, rounding = radius - thickness / 2, thickness / 2

    def sample(rng, n):
        flat = n // 2
        up = rng.choice([-1.0, 1.0], flat)
        flat_points = np.column_stack([rng.uniform(0, a - margin, flat), up * rounding])
        flat_normals = np.column_stack([np.zeros(flat), up])
        phi = rng.uniform(-np.pi / 2, np.pi / 2, n - flat)
        u = np.column_stack([np.cos(phi), np.sin(phi)])
        return from_half_plane(rng, np.vstack([flat_points, np.array([a, 0.0]) + rounding * u]),
                               np.vstack([flat_normals, u]))
    return sample


def hex_prism_surface(apothem, half_length, margin=0.05):
    """Caps (normal +-z) within the circle of radius apothem - margin, which keeps them that far
    from the sides; side points at least ``margin`` from the side's edges, made on the top side
    y = apothem (normal +y) and turned about z by a multiple of 60 degrees."""
    half_side = apothem / np.sqrt(3)

    def sample(rng, n):
        caps = n // 2
        r = (apothem - margin) * np.sqrt(rng.uniform(0, 1, caps))
        theta = rng.uniform(0, 2 * np.pi, caps)
        end = rng.choice([-1.0, 1.0], caps)
        cap_points = np.column_stack([r * np.cos(theta), r * np.sin(theta), end * half_length])
        cap_normals = np.column_stack([np.zeros((caps, 2)), end])
        side = n - caps
        top = np.column_stack([rng.uniform(-(half_side - margin), half_side - margin, side),
                               np.full(side, apothem),
                               rng.uniform(-(half_length - margin), half_length - margin, side)])
        angle = rng.integers(0, 6, side) * (np.pi / 3)
        c, s = np.cos(angle), np.sin(angle)
        turn = lambda v: np.column_stack([c * v[:, 0] - s * v[:, 1],          # noqa: E731
                                          s * v[:, 0] + c * v[:, 1], v[:, 2]])
        side_normals = turn(np.tile([0.0, 1.0, 0.0], (side, 1)))
        return np.vstack([cap_points, turn(top)]), np.vstack([cap_normals, side_normals])
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
    # The pyramid and the hexagonal prism against the nearest point of their triangle meshes.
    Case("pyramid_wide", lambda p: S.sdf_pyramid(p, *cast(p, 1.6, 1.0)),
         lambda p: pyramid_distance(p, 1.6, 1.0), ((-0.8, 0, -0.8), (0.8, 1.0, 0.8)),
         pyramid_surface(1.6, 1.0)),
    Case("pyramid_tall", lambda p: S.sdf_pyramid(p, *cast(p, 0.8, 1.6)),
         lambda p: pyramid_distance(p, 0.8, 1.6), ((-0.4, 0, -0.4), (0.4, 1.6, 0.4)),
         pyramid_surface(0.8, 1.6)),
    Case("disk", lambda p: S.sdf_disk(p, *cast(p, 1.2, 0.3)),
         lambda p: disk_distance(p, 1.2, 0.3), around(1.2, 0.15, 1.2), disk_surface(1.2, 0.3)),
    Case("disk_sphere", lambda p: S.sdf_disk(p, *cast(p, 0.9, 1.8)),       # thickness 2 radius
         lambda p: sphere_distance(p, 0.9), around(0.9, 0.9, 0.9), sphere_surface(0.9)),
    Case("hex_prism", lambda p: S.sdf_hex_prism(p, *cast(p, 0.7, 0.9)),
         lambda p: hex_prism_distance(p, 0.7, 0.9), around(0.7 * 2 / np.sqrt(3), 0.7, 0.9),
         hex_prism_surface(0.7, 0.9)),
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


def test_pyramid_below_and_inside_next_to_its_base_is_the_distance_to_the_base_within_1e_12():
    """The base face, which Quilez's sdPyramid leaves out: below y = 0 the nearest point is the
    point clamped into the base square; inside, within 0.05 of the base and 0.4 of the axis
    (over 0.28 from every side), the base is nearest, at distance y."""
    base, height = 1.6, 1.0
    half = np.array([base / 2, 0.0, base / 2])
    rng = np.random.default_rng(8)
    depth = 10 ** rng.uniform(-9, 0.5, 600)
    below = np.column_stack([rng.uniform(-2, 2, 600), -depth, rng.uniform(-2, 2, 600)])
    expected = np.linalg.norm(below - np.clip(below, -half, half), axis=-1)
    np.testing.assert_allclose(S.sdf_pyramid(below, base, height), expected, rtol=0, atol=EXACT)
    inside = np.column_stack([rng.uniform(-0.4, 0.4, 600), depth * 0.05 / depth.max(),
                              rng.uniform(-0.4, 0.4, 600)])
    np.testing.assert_allclose(S.sdf_pyramid(inside, base, height), -inside[:, 1], rtol=0,
                               atol=EXACT)


def test_pyramid_points_above_apex_are_at_distance_to_it_within_1e_12():
    """On the axis above the apex the nearest point is the apex."""
    pushes = np.array([0.0, 1e-9, 1e-6, 1e-3, 0.1, 2.0])
    points = np.column_stack([np.zeros(6), 1.3 + pushes, np.zeros(6)])
    np.testing.assert_allclose(S.sdf_pyramid(points, 0.9, 1.3), pushes, rtol=0, atol=EXACT)


# --- Exactness: the gradient of a distance has unit length ------------------------------------

GRADIENT_STEP = 1e-6


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_gradient_has_unit_length_within_1e_6(case):
    """|grad f| = 1 wherever an exact distance is differentiable: everywhere but the medial
    axis (inside, where two faces are equally near; a torus's axis), which seeded random points
    miss. Central differences with step 1e-6 err by ~1e-12 / (radius of curvature)^2 from
    truncation and ~1e-9 from rounding, so 1e-6 is ample; a bound that is not a distance (a
    scaled distance, a max of unnormalised planes) misses it by far more."""
    p = far_and_inside_points(np.random.default_rng(7), case.bounds)
    gradient = np.column_stack([(case.sdf(p + e) - case.sdf(p - e)) / (2 * GRADIENT_STEP)
                                for e in np.eye(3) * GRADIENT_STEP])
    np.testing.assert_allclose(np.linalg.norm(gradient, axis=1), 1.0, rtol=0, atol=1e-6)
