"""Check for lesson 01's sphere tracer, ``march``: where each ray stops and after how many steps.

``march`` returns three arrays, ``(t, steps, hit)``, so its check is written out here rather
than handed to the shared comparison: it traces rays through a small test scene (a floor, a
sphere and a box) with `reference_cpu.march.march` and the student's function, and asks hits
and step counts to agree exactly and t within the tolerance of `marchlab.check.judge`. Rays
from a camera, rays starting inside a solid, a low step limit and a short maximum distance
each test one rule of the loop.
"""

from __future__ import annotations

import copy
from typing import Callable

import numpy as np

from reference_cpu import march as M
from scene_model.geometry import normalize

from .judge import SAMPLES, TOLERANCE, _bad, _call, _errors, _fmt, _test_scene_sdf, _units, _verdict
from .result import CheckResult

__all__ = ["march"]


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
