"""Checks for lesson 04's shadow rays: hard shadows (0 or 1) and Quilez's soft shadows.

Shadow rays start on the floor of the test scene (the one ``march`` is checked in) and go
toward lights above it, a light below the hanging sphere and a sun at infinity, so that
stopping at the light is tested too. The student's function is compared with its namesake in
`reference_cpu.shadows` (how, in `marchlab.check.judge`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu import march as M, sdf as S, shadows as SW
from scene_model.geometry import normalize

from .judge import SAMPLES, compare, sample_scene_sdf
from .result import CheckResult

__all__ = ["hard_shadow", "soft_shadow"]


def _shadow_cases(seed, with_k):
    """Shadow rays from floor points toward lights above, below the sphere, and at infinity."""
    rng = np.random.default_rng(seed)
    sdf = sample_scene_sdf()
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
    return compare("hard_shadow", student, SW.hard_shadow, _shadow_cases(seed, False),
                   mistakes)


def soft_shadow(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(sdf, origins, to_light, light_distance, max_steps, epsilon,
    max_distance, k)`` -> (N,) in [0, 1], Quilez's penumbra estimate."""
    def penumbra(sdf, o, l, dist, steps, eps, far, k, zero_blocked=True, scale=1.0,
                 limit=True, over_t=True):
        visible = np.ones(len(o))

        def observe(index, t, h, step):
            if step > 1:
                visible[index] = np.minimum(visible[index],
                                            scale * k * h / (t if over_t else 1))
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
        (lambda *a: penumbra(*a, over_t=False), "the clearance h must be divided by the "
         "distance t travelled: h/t is the angle at which the occluder is passed, and an "
         "occluder far along the ray hides less of the light than a near one."),
    ]
    return compare("soft_shadow", student, SW.soft_shadow, _shadow_cases(seed, True),
                   mistakes)
