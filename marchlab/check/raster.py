"""Checks for lesson 09's rasteriser: the edge function, perspective-correct interpolation,
barycentric coordinates in space and a cube map's face.

- ``edge_function`` is compared with `reference_cpu.rasterise.edge`, on points inside,
  outside and exactly on edges, in floating point and in the rasteriser's fixed point.
- ``perspective_correct`` (image barycentrics to the attribute on the triangle in space) is
  compared with what a ray caster finds: the attribute at the point where the ray through
  the image point meets the triangle (`ray_cast_attribute`), not with the rasteriser's
  formula, which is what the student writes (tests/lessons/test_checks_raster.py shows the
  two agree on the rasteriser's own weights).
- ``barycentric`` is compared with `reference_cpu.truth.mesh_cast.barycentric`, the ray
  caster's weights, on points inside and outside triangles placed anyhow in space.
- ``cube_face`` (which of a cube shadow map's six faces a direction from the light falls in)
  is compared with `reference_cpu.shadow_map.cube_face`, on random directions and on ones
  close to each axis and to the cube's edges (never exactly on them, where either face is
  right).

How a student's function is judged is in `marchlab.check.judge`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu.rasterise import SUBPIXELS, edge
from reference_cpu.shadow_map import cube_face as _cube_face_from
from reference_cpu.truth.mesh_cast import barycentric as _barycentric
from scene_model.geometry import dot

from .judge import CASES, SAMPLES, compare, unit_vectors
from .result import CheckResult

__all__ = ["edge_function", "perspective_correct", "barycentric", "cube_face"]

DEPTHS = (0.2, 50.0)       # view depths z of the corners (m): near the eye to far away


# --- edge_function ---------------------------------------------------------------------------

def _edge_cases(rng, n=SAMPLES):
    """(ax, ay, bx, by, px, py), each (n,): edges of a 160 x 120 image and points round them,
    every fourth point exactly on its edge (where the fill rule decides)."""
    a = rng.uniform(-20, 180, (n, 2))
    b = rng.uniform(-20, 180, (n, 2))
    p = rng.uniform(-20, 180, (n, 2))
    on = np.arange(n) % 4 == 0
    s = rng.integers(-2, 4, n)[:, None]                  # a + s (b - a): on the edge's line
    p[on] = (a + s * (b - a))[on]
    return a[:, 0], a[:, 1], b[:, 0], b[:, 1], p[:, 0], p[:, 1]


def _fixed_point(case):
    """A case in the rasteriser's integers: pixels times `SUBPIXELS`, rounded."""
    return tuple(np.round(v * SUBPIXELS).astype(np.int64) for v in case)


def edge_function(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(ax, ay, bx, by, px, py)`` (all (N,)) -> (N,), the edge function
    (b - a) x (p - a) of the edges a -> b at the points p."""
    rng = np.random.default_rng(seed)
    cases = [_edge_cases(rng) for _ in range(CASES)]
    cases = cases[: CASES // 2] + [_fixed_point(c) for c in cases[CASES // 2:]]
    length = lambda ax, ay, bx, by: np.hypot(bx - ax, by - ay)
    mistakes = [
        (lambda ax, ay, bx, by, px, py: edge(ax, ay, px, py, bx, by),
         "the sign is flipped: E_ab(p) = (b − a) × (p − a) = (bx − ax)(py − ay) − (by − ay)(px − "
         "ax); yours is (p − a) × (b − a), its negative, which puts every triangle's inside on "
         "the outer side of its edges."),
        (lambda ax, ay, bx, by, px, py: (bx - ax) * (py - ay) + (by - ay) * (px - ax),
         "a 2D cross product subtracts: (b − a) × (p − a) = (bx − ax)(py − ay) − (by − ay)(px − "
         "ax)."),
        (lambda ax, ay, bx, by, px, py: (bx - ax) * (px - ax) + (by - ay) * (py - ay),
         "that is the dot product (b − a)·(p − a), which measures along the edge; the edge "
         "function is the cross product (b − a) × (p − a), which measures across it: "
         "(bx − ax)(py − ay) − (by − ay)(px − ax)."),
        (lambda ax, ay, bx, by, px, py: edge(ax, ay, bx, by, px, py) / length(ax, ay, bx, by),
         "no division by the edge's length: the edge function is the cross product itself, "
         "twice the signed area of the triangle (a, b, p). Its sign says which side p is on, "
         "and the three of a triangle over their sum are p's barycentric coordinates."),
    ]
    return compare("edge_function", student, edge, cases, mistakes)


# --- perspective_correct ---------------------------------------------------------------------

def ray_cast_attribute(weights, z, attributes):
    """(N, A): the attribute at the point of a triangle that the ray through an image point
    meets, interpolated with that point's barycentric coordinates in space.

    The image point has barycentric coordinates ``weights`` (N, 3) in the image of a triangle
    whose corners lie at view depths ``z`` (N, 3) and carry ``attributes`` (N, 3, A). Which
    image triangle does not matter (the answer depends on the weights and depths only), so
    its corners are put at image points (0, 0), (1, 0), (0, 1) of a pinhole camera at the
    origin looking along +z (image point (x / z, y / z)): corner i is z_i (s_i, 1). The ray
    (s, 1) through s = sum weights_i s_i meets the corners' plane at t = (n . c_0) / (n . (s,
    1)), and `reference_cpu.truth.mesh_cast.barycentric` gives that point's weights, as the
    ray caster finds them.
    """
    weights, z = np.asarray(weights, np.float64), np.asarray(z, np.float64)
    n = len(weights)
    image = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    corners = z[:, :, None] * np.concatenate([np.broadcast_to(image, (n, 3, 2)),
                                              np.ones((n, 3, 1))], axis=2)      # (N, 3, 3)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    ray = np.column_stack([weights @ image, np.ones(n)])
    normal = np.cross(b - a, c - a)
    hit = (dot(normal, a) / dot(normal, ray))[:, None] * ray
    return np.einsum("ni,nia->na", _barycentric(hit, a, b, c), attributes)


def _interpolation_cases(rng, n=SAMPLES, size=2):
    """(weights, z, attributes): image barycentrics inside a triangle (two in three strictly
    inside, the rest on an edge), depths from near to far, ``size`` values per corner."""
    weights = rng.dirichlet(np.ones(3), n)
    edge_points = np.arange(n) % 3 == 0
    weights[edge_points, rng.integers(0, 3, edge_points.sum())] = 0.0
    weights /= weights.sum(axis=1, keepdims=True)
    z = np.exp(rng.uniform(*np.log(DEPTHS), (n, 3)))
    return weights, z, rng.uniform(-1, 1, (n, 3, size))


def _perspective(w, z, a, numerator=-1, denominator=-1, depth=None):
    """sum w z^numerator a / sum w z^denominator, or times ``depth(w, z)`` when given."""
    top = np.einsum("ni,nia->na", w * z ** numerator, a)
    if depth is not None:
        return top * depth(w, z)[:, None]
    if denominator is None:
        return top
    return top / (w * z ** denominator).sum(axis=1)[:, None]


def perspective_correct(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(weights, z, attributes)`` (weights (N, 3) barycentric in the image,
    z (N, 3) the corners' view depths, attributes (N, 3, A)) -> (N, A), the attribute at the
    surface point the image point shows."""
    rng = np.random.default_rng(seed)
    cases = [_interpolation_cases(rng, size=(2, 3, 1)[k % 3]) for k in range(CASES)]
    mistakes = [
        (lambda w, z, a: np.einsum("ni,nia->na", w, a),
         "this is affine interpolation, sum b_i a_i: right where the three depths are equal, "
         "but the image shrinks what is far, so an image point halfway between a near and a "
         "far corner shows a surface point nearer the far one. a / z is what varies linearly "
         "in the image: interpolate a_i / z_i and 1 / z_i with the weights, then divide."),
        (lambda w, z, a: _perspective(w, z, a, 1, 1),
         "divide by the depths, do not multiply: a_i / z_i and 1 / z_i are what vary linearly "
         "in the image."),
        (lambda w, z, a: _perspective(w, z, a, denominator=None),
         "sum b_i a_i / z_i is a / z at the point: divide it by sum b_i / z_i (which is 1 / z "
         "there), or the attribute shrinks with the depth."),
        (lambda w, z, a: _perspective(w, z, a, depth=lambda w, z: (w * z).sum(axis=1)),
         "the depth at the point is 1 / (sum b_i / z_i), not sum b_i z_i: z itself does not "
         "vary linearly in the image, 1 / z does."),
        (lambda w, z, a: _perspective(w, z, a, -2, -2),
         "divide by z once: a point's image is (x / z, y / z), so it is a / z and 1 / z that "
         "vary linearly in the image, not a / z²."),
    ]
    return compare("perspective_correct", student, ray_cast_attribute, cases, mistakes)


# --- barycentric -----------------------------------------------------------------------------

def _triangle_cases(rng, n=SAMPLES):
    """(p, a, b, c), each (n, 3): triangles placed anyhow in space (none thinner than an
    angle of about 6 degrees), and points in their planes, half of them outside."""
    a, b, c = (rng.uniform(-2, 2, (n, 3)) for _ in range(3))
    for _ in range(100):                        # draw the slivers again
        e1, e2, e3 = b - a, c - b, a - c
        area2 = np.linalg.norm(np.cross(e1, -e3), axis=1)
        longest = np.max([dot(e, e) for e in (e1, e2, e3)], axis=0)
        thin = area2 < 0.1 * longest
        if not thin.any():
            break
        c[thin] = a[thin] + unit_vectors(rng, int(thin.sum())) * rng.uniform(0.5, 2, (
            int(thin.sum()), 1))
    weights = rng.dirichlet(np.ones(3), n)
    # Every other point beyond one edge: that corner's weight negative, the others summing
    # to 1 minus it.
    outside = np.nonzero(np.arange(n) % 2 == 1)[0]
    corner = rng.integers(0, 3, len(outside))
    negative = -rng.uniform(0.05, 1.0, len(outside))
    weights[outside] *= (1 - negative)[:, None] / (1 - weights[outside, corner])[:, None]
    weights[outside, corner] = negative
    p = weights[:, :1] * a + weights[:, 1:2] * b + weights[:, 2:] * c
    return p, a, b, c


def _areas(p, a, b, c, signed=True, total=None):
    """Weights from the sub-triangles opposite each corner: signed (measured along the
    triangle's normal) or not, over the whole area (or over ``total``)."""
    normal = np.cross(b - a, c - a)
    whole = np.linalg.norm(normal, axis=1)
    unit = normal / whole[:, None]
    parts = [np.cross(c - b, p - b), np.cross(a - c, p - c), np.cross(b - a, p - a)]
    if signed:
        parts = [dot(s, unit) for s in parts]
    else:
        parts = [np.linalg.norm(s, axis=1) for s in parts]
    return np.stack(parts, axis=-1) / (whole if total is None else total)[:, None]


def barycentric(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, a, b, c)`` (all (N, 3), p in the plane of the triangle a, b, c) ->
    (N, 3), p's weights (w_a, w_b, w_c): p = w_a a + w_b b + w_c c, w_a + w_b + w_c = 1."""
    rng = np.random.default_rng(seed)
    cases = [_triangle_cases(rng) for _ in range(CASES)]
    opposite = ("a corner's weight is the area of the triangle p makes with the two other "
                "corners (the one opposite it) over the whole area: w_a = area(p, b, c) / "
                "area(a, b, c), and so on; ")
    mistakes = [
        (lambda p, a, b, c: _areas(p, a, b, c, signed=False),
         "the areas lost their sign: outside the triangle a weight is negative (p beyond the "
         "edge opposite that corner). Take the sign from the direction of each cross "
         "product along the triangle's normal (a dot product), not only its length."),
        (lambda p, a, b, c: _areas(p, a, b, c)[:, [1, 2, 0]],
         opposite + "yours are in the order (w_b, w_c, w_a)."),
        (lambda p, a, b, c: _areas(p, a, b, c)[:, [2, 0, 1]],
         opposite + "yours are in the order (w_c, w_a, w_b): each is the area of a triangle "
         "that has its own corner in it, not the one opposite."),
        (lambda p, a, b, c: _areas(p, a, b, c, total=np.ones(len(p))),
         "divide by the area of the whole triangle (the length of (b − a) × (c − a)): the "
         "three weights must add up to 1."),
        (lambda p, a, b, c: _areas(p, a, b, c) / 2,
         "the weights must add up to 1: the sub-triangles' areas and the whole triangle's "
         "must be measured the same way (both the length of a cross product, or both half "
         "of it)."),
    ]
    return compare("barycentric", student, _barycentric, cases, mistakes)


# --- cube_face -------------------------------------------------------------------------------

def reference_cube_face(directions):
    """(N,) the face of each of ``directions`` (N, 3), seen from the origin, in
    `reference_cpu.shadow_map.cube_face`'s order +x, -x, +y, -y, +z, -z."""
    return _cube_face_from(directions, np.zeros(3))


def _direction_cases(rng, n=SAMPLES):
    """(directions,): random ones, half of them tilted a little off an axis or off an edge of
    the cube (two coordinates equal in size), so that a face decided by the wrong rule shows,
    but none exactly on an edge."""
    d = unit_vectors(rng, n) * rng.uniform(0.1, 10.0, (n, 1))
    near_axis = np.arange(n) % 4 == 1
    axis = rng.integers(0, 3, near_axis.sum())
    d[near_axis] *= 0.2
    d[near_axis, axis] = rng.choice([-1.0, 1.0], near_axis.sum()) * rng.uniform(1, 5,
                                                                                near_axis.sum())
    rows = np.nonzero(np.arange(n) % 4 == 2)[0]             # near an edge of the cube
    first = rng.integers(0, 3, len(rows))
    second = (first + rng.integers(1, 3, len(rows))) % 3
    size = rng.uniform(1, 5, len(rows))
    d[rows] *= 0.1
    d[rows, first] = rng.choice([-1.0, 1.0], len(rows)) * size
    d[rows, second] = rng.choice([-1.0, 1.0], len(rows)) * size * rng.choice([0.99, 1.01],
                                                                             len(rows))
    return (d,)


def _faces(d, order, largest=True, signed_axis=False, negative_even=False):
    """Faces by a rule: the largest (or smallest) coordinate's axis, compared by size or by
    signed value, numbered in ``order`` (a function of axis and sign)."""
    size = d if signed_axis else np.abs(d)
    axis = np.argmax(size, axis=1) if largest else np.argmin(size, axis=1)
    negative = np.take_along_axis(d, axis[:, None], axis=1)[:, 0] < 0
    return order(axis, negative != negative_even)


def cube_face(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(directions)`` ((N, 3) directions from the light, not unit) -> (N,)
    the cube map face each falls in: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z."""
    rng = np.random.default_rng(seed)
    cases = [_direction_cases(rng) for _ in range(CASES)]
    paired = lambda axis, negative: 2 * axis + negative
    order = "faces are numbered +x, -x, +y, -y, +z, -z: face 2 k for a positive coordinate " \
        "on axis k, 2 k + 1 for a negative one"
    mistakes = [
        (lambda d: _faces(d, paired, signed_axis=True),
         "compare the coordinates' sizes |x|, |y|, |z|, not their signed values: (-5, 1, 0) "
         "leans towards -x, the face its largest size points to."),
        (lambda d: _faces(d, paired, largest=False),
         "the face is the one the direction leans towards most: the largest coordinate in "
         "size, not the smallest (a 90-degree frustum holds the directions whose largest "
         "coordinate is its axis's)."),
        (lambda d: _faces(d, paired, negative_even=True), order + " (+x is face 0)."),
        (lambda d: _faces(d, lambda axis, negative: axis + 3 * negative), order + "; yours "
         "are numbered +x, +y, +z, -x, -y, -z."),
    ]
    return compare("cube_face", student, reference_cube_face, cases, mistakes)
