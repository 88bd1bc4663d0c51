"""Checks for lesson 01's signed distance functions: sphere, box, plane, torus and the rest.

Each exercise ``student(p, ...)`` takes points ``p : (N, 3)`` and returns distances ``(N,)``,
negative inside the shape. Its check compares it with its namesake in `reference_cpu.sdf` on
points near the shape and farther out, and names the likely cause when the answer matches a
known mistake (a squared length, a missing absolute value, swapped radii...). How the
comparison is made and reported is in `marchlab.check.judge`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu import sdf as S
from scene_model.geometry import dot

from .judge import CASES, compare, random_points
from .result import CheckResult

__all__ = ["sdf_sphere", "sdf_box", "sdf_round_box", "sdf_plane", "sdf_torus",
           "sdf_capped_cylinder", "sdf_capsule", "sdf_cone"]


def sdf_sphere(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, radius)`` (p : (N, 3)) -> (N,) against `reference_cpu.sdf.sdf_sphere`."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        r = rng.uniform(0.3, 1.5)
        cases.append((random_points(rng, r), r))
    mistakes = [
        (lambda p, r: dot(p, p) - r * r, "you returned |p|² − r², a squared quantity; the "
         "distance is |p| − r (the square root of p·p, minus the radius)."),
        (lambda p, r: dot(p, p) - r, "you used the squared length p·p: take its square root."),
        (lambda p, r: S.length(p), "the radius is missing: subtract it from |p|."),
        (lambda p, r: S.length(p) + r, "the radius must be subtracted, not added."),
    ]
    return compare("sdf_sphere", student, S.sdf_sphere, cases, mistakes, distance=True)


def sdf_box(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, half_size)`` (p : (N, 3), half_size : (3,)) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        b = rng.uniform(0.2, 1.5, 3)
        cases.append((random_points(rng, b.max()), b))
    outside = lambda p, b: S.length(np.maximum(np.abs(p) - b, 0))
    mistakes = [
        (outside, "only the outside part: inside the box your function gives 0, but the "
         "distance there is negative; add min(max(q.x, q.y, q.z), 0) with q = |p| − b."),
        (lambda p, b: S.length(np.maximum(p - b, 0)) + np.minimum((p - b).max(axis=-1), 0),
         "the absolute value is missing: q = |p| − half_size folds every octant onto the "
         "positive one; with p − half_size only one corner of the box is right."),
        (lambda p, b: S.sdf_box(p, 2 * b), "half_size is half the box's extent; you treated it "
         "as the full size."),
        (lambda p, b: (np.abs(p) - b).max(axis=-1), "max(q.x, q.y, q.z) is exact inside but "
         "only a bound outside, near the edges and corners; outside use |max(q, 0)|."),
    ]
    return compare("sdf_box", student, S.sdf_box, cases, mistakes, distance=True)


def sdf_round_box(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, half_size, radius)`` -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        b = rng.uniform(0.4, 1.5, 3)
        cases.append((random_points(rng, b.max()), b, rng.uniform(0.05, 0.35)))
    mistakes = [(lambda p, b, r: S.sdf_box(p, b) - r, "the box must first be shrunk by the "
                 "radius (half_size − radius), or the rounding makes it grow beyond half_size.")]
    return compare("sdf_round_box", student, S.sdf_round_box, cases, mistakes, distance=True)


def sdf_plane(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, normal, offset)`` (normal : (3,), not unit length) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 2.0), rng.normal(size=3) * rng.uniform(0.5, 3), rng.uniform(-1, 1))
             for _ in range(CASES)]
    mistakes = [
        (lambda p, n, h: dot(p, n) - h, "the normal is not unit length: divide it by its "
         "length before the dot product."),
        (lambda p, n, h: dot(p, n / np.sqrt(dot(n, n))) + h, "the offset is subtracted: the "
         "plane is the set of points with n·x = offset."),
    ]
    return compare("sdf_plane", student, S.sdf_plane, cases, mistakes, distance=True)


def sdf_torus(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, major_radius, minor_radius)`` (torus in the xz-plane) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        big = rng.uniform(0.6, 1.5)
        cases.append((random_points(rng, big + 0.3), big, rng.uniform(0.1, 0.5) * big))
    xy = lambda p, a, b: S.length2(S.length2(p[:, 0], p[:, 1]) - a, p[:, 2]) - b
    mistakes = [
        (lambda p, a, b: S.sdf_torus(p, b, a), "the two radii are swapped: major_radius is the "
         "radius of the ring's centre circle, minor_radius that of the tube."),
        (xy, "your torus lies in the xy-plane; marchlab's lies in the xz-plane (around the y "
         "axis): the ring uses the length of (p.x, p.z), and p.y is the height."),
        (lambda p, a, b: S.length2(S.length2(p[:, 0], p[:, 2]) - a, p[:, 1]),
         "the tube radius (minor_radius) is never subtracted."),
        (lambda p, a, b: S.length2(p[:, 0], p[:, 2]) - a - b, "the height p.y is missing: the "
         "distance to the ring is the length of the 2-D vector (|p.xz| − major_radius, p.y)."),
    ]
    return compare("sdf_torus", student, S.sdf_torus, cases, mistakes, distance=True)


def sdf_capped_cylinder(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, radius, half_height)`` (cylinder along y) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 1.0), rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0))
             for _ in range(CASES)]
    mistakes = [(lambda p, r, h: S.length2(p[:, 0], p[:, 2]) - r, "that is an infinite "
                 "cylinder: the caps at y = ±half_height are missing.")]
    return compare("sdf_capped_cylinder", student, S.sdf_capped_cylinder, cases, mistakes,
                   distance=True)


def sdf_capsule(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, a, b, radius)`` (a, b : (3,) the segment's ends) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 1.0), rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3),
              rng.uniform(0.1, 0.5)) for _ in range(CASES)]

    def unclamped(p, a, b, r):
        h = dot(p - a, b - a) / dot(b - a, b - a)
        return S.length(p - a - h[:, None] * (b - a)) - r
    mistakes = [(unclamped, "the projection h is not clamped to [0, 1]: that is the distance "
                 "to the infinite line through a and b, not to the segment.")]
    return compare("sdf_capsule", student, S.sdf_capsule, cases, mistakes, distance=True)


def sdf_cone(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, radius, height)`` (base at y = 0, apex at y = height) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 1.0) + [0, 0.5, 0], rng.uniform(0.2, 1.0), rng.uniform(0.3, 1.5))
             for _ in range(CASES)]
    return compare("sdf_cone", student, S.sdf_cone, cases, distance=True)
