"""Self-checks for the graphics exercises: SDFs, CSG operators, lighting terms, marching, shadows.

Each check has the name of the marchlab function it stands for (``sdf_torus`` checks a
student's ``sdf_torus`` against `reference_cpu.sdf.sdf_torus`). It calls both functions on
the same seeded random inputs, shaped as the reference function's docstring says, and prints
one paragraph: "passed" with the number of samples and the largest difference, or "not yet"
with the first input where the two disagree, the expected and the returned value, and the
likely cause when the answer matches a known mistake (a squared distance, a flipped sign...).

A check never raises because of the student's function: a wrong answer, a wrong shape or an
exception (say, the ``raise NotImplementedError`` of an exercise template) is reported, and
the check returns a `CheckResult`, which is true only when the function passed.
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
import math
import os
import textwrap
import traceback
from typing import Callable

import numpy as np

from marchlab.geometry import dot, normalize, rotation_matrix
from marchlab.shapes import Box, Plane, Sphere, Translate
from reference_cpu import march as M
from reference_cpu import sdf as S
from reference_cpu import shading as SH
from reference_cpu import shadows as SW
from reference_cpu.lights import attenuation as _attenuation
from reference_cpu.scene_sdf import build_scene_sdf

from .result import CheckResult

__all__ = ["CheckResult", "TOLERANCE",
           "sdf_sphere", "sdf_box", "sdf_round_box", "sdf_plane", "sdf_torus",
           "sdf_capped_cylinder", "sdf_capsule", "sdf_cone",
           "op_union", "op_intersection", "op_subtraction", "op_smooth_union",
           "op_smooth_intersection", "op_smooth_subtraction", "smooth_union",
           "op_translate", "op_rotate", "op_scale", "op_repeat",
           "reflect", "diffuse", "specular_phong", "specular_blinn_phong", "phong",
           "blinn_phong", "shade_phong", "shade_blinn_phong", "attenuation",
           "march", "hard_shadow", "soft_shadow"]

TOLERANCE = 1e-9     # a value passes when |got - expected| <= TOLERANCE * (1 + |expected|)
CASES, SAMPLES = 8, 128     # parameter sets per check, random samples per parameter set


def _verdict(name, passed, text, samples=0, max_error=math.nan) -> CheckResult:
    head = f"{name}: passed. " if passed else f"{name}: not yet. "
    message = textwrap.fill(head + text[:1].upper() + text[1:], width=96)
    print(message)
    return CheckResult(name, passed, message, samples, max_error)


# --- Calling the student's function -----------------------------------------------------------

_SKIP_DIRS = (os.path.dirname(np.__file__), os.path.dirname(__file__))


def _call(fn, args):
    """``(result, None)`` or ``(None, what went wrong)``: the student's exception, reported."""
    try:
        return fn(*args), None
    except NotImplementedError as err:
        detail = f" ({err})" if str(err) else ""
        return None, (f"your function still raises NotImplementedError{detail}: replace the "
                      "`raise` line with your own code and run the cell again.")
    except Exception as err:       # any mistake in the student's code becomes the verdict
        return None, f"your function raised {type(err).__name__}: {err}{_where(err)}."


def _where(err) -> str:
    """' (line n: `code`)' for the innermost frame of the student's own code, if known."""
    frames = [f for f in traceback.extract_tb(err.__traceback__)[1:]
              if not f.filename.startswith(_SKIP_DIRS)]
    if not frames:
        return ""
    line = (frames[-1].line or "").strip()
    return f" (line {frames[-1].lineno}" + (f": `{line}`)" if line else ")")


def _same(a, b) -> bool:
    """Whether two inputs are equal, arrays element by element (to detect in-place changes)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and np.array_equal(a, b, equal_nan=True)
    if dataclasses.is_dataclass(a):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a is b or a == b


# --- Describing inputs and outputs --------------------------------------------------------------

def _fmt(x) -> str:
    """A number or a small vector, to 4 significant digits."""
    x = np.asarray(x)
    if x.ndim == 0:
        return f"{float(x):.4g}" if x.dtype.kind in "fiu" else str(x)
    return "(" + ", ".join(_fmt(v) for v in x) + ")"


def _describe(names, args, i, n) -> str:
    """The inputs of sample i: per-sample arrays (first axis n) by row, parameters whole."""
    parts = []
    for name, value in zip(names, args):
        if callable(value):
            parts.append(f"{name} = the test scene's SDF")
        elif isinstance(value, SH.Surface):
            fields = ("position", "normal", "view", "albedo", "ka", "kd", "ks", "shininess")
            parts.append(f"{name} = Surface(" + ", ".join(
                f"{f}={_fmt(getattr(value, f)[i])}" for f in fields) + ")")
        elif isinstance(value, list):
            parts.append(f"{name} = [" + ", ".join(
                f"(L={_fmt(l[i])}, radiance={_fmt(r[i])})" for l, r in value) + "]")
        elif isinstance(value, np.ndarray) and value.ndim >= 1 and value.shape[0] == n:
            parts.append(f"{name} = {_fmt(value[i])}")
        else:
            parts.append(f"{name} = {_fmt(value)}")
    return ", ".join(parts)


def _as_array(got, expected) -> tuple[np.ndarray | None, str | None]:
    """The student's result as a float array of the expected shape, or why it is not one."""
    if got is None:
        return None, "your function returned None: did you forget the `return` statement?"
    try:
        array = np.asarray(got, dtype=np.float64)
    except (TypeError, ValueError):
        return None, f"your function returned a {type(got).__name__}, not an array of numbers."
    want = expected.shape
    if array.shape == want:
        return array, None
    if array.ndim == 0 and len(want) >= 1:
        hint = ("one number for all the points: an operation summed or reduced the whole "
                "array; reduce along the last axis only (axis=-1)")
    elif array.shape == want + (3,):
        hint = ("one value per coordinate instead of one per point: take the length or dot "
                "product along the last axis (axis=-1)")
    elif array.shape == want + (1,):
        hint = "an extra axis of length 1 (keepdims=True, or [:, None] too many)"
    elif len(want) == 2 and array.shape == want[:1]:
        hint = "one value per point where a vector per point was expected"
    else:
        hint = "check which axis your sums, lengths and maxima run over"
    return None, f"your function returned shape {array.shape}, expected {want}: {hint}."


# --- Comparing arrays ----------------------------------------------------------------------

def _errors(got, expected):
    """Relative-absolute error per element; nan (never passing) where exactly one is nan."""
    with np.errstate(invalid="ignore"):
        err = np.abs(got - expected) / (1 + np.abs(expected))
    both_nan = np.isnan(got) & np.isnan(expected)
    same_inf = np.isinf(got) & (got == expected)
    return np.where(both_nan | same_inf, 0.0, err)


def _bad(err):
    """Per sample (first axis): does any element fail? nan counts as failing."""
    bad = ~(err <= TOLERANCE)
    return bad.reshape(len(bad), -1).any(axis=1) if bad.ndim > 1 else bad


def _compare(name, student, reference, cases, mistakes=(), distance=False) -> CheckResult:
    """Run ``student`` and ``reference`` on every case (a tuple of arguments) and judge.

    ``mistakes`` are ``(function, hint)`` pairs: wrong versions a student might write, with
    the reference's signature; if the student's results match one of them everywhere, its
    hint is the likely cause. ``distance`` marks an SDF, whose sign means inside/outside.
    """
    names = list(inspect.signature(reference).parameters)
    results = []                                      # (case, expected, got)
    for case in cases:
        expected = np.asarray(reference(*copy.deepcopy(case)), dtype=np.float64)
        args = copy.deepcopy(case)
        got, problem = _call(student, args)
        if problem is None:
            changed = [n for n, a, b in zip(names, case, args) if not _same(a, b)]
            if changed:
                problem = (f"your function changed its input `{changed[0]}` in place (with "
                           "`-=`, `+=` or an assignment into it); compute a new array instead, "
                           "the caller still needs the original.")
        if problem is None:
            got, problem = _as_array(got, expected)
        if problem is not None:
            if "NotImplementedError" not in problem:
                problem += f" First input tried: {_describe(names, case, 0, len(expected))}."
            return _verdict(name, False, problem)
        results.append((case, expected, got))

    errors = [_errors(got, expected) for _, expected, got in results]
    samples = sum(len(e) for _, e, _ in results)
    finite = [e[np.isfinite(e)] for e in errors]
    max_error = max((float(f.max()) for f in finite if f.size), default=math.nan)
    bad = [_bad(e) for e in errors]
    wrong = int(sum(b.sum() for b in bad))
    if wrong == 0:
        return _verdict(name, True, f"Your function agrees with marchlab's on {samples} random "
                        f"samples ({len(cases)} parameter sets, seeded); largest error "
                        f"{max_error:.2g}, tolerance {TOLERANCE:g}·(1 + |expected|).",
                        samples, max_error)

    k = next(j for j, b in enumerate(bad) if b.any())
    case, expected, got = results[k]
    i = int(np.argmax(bad[k]))
    where = (f"For {_describe(names, case, i, len(expected))} marchlab gives "
             f"{_fmt(expected[i])} but your function returned {_fmt(got[i])} (wrong at "
             f"{wrong} of {samples} samples; tolerance {TOLERANCE:g}·(1 + |expected|)).")
    cause = _known_mistake(results, mistakes) or _diagnose(results, bad, distance)
    return _verdict(name, False, where + (f" Likely cause: {cause}" if cause else ""),
                    samples, max_error)


def _known_mistake(results, mistakes) -> str | None:
    """The hint of the first mistake that reproduces the student's results everywhere."""
    for wrong, hint in mistakes:
        with np.errstate(all="ignore"):
            if all(not _bad(_errors(got, np.asarray(wrong(*copy.deepcopy(case)), float))).any()
                   for case, _, got in results):
                return hint
    return None


def _diagnose(results, bad, distance) -> str | None:
    """A guess from the pattern of the differences, when no known mistake matched."""
    e = np.concatenate([r[1].ravel() for r in results])
    g = np.concatenate([r[2].ravel() for r in results])
    rows = np.concatenate(bad)
    if np.isnan(g).any() and not np.isnan(e[np.isnan(g)]).all():
        return ("your function returns nan where marchlab's value is a number: a square root "
                "of a negative number, 0/0, or a negative number raised to a fractional power.")
    ok = np.isfinite(e) & np.isfinite(g)
    e, g = e[ok], g[ok]
    close = lambda a, b: bool(np.all(np.abs(a - b) <= 1e-6 * (1 + np.abs(b))))
    if close(g, -e):
        return ("the sign is flipped everywhere"
                + (": a distance is negative inside the shape and positive outside." if distance
                   else "."))
    if close(g, e * e) or close(g, np.sign(e) * e * e):
        return "you returned the square of the value: is a square root (a length) missing?"
    diff = g - e
    if np.ptp(diff) <= 1e-6 * (1 + np.abs(e).max()):
        return f"your values are off by the same constant {diff.mean():.4g} everywhere."
    big = np.abs(e) > 1e-3
    if big.sum() > 3:
        ratio = g[big] / e[big]
        if np.ptp(ratio) <= 1e-6 * np.abs(ratio).max():
            return f"your values are {ratio.mean():.4g} times marchlab's everywhere: a factor."
    if distance:
        rows_e = np.concatenate([r[1] for r in results])
        if not (rows & (rows_e > 0)).any():
            return ("right outside the shape but wrong inside it (where the distance is "
                    "negative): look at the part of the formula that applies inside.")
        if not (rows & (rows_e < 0)).any():
            return ("right inside the shape but wrong outside it: look at the part of the "
                    "formula that applies outside.")
        if np.all(g[np.abs(g - e) > 1e-9] > e[np.abs(g - e) > 1e-9]):
            return ("your values are larger than the true distance where they differ: a sphere "
                    "tracer trusting them would step through the surface.")
    return None


# --- Random inputs ---------------------------------------------------------------------------

def _points(rng, size, n=SAMPLES):
    """(n, 3) points: half near a shape of the given size, half farther out."""
    spread = np.where(np.arange(n) % 2 == 0, 1.2, 3.0)[:, None] * size
    return rng.uniform(-1, 1, (n, 3)) * spread


def _units(rng, n=SAMPLES):
    return normalize(rng.normal(size=(n, 3)))


def _distances(rng, n=SAMPLES):
    """Two (n,) arrays of signed distances; a third of the pairs are close (inside a blend)."""
    d1 = rng.uniform(-2, 2, n)
    d2 = np.where(np.arange(n) % 3 == 0, d1 + rng.uniform(-0.3, 0.3, n), rng.uniform(-2, 2, n))
    return d1, d2


# --- Primitives ----------------------------------------------------------------------------

def sdf_sphere(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, radius)`` (p : (N, 3)) -> (N,) against `reference_cpu.sdf.sdf_sphere`."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        r = rng.uniform(0.3, 1.5)
        cases.append((_points(rng, r), r))
    mistakes = [
        (lambda p, r: dot(p, p) - r * r, "you returned |p|² − r², a squared quantity; the "
         "distance is |p| − r (the square root of p·p, minus the radius)."),
        (lambda p, r: dot(p, p) - r, "you used the squared length p·p: take its square root."),
        (lambda p, r: S.length(p), "the radius is missing: subtract it from |p|."),
        (lambda p, r: S.length(p) + r, "the radius must be subtracted, not added."),
    ]
    return _compare("sdf_sphere", student, S.sdf_sphere, cases, mistakes, distance=True)


def sdf_box(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, half_size)`` (p : (N, 3), half_size : (3,)) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        b = rng.uniform(0.2, 1.5, 3)
        cases.append((_points(rng, b.max()), b))
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
    return _compare("sdf_box", student, S.sdf_box, cases, mistakes, distance=True)


def sdf_round_box(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, half_size, radius)`` -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        b = rng.uniform(0.4, 1.5, 3)
        cases.append((_points(rng, b.max()), b, rng.uniform(0.05, 0.35)))
    mistakes = [(lambda p, b, r: S.sdf_box(p, b) - r, "the box must first be shrunk by the "
                 "radius (half_size − radius), or the rounding makes it grow beyond half_size.")]
    return _compare("sdf_round_box", student, S.sdf_round_box, cases, mistakes, distance=True)


def sdf_plane(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, normal, offset)`` (normal : (3,), not unit length) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 2.0), rng.normal(size=3) * rng.uniform(0.5, 3), rng.uniform(-1, 1))
             for _ in range(CASES)]
    mistakes = [
        (lambda p, n, h: dot(p, n) - h, "the normal is not unit length: divide it by its "
         "length before the dot product."),
        (lambda p, n, h: dot(p, n / np.sqrt(dot(n, n))) + h, "the offset is subtracted: the "
         "plane is the set of points with n·x = offset."),
    ]
    return _compare("sdf_plane", student, S.sdf_plane, cases, mistakes, distance=True)


def sdf_torus(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, major_radius, minor_radius)`` (torus in the xz-plane) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        big = rng.uniform(0.6, 1.5)
        cases.append((_points(rng, big + 0.3), big, rng.uniform(0.1, 0.5) * big))
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
    return _compare("sdf_torus", student, S.sdf_torus, cases, mistakes, distance=True)


def sdf_capped_cylinder(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, radius, half_height)`` (cylinder along y) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 1.0), rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0))
             for _ in range(CASES)]
    mistakes = [(lambda p, r, h: S.length2(p[:, 0], p[:, 2]) - r, "that is an infinite "
                 "cylinder: the caps at y = ±half_height are missing.")]
    return _compare("sdf_capped_cylinder", student, S.sdf_capped_cylinder, cases, mistakes,
                    distance=True)


def sdf_capsule(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, a, b, radius)`` (a, b : (3,) the segment's ends) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 1.0), rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3),
              rng.uniform(0.1, 0.5)) for _ in range(CASES)]

    def unclamped(p, a, b, r):
        h = dot(p - a, b - a) / dot(b - a, b - a)
        return S.length(p - a - h[:, None] * (b - a)) - r
    mistakes = [(unclamped, "the projection h is not clamped to [0, 1]: that is the distance "
                 "to the infinite line through a and b, not to the segment.")]
    return _compare("sdf_capsule", student, S.sdf_capsule, cases, mistakes, distance=True)


def sdf_cone(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, radius, height)`` (base at y = 0, apex at y = height) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 1.0) + [0, 0.5, 0], rng.uniform(0.2, 1.0), rng.uniform(0.3, 1.5))
             for _ in range(CASES)]
    return _compare("sdf_cone", student, S.sdf_cone, cases, distance=True)


# --- CSG operators ---------------------------------------------------------------------------

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
    return _compare("op_union", student, S.op_union, _pairs(seed, False), mistakes, True)


def op_intersection(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2)`` -> (N,)."""
    mistakes = [(lambda a, b: np.minimum(a, b), "that is the union: an intersection keeps the "
                 "farther surface, max(d1, d2).")]
    return _compare("op_intersection", student, S.op_intersection, _pairs(seed, False),
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
    ]
    return _compare("op_subtraction", student, S.op_subtraction, _pairs(seed, False),
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
    return _compare("op_smooth_union", student, S.op_smooth_union, _pairs(seed, True),
                    mistakes, True)


smooth_union = op_smooth_union


def op_smooth_intersection(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2, k)`` -> (N,)."""
    return _compare("op_smooth_intersection", student, S.op_smooth_intersection,
                    _pairs(seed, True),
                    _smooth_mistakes(S.op_smooth_intersection, S.op_intersection,
                                     lambda a, b: a), True)


def op_smooth_subtraction(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d1, d2, k)`` (shape 1 minus shape 2, rounded) -> (N,)."""
    return _compare("op_smooth_subtraction", student, S.op_smooth_subtraction,
                    _pairs(seed, True),
                    _smooth_mistakes(S.op_smooth_subtraction, S.op_subtraction,
                                     lambda a, b: -b), True)


# --- Transforms (they move the query point) ----------------------------------------------------

def op_translate(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, offset)`` -> (N, 3), the query point of a moved shape."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 2.0), rng.uniform(-2, 2, 3)) for _ in range(CASES)]
    mistakes = [(lambda p, o: p + o, "a transform moves the query point the opposite way: "
                 "to move the shape by offset, evaluate it at p − offset.")]
    return _compare("op_translate", student, S.op_translate, cases, mistakes)


def op_rotate(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, matrix)`` (matrix : (3, 3) rotation R) -> (N, 3), R^T p per point."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 2.0), rotation_matrix(rng.uniform(-180, 180, 3)))
             for _ in range(CASES)]
    mistakes = [(lambda p, m: p @ m.T, "you rotated the point by R; the query point turns the "
                 "other way, by R⁻¹ = Rᵀ (p @ R in NumPy's row-vector form).")]
    return _compare("op_rotate", student, S.op_rotate, cases, mistakes)


def op_scale(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, factor)`` -> (N, 3), the query point of a shape scaled by factor."""
    rng = np.random.default_rng(seed)
    cases = [(_points(rng, 2.0), rng.uniform(0.3, 3.0)) for _ in range(CASES)]
    mistakes = [(lambda p, s: p * s, "to make the shape s times larger, shrink the query "
                 "point: p / s (and multiply the distance back by s afterwards).")]
    return _compare("op_scale", student, S.op_scale, cases, mistakes)


def op_repeat(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(p, period)`` (period : (3,), 0 = no repetition on that axis) -> (N, 3)."""
    rng = np.random.default_rng(seed)
    cases = []
    for j in range(CASES):
        period = rng.uniform(0.5, 2.0, 3)
        period[j % 3] = 0.0 if j >= 4 else period[j % 3]     # half the cases leave an axis alone
        cases.append((_points(rng, 4.0), period))
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
    return _compare("op_repeat", student, S.op_repeat, cases, mistakes)


# --- Lighting ----------------------------------------------------------------------------------

def _lighting_vectors(rng, n=SAMPLES):
    """Unit n, l, v with v near the mirror direction of the light half the time."""
    normal, to_light = _units(rng, n), _units(rng, n)
    mirror = SH.reflect(-to_light, normal)
    near = normalize(mirror + 0.3 * rng.normal(size=(n, 3)))
    view = np.where((np.arange(n) % 2 == 0)[:, None], near, _units(rng, n))
    return normal, to_light, view


def reflect(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d, n)`` (d, n : (N, 3), n unit) -> (N, 3), the mirror direction."""
    rng = np.random.default_rng(seed)
    cases = [(_units(rng) * rng.uniform(0.5, 2), _units(rng)) for _ in range(CASES)]
    mistakes = [
        (lambda d, n: d + 2 * dot(d, n)[:, None] * n, "the sign: subtract 2(d·n)n."),
        (lambda d, n: d - dot(d, n)[:, None] * n, "the factor 2 is missing: d − (d·n)n only "
         "removes the normal part (a projection onto the surface), it does not mirror it."),
        (lambda d, n: 2 * dot(d, n)[:, None] * n - d, "that is −reflect(d, n): the result "
         "points back the way it came."),
    ]
    return _compare("reflect", student, SH.reflect, cases, mistakes)


def diffuse(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(n, l)`` (unit (N, 3)) -> (N,), Lambert's max(N·L, 0)."""
    rng = np.random.default_rng(seed)
    cases = [(_units(rng), _units(rng)) for _ in range(CASES)]
    mistakes = [(lambda n, l: dot(n, l), "not clamped: where the light is behind the surface "
                 "N·L < 0, and light cannot be negative; use max(N·L, 0)."),
                (lambda n, l: np.abs(dot(n, l)), "abs(N·L) lights the back of the surface "
                 "too; use max(N·L, 0).")]
    return _compare("diffuse", student, SH.diffuse, cases, mistakes)


def _specular_cases(seed):
    rng = np.random.default_rng(seed)
    return [(*_lighting_vectors(rng), rng.uniform(1, 64, SAMPLES)) for _ in range(CASES)]


def _specular_mistakes(model):
    phong_cos = lambda n, l, v: dot(SH.reflect(-l, n), v)
    blinn_cos = lambda n, l, v: dot(n, normalize(l + v))
    cosine, other = (phong_cos, blinn_cos) if model == "phong" else (blinn_cos, phong_cos)
    lobe = lambda n, l, v, a: np.maximum(cosine(n, l, v), 0) ** a
    mask = lambda f: (lambda n, l, v, a: np.where(dot(n, l) > 0, f(n, l, v, a), 0))
    mistakes = [
        (lobe, "no highlight may appear where the light is behind the surface: return 0 where "
         "N·L <= 0."),
        (mask(lambda n, l, v, a: cosine(n, l, v) ** a), "clamp the cosine with "
         "max(·, 0) before raising it to the power: a negative number to a fractional power "
         "is nan."),
        (mask(lambda n, l, v, a: np.maximum(other(n, l, v), 0) ** a), "that is the "
         + ("Blinn-Phong half-vector" if model == "phong" else "Phong mirror-vector")
         + " highlight."),
    ]
    if model == "phong":
        mistakes.append((mask(lambda n, l, v, a: np.maximum(dot(SH.reflect(l, n), v), 0) ** a),
                         "R = reflect(−L, N): L points toward the light, so the light travels "
                         "along −L; reflect(L, N) points into the surface."))
    else:
        mistakes.append((mask(lambda n, l, v, a: np.maximum(dot(n, l + v), 0) ** a),
                         "H = normalize(L + V): without normalising, N·H is not a cosine."))
    return mistakes


def specular_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(n, l, v, shininess)`` (unit (N, 3); shininess (N,)) -> (N,)."""
    return _compare("specular_phong", student, SH.specular_phong, _specular_cases(seed),
                    _specular_mistakes("phong"))


def specular_blinn_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(n, l, v, shininess)`` -> (N,), max(N·H, 0)^shininess."""
    return _compare("specular_blinn_phong", student, SH.specular_blinn_phong,
                    _specular_cases(seed), _specular_mistakes("blinn"))


phong = specular_phong
blinn_phong = specular_blinn_phong


def _surfaces(seed):
    """Cases (surface, incoming, ambient) with one to three lights."""
    rng = np.random.default_rng(seed)
    cases = []
    for j in range(CASES):
        normal, _, view = _lighting_vectors(rng)
        u = lambda: rng.uniform(0, 1, SAMPLES)
        s = SH.Surface(position=_points(rng, 2.0), normal=normal, view=view,
                       albedo=rng.uniform(0, 1, (SAMPLES, 3)), ka=u(), kd=u(), ks=u(),
                       shininess=rng.uniform(1, 64, SAMPLES))
        incoming = []
        for _ in range(1 + j % 3):
            to_light = normalize(normal + rng.normal(size=(SAMPLES, 3)))
            incoming.append((to_light, rng.uniform(0, 1.5, (SAMPLES, 3))))
        cases.append((s, incoming, rng.uniform(0, 1, 3)))
    return cases


def _shade_mistakes(specular):
    def lit(s, incoming, ambient, tint=False, with_ambient=True, albedo_ambient=True,
            with_radiance=True):
        color = s.ka[:, None] * (s.albedo if albedo_ambient else 1) * ambient * with_ambient
        for l, radiance in incoming:
            sp = (s.ks * specular(s.normal, l, s.view, s.shininess))[:, None]
            term = s.kd[:, None] * SH.diffuse(s.normal, l)[:, None] * s.albedo + \
                sp * (s.albedo if tint else 1)
            color = color + (radiance if with_radiance else 1) * term
        return color
    return [
        (lambda *a: lit(*a, tint=True), "the specular term is multiplied by the albedo; "
         "in this model the highlight has the light's colour, not the surface's."),
        (lambda *a: lit(*a, with_ambient=False), "the ambient term ka·albedo·i_a is missing."),
        (lambda *a: lit(*a, albedo_ambient=False), "the ambient term is ka·albedo·i_a: the "
         "albedo is missing from it."),
        (lambda *a: lit(*a, with_radiance=False), "each light's diffuse and specular terms "
         "must be multiplied by its radiance (colour, intensity, attenuation, shadow)."),
    ]


def shade_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(surface, incoming, ambient)`` -> (N, 3).

    ``surface`` is a `reference_cpu.shading.Surface`, ``incoming`` a list of
    ``(to_light (N, 3), radiance (N, 3))`` pairs, one per light, ``ambient`` (3,).
    """
    return _compare("shade_phong", student, SH.shade_phong, _surfaces(seed),
                    _shade_mistakes(SH.specular_phong))


def shade_blinn_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(surface, incoming, ambient)`` -> (N, 3), with the Blinn highlight."""
    return _compare("shade_blinn_phong", student, SH.shade_blinn_phong, _surfaces(seed),
                    _shade_mistakes(SH.specular_blinn_phong))


def attenuation(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(distance, constant, linear, quadratic)`` (distance (N,)) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(rng.uniform(0, 20, SAMPLES), *rng.uniform(0.2, 1, 1), *rng.uniform(0, 0.3, 2))
             for _ in range(CASES)]
    mistakes = [(lambda d, c, l, q: c + l * d + q * d * d, "attenuation divides: "
                 "1 / (constant + linear·d + quadratic·d²).")]
    return _compare("attenuation", student, _attenuation, cases, mistakes)


# --- Marching and shadows ----------------------------------------------------------------------

def _test_scene_sdf():
    """The floor y = 0, a sphere hanging over it and a box standing on it."""
    return build_scene_sdf([Plane(), Translate(Sphere(0.6), (0.0, 1.2, 0.0)),
                            Translate(Box((0.4, 0.4, 0.4)), (1.5, 0.4, 0.5))])


def march(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(origins, directions, sdf, max_steps, epsilon, max_distance)``.

    It must return ``(t, steps, hit)`` as `reference_cpu.march.march` does: t (N,) (inf on a
    miss), steps (N,) int, hit (N,) bool. ``sdf(p)`` returns a tuple whose first item is the
    distance (N,). Rays and hits must agree exactly; t within the tolerance.
    """
    rng = np.random.default_rng(seed)
    sdf = _test_scene_sdf()
    eye = np.array([0.0, 1.5, 6.0])
    targets = rng.uniform([-3, -0.5, -3], [3, 3, 3], (2 * SAMPLES, 3))
    toward = normalize(targets - eye)
    inside = np.array([0.0, 1.2, 0.0]) + 0.3 * _units(rng, SAMPLES)     # inside the sphere
    cases = [("rays from a camera", (eye, toward, sdf, 128, 1e-3, 40.0)),
             ("rays starting inside the sphere", (inside, _units(rng), sdf, 128, 1e-3, 40.0)),
             ("a low max_steps of 6", (eye, toward, sdf, 6, 1e-3, 40.0)),
             ("a short max_distance of 6", (eye, toward, sdf, 128, 1e-3, 6.0))]
    samples, max_error = 0, 0.0
    for label, case in cases:
        t, steps, hit = M.march(*copy.deepcopy(case))
        got, problem = _call(student, copy.deepcopy(case))
        n = len(t)
        if problem is None:
            got, problem = _march_result(got, n)
        if problem is not None:
            where = "" if "NotImplementedError" in problem else f" (Test: {label}.)"
            return _verdict("march", False, problem + where)
        g_t, g_steps, g_hit = got
        samples += n
        wrong_hit, wrong_steps = g_hit != hit, g_steps != steps
        errors = _errors(g_t, t)
        max_error = max(max_error, float(np.max(errors, initial=0.0, where=np.isfinite(errors))))
        bad = wrong_hit | wrong_steps | _bad(errors)
        if not bad.any():
            continue
        i = int(np.argmax(bad))
        ray = f"the ray from {_fmt(np.broadcast_to(case[0], (n, 3))[i])} along {_fmt(case[1][i])}"
        where = (f"With {label}, {ray} should give hit={bool(hit[i])}, steps={steps[i]}, "
                 f"t={_fmt(t[i])}; yours gave hit={bool(g_hit[i])}, steps={g_steps[i]}, "
                 f"t={_fmt(g_t[i])} ({int(bad.sum())} of {n} rays differ).")
        cause = _march_cause(label, t, steps, hit, g_t, g_steps, g_hit)
        return _verdict("march", False, where + (f" Likely cause: {cause}" if cause else ""),
                        samples, max_error)
    tests = ", ".join(label for label, _ in cases)
    return _verdict("march", True, f"Your t, steps and hit agree with marchlab's march on "
                    f"{samples} rays ({len(cases)} tests: {tests}); t within "
                    f"{TOLERANCE:g}·(1 + t).", samples, max_error)


def _march_result(got, n):
    """The student's (t, steps, hit) as arrays of length n, or why they are not."""
    if not isinstance(got, (tuple, list)) or len(got) != 3:
        return None, ("your march must return three arrays (t, steps, hit); it returned "
                      f"{type(got).__name__}" + (f" of length {len(got)}" if
                                                  isinstance(got, (tuple, list)) else "") + ".")
    arrays = []
    for name, value, dtype in zip(("t", "steps", "hit"), got, (np.float64, np.int64, bool)):
        try:
            a = np.asarray(value).astype(dtype)
        except (TypeError, ValueError):
            return None, f"`{name}` is not an array of numbers."
        if a.shape != (n,):
            return None, f"`{name}` has shape {a.shape}; expected ({n},), one value per ray."
        arrays.append(a)
    return arrays, None


def _march_cause(label, t, steps, hit, g_t, g_steps, g_hit) -> str | None:
    """A guess at what is wrong with a student's march, from how its results differ."""
    if np.isfinite(g_t[~g_hit]).any():
        return "a ray that misses must have t = inf (np.inf), whatever distance it reached."
    if label.startswith("rays starting inside") and (g_hit & (g_steps == 1) & (steps > 1)).any():
        return ("inside a solid the SDF is negative, which is already < epsilon: compare and "
                "step with |sdf|, the absolute value.")
    same_hits = np.array_equal(hit, g_hit)
    if same_hits and np.all(g_steps - steps == g_steps[0] - steps[0]):
        return (f"your step counts are off by {int(g_steps[0] - steps[0]):+d} on every ray: "
                "steps counts SDF evaluations, the one that found the hit included.")
    if label.startswith("a short") and (g_hit & ~hit).any():
        return ("a ray misses as soon as t > max_distance: check t after each step, before "
                "the next evaluation.")
    if label.startswith("a low") and (g_hit != hit).any():
        return "after max_steps evaluations without a hit the ray misses; count them from 1."
    if same_hits and np.array_equal(g_steps, steps):
        return ("t is wrong where the rays hit: it should be the distance travelled when "
                "|sdf| first dropped below epsilon (before adding that last distance).")
    return None


def _shadow_cases(seed, with_k):
    """Shadow rays from floor points toward lights above, below the sphere, and at infinity."""
    rng = np.random.default_rng(seed)
    sdf = _test_scene_sdf()
    floor = np.column_stack([rng.uniform(-3, 3, SAMPLES), np.full(SAMPLES, 0.01),
                             rng.uniform(-3, 3, SAMPLES)])
    lights = [rng.uniform([-3, 3, -3], [3, 6, 3]) for _ in range(3)] + [np.array([0, 0.45, 0])]
    cases = []
    for position in lights:
        offset = position - floor
        distance = S.length(offset)
        cases.append([sdf, floor, offset / distance[:, None], distance, 128, 1e-3, 50.0])
    sun = normalize(np.array([0.3, 1.0, 0.2]))
    cases.append([sdf, floor, np.tile(sun, (SAMPLES, 1)), np.full(SAMPLES, np.inf), 128, 1e-3,
                  50.0])
    for case in cases:
        if with_k:
            case.append(float(rng.uniform(2, 32)))
    return [tuple(c) for c in cases]


def hard_shadow(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(sdf, origins, to_light, light_distance, max_steps, epsilon,
    max_distance)`` -> (N,): 1 where the light is visible, 0 where the shadow ray hits."""
    ignore_light = lambda sdf, o, l, dist, *rest: SW.hard_shadow(sdf, o, l, np.inf, *rest)
    mistakes = [
        (ignore_light, "a shadow ray must stop at the light: march no farther than "
         "min(light_distance, max_distance), or objects behind the light cast shadows."),
        (lambda *a: 1 - SW.hard_shadow(*a), "1 means the light is visible, 0 that it is "
         "blocked: your values are the other way round."),
    ]
    return _compare("hard_shadow", student, SW.hard_shadow, _shadow_cases(seed, False),
                    mistakes)


def soft_shadow(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(sdf, origins, to_light, light_distance, max_steps, epsilon,
    max_distance, k)`` -> (N,) in [0, 1], Quilez's penumbra estimate."""
    def penumbra(sdf, o, l, dist, steps, eps, far, k, zero_blocked=True, scale=1.0,
                 limit=True):
        visible = np.ones(len(o))

        def observe(index, t, h, step):
            if step > 1:
                visible[index] = np.minimum(visible[index], scale * k * h / t)
        lim = np.minimum(dist, far) if limit else far
        _, _, blocked = M.march(o, l, sdf, steps, eps, lim, observe=observe)
        if zero_blocked:
            visible[blocked] = 0
        return np.clip(visible, 0, 1)
    mistakes = [
        (lambda *a: penumbra(*a, zero_blocked=False), "a shadow ray that hits something sees "
         "no light: set the visibility of blocked rays to 0."),
        (lambda *a: penumbra(*a, scale=1 / a[7]), "the factor k is missing: the penumbra term "
         "is k·h/t (larger k, harder shadows)."),
        (lambda *a: penumbra(*a, limit=False), "march no farther than the light: the limit is "
         "min(light_distance, max_distance)."),
        (lambda *a: SW.hard_shadow(*a[:7]), "these are hard shadows (0 or 1): keep the "
         "smallest k·h/t seen along the ray (march's observe argument gives h and t)."),
    ]
    return _compare("soft_shadow", student, SW.soft_shadow, _shadow_cases(seed, True),
                    mistakes)
