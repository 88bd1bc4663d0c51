"""How a physics check judges a student's function; shared by every physics check.

Each check takes the student's function, calls it on seeded random inputs and compares every
answer with marchlab's own (the functions of ``physics/``, or the simulator itself), then
prints one verdict: passed (how many samples, the largest error) or "not yet", with the first
input that went wrong, the expected and the received answer, and a likely cause when the
answer matches a known mistake (a flipped normal, a forgotten 1 + e, ...). A check never
raises, whatever the student's function does; it returns a `CheckResult`, which is truthy
when the check passed. Arguments are passed by position, so any parameter names will do.

The topic modules (`marchlab.check.impulses`, `marchlab.check.integration`,
`marchlab.check.invariants`) say what to try and which mistakes to recognise, as `Mistake`
records, and hand both to `verdict` here. They share the random inputs `unit_vector` and
`random_mass` and the tolerances `RTOL` and `ATOL`. Names with a leading underscore are the
verdict's own machinery, used only here.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .result import CheckResult

RTOL, ATOL = 1e-9, 1e-12          # agreement asked of float64 arithmetic: rounding only


@dataclass
class Mistake:
    """A plausible wrong answer, ``answer(sample)``, and what to tell a student who gave it."""
    answer: Callable[[dict], object]
    hint: str


def verdict(name, student, samples, expected, mistakes=(), units="", rtol=RTOL, atol=ATOL,
            note="") -> CheckResult:
    """Run ``student(*sample.values())`` on every sample, compare with ``expected``, print the
    verdict.

    samples : list of dict, the arguments of each call in order (named for the messages).
    expected : list of ndarray, marchlab's answer for each sample (its shape is the shape asked).
    """
    def finish(passed, text, max_error=float("nan")):
        message = f"{name}: {text}"
        print(message)
        return CheckResult(name, passed, message, len(samples), max_error)

    if not callable(student):
        return finish(False, "not yet: pass your function itself, e.g. "
                             f"marchlab.check.{name}(my_{name}), not "
                             f"{type(student).__name__} (a call's result?)")
    got = []
    for sample, want in zip(samples, expected):
        # The student gets copies, so a function that changes its arguments is caught below
        # and cannot spoil the samples.
        given = {k: np.copy(v) if isinstance(v, np.ndarray) else v for k, v in sample.items()}
        try:
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                answer = student(*given.values())
        except NotImplementedError:
            return finish(False, "not yet: your function raises NotImplementedError; replace "
                                 "that line with your code and run the check again")
        except Exception as err:           # the student's bug, reported, never re-raised
            return finish(False, f"not yet: your function raised {type(err).__name__}: {err}\n"
                                 f"  on input  {_describe(sample)}")
        answer, problem = _as_shape(answer, np.shape(want))
        if problem:
            return finish(False, f"not yet: {problem}\n  on input  {_describe(sample)}")
        changed = [k for k, v in given.items()
                   if isinstance(v, np.ndarray) and not np.array_equal(v, sample[k])]
        if changed:
            return finish(False, "not yet: your function changed its argument "
                                 f"{changed[0]} in place; build a new array instead "
                                 f"(e.g. x + h * v, not x += h * v)")
        got.append(answer)

    errors = [_error(g, w) for g, w in zip(got, expected)]
    max_error = float(max(errors, default=0.0))
    wrong = [i for i, (g, w) in enumerate(zip(got, expected)) if not _close(g, w, rtol, atol)]
    if not wrong:
        return finish(True, f"passed ({len(samples)} random samples, largest error "
                            f"{max_error:.2g}{units}; tolerance {rtol:g} relative){note}",
                      max_error)
    first = wrong[0]
    text = (f"not yet: wrong on {len(wrong)} of {len(samples)} samples; the first:\n"
            f"  input     {_describe(samples[first])}\n"
            f"  expected  {_show(expected[first])}{units}\n"
            f"  got       {_show(got[first])}{units}")
    cause = _likely_cause(mistakes, samples, got, wrong)
    if cause:
        text += f"\n  likely cause: {cause}"
    return finish(False, text, max_error)


def _as_shape(answer, shape):
    """The answer as a float array of ``shape``, or a message saying what was wrong with it."""
    if answer is None:
        return None, "your function returned None: did you forget the `return`?"
    try:
        array = np.asarray(answer, dtype=np.float64)
    except (TypeError, ValueError):
        return None, (f"expected {'a number' if shape == () else f'an array of shape {shape}'}, "
                      f"got {type(answer).__name__}: {answer!r}")
    if array.shape != shape:
        if shape == () and array.size == 1:
            return array.reshape(()), None
        if shape == () and array.shape == (3,):
            return None, "expected a number, got a 3-vector"
        return None, f"expected shape {shape}, got shape {array.shape}"
    return array, None


def _close(got, want, rtol, atol) -> bool:
    return bool(np.all(np.abs(got - want) <= atol + rtol * np.abs(want)))


def _error(got, want) -> float:
    difference = np.abs(got - want)
    return float(np.max(difference)) if np.all(np.isfinite(difference)) else float("inf")


def _likely_cause(mistakes, samples, got, wrong):
    """The hint of a mistake that reproduces every answer; else of one that reproduces the
    first wrong answer (a weaker claim, said so)."""
    def explains(mistake, index):
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            guess = np.asarray(mistake.answer(samples[index]), float)
        same_nan = np.isnan(guess) & np.isnan(got[index])
        return bool(np.all(same_nan | (np.abs(got[index] - guess)
                                       <= 1e-9 + 1e-6 * np.abs(guess))))
    for mistake in mistakes:
        if all(explains(mistake, i) for i in range(len(samples))):
            return mistake.hint
    for mistake in mistakes:
        if explains(mistake, wrong[0]):
            return f"(on this input) {mistake.hint}"
    if not np.all(np.isfinite(got[wrong[0]])):
        return "your answer is not finite: a division by zero, or a square root of a negative?"
    return None


def _show(value) -> str:
    """A number, or an array on one line."""
    if np.ndim(value) == 0:
        return f"{float(value):.9g}"
    return " ".join(np.array2string(np.asarray(value), precision=6, separator=", ").split())


def _describe(sample) -> str:
    return ", ".join(f"{k}={_show(v)}" for k, v in sample.items())


def unit_vector(rng):
    """A random unit vector (3,), uniform over directions."""
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def random_mass(rng):
    """A random mass (kg), log-uniform from 0.1 to 10."""
    return float(np.exp(rng.uniform(np.log(0.1), np.log(10.0))))

