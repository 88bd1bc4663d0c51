"""Checks for lesson 02's operators on SDFs: CSG, smooth blends and transforms.

The CSG and blend exercises combine two arrays of signed distances ``d1, d2 : (N,)``; the
transforms move the query points ``p : (N, 3)`` the opposite way to the shape. Each check
compares the student's function with its namesake in `reference_cpu.sdf` (how, in
`marchlab.check.judge`) and knows the classic mistakes: a union that keeps the farther
surface, a fillet term with the wrong sign, a translation the wrong way round.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu import sdf as S
from scene_model.geometry import rotation_matrix

from .judge import CASES, SAMPLES, compare, random_points
from .result import CheckResult

__all__ = ["op_union", "op_intersection", "op_subtraction", "op_smooth_union",
           "op_smooth_intersection", "op_smooth_subtraction", "smooth_union",
           "op_translate", "op_rotate", "op_scale", "op_repeat", "op_repeat_limited"]


# --- CSG operators ---------------------------------------------------------------------------

def _distances(rng, n=SAMPLES):
    """Two (n,) arrays of signed distances; a third of the pairs are close (inside a blend)."""
    d1 = rng.uniform(-2, 2, n)
    d2 = np.where(np.arange(n) % 3 == 0, d1 + rng.uniform(-0.3, 0.3, n), rng.uniform(-2, 2, n))
    return d1, d2


def _pairs(seed, with_k):
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        d1, d2 = _distances(rng)
        cases.append((d1, d2, rng.uniform(0.1, 1.0)) if with_k else (d1, d2))
    return cases


def op_union(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2)`` (two (N,) distances) -> (N,)."""
    mistakes = [(lambda a, b: np.maximum(a, b), "that is the intersection: a union keeps the "
                 "nearer surface, min(d1, d2).")]
    return compare("op_union", student, S.op_union, _pairs(seed, False), mistakes, True)


def op_intersection(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2)`` -> (N,)."""
    mistakes = [(lambda a, b: np.minimum(a, b), "that is the union: an intersection keeps the "
                 "farther surface, max(d1, d2).")]
    return compare("op_intersection", student, S.op_intersection, _pairs(seed, False),
                   mistakes, True)


def op_subtraction(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2)`` (shape 1 minus shape 2) -> (N,)."""
    mistakes = [
        (lambda a, b: np.maximum(-a, b), "you cut shape 1 out of shape 2; the result should be "
         "shape 1 minus shape 2: max(d1, −d2)."),
        (lambda a, b: np.maximum(a, b), "that is the intersection: negate the cutter, "
         "max(d1, −d2)."),
        (lambda a, b: a - b, "distances do not subtract: 'inside 1 and outside 2' is "
         "max(d1, −d2)."),
        (lambda a, b: np.minimum(a, -b), "min keeps the points inside 1 *or* outside 2 (a union "
         "with everything around shape 2); 'inside 1 and outside 2' is an intersection: "
         "max(d1, −d2)."),
    ]
    return compare("op_subtraction", student, S.op_subtraction, _pairs(seed, False),
                   mistakes, True)


# The blend factor h of each smooth operator before clamping, and the sign of its k h (1 - h)
# term, to build the wrong versions a student might write (the right ones are in
# reference_cpu.sdf).
_BLEND = {
    "op_smooth_union": (lambda a, b, k: 0.5 + 0.5 * (b - a) / k, -1),
    "op_smooth_intersection": (lambda a, b, k: 0.5 - 0.5 * (b - a) / k, 1),
    "op_smooth_subtraction": (lambda a, b, k: 0.5 - 0.5 * (a + b) / k, 1),
}


def _smooth_mistakes(reference, hard, mix_second):
    """Mistakes shared by the three smooth operators; ``mix_second(d1, d2)`` is the value
    the mix takes at h = 1 (d1, or -d2 for the subtraction)."""
    raw, sign = _BLEND[reference.__name__]
    blend = lambda a, b, k: np.clip(raw(a, b, k), 0, 1)
    fillet = lambda a, b, k: sign * k * blend(a, b, k) * (1 - blend(a, b, k))

    def unclamped(a, b, k):
        h, first = raw(a, b, k), (b if reference is S.op_smooth_union else a)
        return first + (mix_second(a, b) - first) * h + sign * k * h * (1 - h)
    return [
        (lambda a, b, k: hard(a, b), "there is no blending: that is the hard operator; mix the "
         "two distances by h and add the k·h·(1 − h) term."),
        (lambda a, b, k: reference(a, b, k) - 2 * fillet(a, b, k), "the k·h·(1 − h) term has "
         f"the wrong sign: this operator {'subtracts' if sign < 0 else 'adds'} it."),
        (lambda a, b, k: reference(a, b, k) - fillet(a, b, k), "the k·h·(1 − h) term is "
         "missing: mixing alone does not round the seam."),
        (unclamped, "h is not clamped to [0, 1]: outside the blend region (where the distances "
         "differ by more than k) it must select one of them."),
    ]


def op_smooth_union(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2, k)`` (Quilez's polynomial smooth minimum) -> (N,)."""
    def h_backwards(a, b, k):
        h = np.clip(0.5 + 0.5 * (b - a) / k, 0, 1)
        return a + (b - a) * h - k * h * (1 - h)
    mistakes = _smooth_mistakes(S.op_smooth_union, S.op_union, lambda a, b: a) + [
        (h_backwards, "h is backwards: h = 1 should select d1, so the mix is d2 + (d1 − d2)·h, "
         "i.e. mix(d2, d1, h).")]
    return compare("op_smooth_union", student, S.op_smooth_union, _pairs(seed, True),
                   mistakes, True)


smooth_union = op_smooth_union


# Lesson 02 derives the smooth intersection and subtraction from the smooth union, with
# max(a, b) = −min(−a, −b): intersection = −smin(−d1, −d2), subtraction = −smin(−d1, d2).
# These are the slips of that derivation.
_NEGATE_RESULT = ("max(a, b) = −min(−a, −b): the smooth minimum of the negated distances must "
                  "be negated again, or inside and outside swap.")


def op_smooth_intersection(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2, k)`` -> (N,)."""
    smin = S.op_smooth_union
    mistakes = _smooth_mistakes(S.op_smooth_intersection, S.op_intersection, lambda a, b: a) + [
        (lambda a, b, k: smin(-a, -b, k), _NEGATE_RESULT),
        (lambda a, b, k: smin(a, b, k), "that is the smooth union; an intersection is a "
         "(smooth) maximum: −smin(−d1, −d2, k)."),
    ]
    return compare("op_smooth_intersection", student, S.op_smooth_intersection,
                   _pairs(seed, True), mistakes, True)


def op_smooth_subtraction(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2, k)`` (shape 1 minus shape 2, rounded) -> (N,)."""
    smin = S.op_smooth_union
    mistakes = _smooth_mistakes(S.op_smooth_subtraction, S.op_subtraction, lambda a, b: -b) + [
        (lambda a, b, k: smin(-a, b, k), _NEGATE_RESULT),
        (lambda a, b, k: -smin(a, -b, k), "you cut shape 1 out of shape 2; the result should "
         "be shape 1 minus shape 2, the smooth version of max(d1, −d2)."),
        (lambda a, b, k: smin(a, -b, k), "a smooth minimum of d1 and −d2 keeps the points "
         "inside 1 *or* outside 2; 'inside 1 and outside 2' is a (smooth) maximum of d1 and "
         "−d2."),
    ]
    return compare("op_smooth_subtraction", student, S.op_smooth_subtraction,
                   _pairs(seed, True), mistakes, True)


# --- Transforms (they move the query point) ----------------------------------------------------

def op_translate(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, offset)`` -> (N, 3), the query point of a moved shape."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 2.0), rng.uniform(-2, 2, 3)) for _ in range(CASES)]
    mistakes = [(lambda p, o: p + o, "a transform moves the query point the opposite way: "
                 "to move the shape by offset, evaluate it at p − offset.")]
    return compare("op_translate", student, S.op_translate, cases, mistakes)


def op_rotate(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, matrix)`` (matrix : (3, 3) rotation R) -> (N, 3), R^T p per point."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 2.0), rotation_matrix(rng.uniform(-180, 180, 3)))
             for _ in range(CASES)]
    mistakes = [(lambda p, m: p @ m.T, "you rotated the point by R; the query point turns the "
                 "other way, by R⁻¹ = Rᵀ (p @ R in NumPy's row-vector form).")]
    return compare("op_rotate", student, S.op_rotate, cases, mistakes)


def op_scale(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, factor)`` -> (N, 3), the query point of a shape scaled by factor."""
    rng = np.random.default_rng(seed)
    cases = [(random_points(rng, 2.0), rng.uniform(0.3, 3.0)) for _ in range(CASES)]
    mistakes = [(lambda p, s: p * s, "to make the shape s times larger, shrink the query "
                 "point: p / s (and multiply the distance back by s afterwards).")]
    return compare("op_scale", student, S.op_scale, cases, mistakes)


def op_repeat(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, period)`` (period : (3,), 0 = no repetition on that axis) -> (N, 3)."""
    rng = np.random.default_rng(seed)
    cases = []
    for j in range(CASES):
        period = rng.uniform(0.5, 2.0, 3)
        period[j % 3] = 0.0 if j >= 4 else period[j % 3]     # half the cases leave an axis alone
        cases.append((random_points(rng, 4.0), period))
    safe = lambda c: np.where(c > 0, c, 1)
    zero_axes = ("; and an axis whose period is 0 is not repeated: leave that coordinate as it "
                 "is, np.where(period > 0, ..., p), instead of dividing by 0")
    not_centred = ("np.mod gives 0..period: the cell is not centred on the origin; subtract "
                   "period·floor(p / period + 0.5)")
    mistakes = [
        (lambda p, c: np.where(c > 0, np.mod(p, safe(c)), p), not_centred + "."),
        (lambda p, c: np.mod(p, c), not_centred + zero_axes + "."),
        (lambda p, c: np.where(c > 0, np.mod(p, safe(c)) - c / 2, p), "mod(p, c) − c/2 puts "
         "the copy at the corner of the cell: the original shape (at the origin) is not one of "
         "the copies; use p − c·floor(p/c + 0.5)."),
        (lambda p, c: p - c * np.floor(p / c + 0.5), "the cells are right" + zero_axes + "."),
        (lambda p, c: p - c * np.round(p / c), "the cells are right" + zero_axes + "."),
    ]
    return compare("op_repeat", student, S.op_repeat, cases, mistakes)


def _limited_cases(rng):
    """Points (a sixth of them with a coordinate exactly 0, like a query on the floor y = 0),
    periods with a 0 on one axis in half the cases, and whole counts from 0 to 3."""
    cases = []
    for j in range(CASES):
        period = rng.uniform(0.5, 2.0, 3)
        if j >= CASES // 2:
            period[j % 3] = 0.0
        p = random_points(rng, 4.0)
        p[::6, j % 3] = 0.0
        cases.append((p, period, rng.integers(0, 4, 3).astype(float)))
    return cases


def op_repeat_limited(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, period, count)`` -> (N, 3): `op_repeat` with copies only in the cells
    -count..count (count : (3,) whole numbers) of each axis; period 0 leaves an axis alone.

    Points beyond the last copy must be measured from it. Half the points lie beyond it, a
    sixth have a coordinate exactly 0 (on an axis whose period may be 0: 0 / 0 is nan).
    """
    safe = lambda c: np.where(c > 0, c, 1)
    cell = lambda p, c: np.floor(p / safe(c) + 0.5)
    fold = lambda p, c, index: p - np.where(c > 0, c * index, 0)

    def divides_by_zero(p, c, n):
        with np.errstate(divide="ignore", invalid="ignore"):
            return p - c * np.clip(np.floor(p / c + 0.5), -n, n)
    mistakes = [
        (lambda p, c, n: S.op_repeat(p, c), "these are infinitely many copies: clamp the cell "
         "index to −count..count, so that the points beyond the last copy fold into it."),
        (lambda p, c, n: np.where(np.abs(cell(p, c)) > n, p, S.op_repeat(p, c)), "beyond the "
         "last copy the point is measured from the original at the origin; measure it from the "
         "nearest copy, the last one: clamp the cell index to −count..count."),
        (lambda p, c, n: fold(p, c, np.clip(cell(p, c), 0, n)), "the copies go both ways: "
         "cells −count..count, so clamp the index to [−count, count], not [0, count]."),
        (lambda p, c, n: fold(p, c, np.minimum(np.abs(cell(p, c)), n)), "the sign of the cell "
         "index is lost (abs): on the negative side the point folds into the wrong copy; clamp "
         "the signed index with np.clip(index, −count, count)."),
        (lambda p, c, n: np.where(c > 0, S.op_repeat(np.clip(p, -c * (n + 0.5),
                                                             c * (n + 0.5)), c), p),
         "clamping the point puts every point beyond the last copy on the border of its cell, "
         "at the same distance whatever its real one; clamp the cell index instead."),
        (divides_by_zero, "an axis whose period is 0 is not repeated: leave that coordinate as "
         "it is, np.where(period > 0, ..., p); p / 0 is nan where the coordinate is 0."),
    ]
    cases = _limited_cases(np.random.default_rng(seed))
    return compare("op_repeat_limited", student, S.op_repeat_limited, cases, mistakes)
