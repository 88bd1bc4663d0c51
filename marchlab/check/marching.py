"""Check for lesson 01's exercise on the march: how many steps does a ray take to a floor?

The lesson shows the loop itself (`reference_cpu.march.textbook_march`); the exercise asks
what it does. A ray starts at height h above the floor y = 0 and heads down at an angle a to
it. The floor is a plane, so every step moves the ray down by d sin a, and the distances form a
geometric sequence: d_i = h (1 - sin a)^(i - 1). The student turns that and the loop's rules
(``steps`` counts every evaluation, a hit needs d_i < epsilon, no ray takes more than
max_steps) into a formula. The check marches the same rays with `textbook_march` and asks for
the same step counts exactly; how it compares and reports is in `marchlab.check.judge`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu.march import textbook_march
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.shapes import Plane

from .judge import CASES, SAMPLES, compare
from .result import CheckResult

__all__ = ["steps_to_floor"]


def marched_steps(height, angle, epsilon, max_steps):
    """The ``steps`` of `textbook_march` from (0, h, 0) along (cos a, -sin a, 0) to the floor.

    Parameters
    ----------
    height : (N,) ndarray
        Start heights above the floor y = 0.
    angle : (N,) ndarray
        Angles between the rays and the floor, radians.
    epsilon : float
    max_steps : int

    Returns
    -------
    (N,) int32 ndarray
    """
    zero = np.zeros_like(height)
    origins = np.column_stack([zero, height, zero])
    directions = np.column_stack([np.cos(angle), -np.sin(angle), zero])
    floor = build_scene_sdf([Plane()])
    return textbook_march(origins, directions, floor, max_steps, epsilon, np.inf)[1]


def _counted(height, angle, epsilon, max_steps, fraction_left=lambda a: 1 - np.sin(a),
             first=2, within_epsilon=True, limited=True):
    """The step count from the geometric sequence, with switches for the classic mistakes.

    The first i with h q^(i - 1) < epsilon is floor(log(epsilon / h) / log q) + 2 (q < 1),
    except that a ray starting within epsilon hits at its first evaluation.
    """
    with np.errstate(divide="ignore"):
        steps = np.floor(np.log(epsilon / height) / np.log(fraction_left(angle))) + first
    if within_epsilon:
        steps = np.where(height < epsilon, 1, steps)
    return np.minimum(steps, max_steps) if limited else steps


def _rays(rng, epsilon):
    """SAMPLES start heights (one in eight already within epsilon) and angles, 2 to 89 degrees,
    none so close to a step boundary that rounding could move the count by one."""
    height = np.where(np.arange(SAMPLES) % 8 == 7, rng.uniform(0.05, 0.95, SAMPLES) * epsilon,
                      rng.uniform(0.2, 5.0, SAMPLES))
    angle = np.radians(rng.uniform(2.0, 89.0, SAMPLES))
    ratio = np.log(epsilon / height) / np.log(1 - np.sin(angle))
    clear = np.abs(ratio - np.round(ratio)) > 1e-6
    return height[clear], angle[clear]


def steps_to_floor(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(height, angle, epsilon, max_steps)`` -> (N,) step counts.

    ``height`` (N,) are start heights above the floor y = 0, ``angle`` (N,) the angles
    between the rays and the floor in radians (0 grazing, pi/2 straight down); ``epsilon``
    and ``max_steps`` are the march's settings. The answer must be the ``steps`` that
    `reference_cpu.march.textbook_march` returns for those rays (`marched_steps`), exactly.
    """
    rng = np.random.default_rng(seed)
    cases = []
    for j in range(CASES):
        epsilon = float(10 ** rng.uniform(-4, -2))
        max_steps = 1000 if j % 2 == 0 else int(rng.integers(4, 40))   # half cut rays short
        cases.append((*_rays(rng, epsilon), epsilon, max_steps))
    mistakes = [
        (lambda *a: _counted(*a, first=1), "steps counts every SDF evaluation, the last one "
         "too: the ray that reaches d < epsilon at evaluation i took i steps, and d_i is "
         "h (1 − sin a)^(i − 1)."),
        (lambda *a: _counted(*a, first=3), "one step too many: the first evaluation, at "
         "t = 0, already counts as step 1, and d_1 = h."),
        (lambda *a: _counted(*a, fraction_left=lambda a: 1 - np.cos(a)), "the angle is "
         "measured from the floor, not from its normal: a step of length d comes down by "
         "d sin a, leaving the fraction 1 − sin a of the height."),
        (lambda *a: _counted(*a, limited=False), "a ray that has not arrived after max_steps "
         "evaluations stops there: steps is never more than max_steps."),
        (lambda *a: _counted(*a, within_epsilon=False), "a ray that starts within epsilon of "
         "the floor hits at its first evaluation: steps is 1 where height < epsilon."),
        (lambda h, a, eps, n: np.minimum(np.ceil(np.log(h / eps) / np.sin(a)), n),
         "ln(h / epsilon) / sin a is the estimate for small angles (ln q ≈ −sin a); count "
         "exactly with the logarithm of q = 1 − sin a."),
    ]
    return compare("steps_to_floor", student, marched_steps, cases, mistakes)
