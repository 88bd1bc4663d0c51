"""How a graphics check judges a student's function; shared by every graphics check.

Each check has the name of the marchlab function it stands for (``sdf_torus`` checks a
student's ``sdf_torus`` against `reference_cpu.sdf.sdf_torus`). It calls both functions on
the same seeded random inputs, shaped as the reference function's docstring says, and prints
one paragraph: "passed" with the number of samples and the largest difference, or "not yet"
with the first input where the two disagree, the expected and the returned value, and the
likely cause when the answer matches a known mistake (a squared distance, a flipped sign...).

A check never raises because of the student's function: a wrong answer, a wrong shape or an
exception (say, the ``raise NotImplementedError`` of an exercise template) is reported, and
the check returns a `~marchlab.check.result.CheckResult`, which is true only when the function
passed.

The topic modules (`marchlab.check.sdf`, `marchlab.check.operators`, `marchlab.check.shading`,
`marchlab.check.marching`, `marchlab.check.shadows`, `marchlab.check.glass`) only say what to
try: the inputs of each exercise and its known mistakes. They hand them to `compare` here,
which runs both functions and writes the verdict. What several topics share is public:
`compare`, the sizes `CASES` and `SAMPLES`, the random inputs `random_points` and
`unit_vectors`, and the scene shadow rays are checked in, `sample_scene_sdf`. Names with a
leading underscore are the verdict's own machinery, used only here.
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
import math
import os
import textwrap
import traceback

import numpy as np

from reference_cpu import shading as SH
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.geometry import normalize
from scene_model.shapes import Box, Plane, Sphere, Translate

from .result import CheckResult

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


def compare(name, student, reference, cases, mistakes=(), distance=False) -> CheckResult:
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


# --- Inputs that several topics use ------------------------------------------------------------

def random_points(rng, size, n=SAMPLES):
    """(n, 3) points: half near a shape of the given size, half farther out."""
    spread = np.where(np.arange(n) % 2 == 0, 1.2, 3.0)[:, None] * size
    return rng.uniform(-1, 1, (n, 3)) * spread


def unit_vectors(rng, n=SAMPLES):
    """(n, 3) random unit vectors, uniform over the directions."""
    return normalize(rng.normal(size=(n, 3)))


def sample_scene_sdf():
    """The SDF of a small scene: the floor y = 0, a sphere hanging over it, a box standing on it."""
    return build_scene_sdf([Plane(), Translate(Sphere(0.6), (0.0, 1.2, 0.0)),
                            Translate(Box((0.4, 0.4, 0.4)), (1.5, 0.4, 0.5))])
