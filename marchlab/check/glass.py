"""Checks for lesson 08's glass: Snell's law in vector form, the critical angle, Schlick's
Fresnel approximation and Beer-Lambert absorption.

Rays meet a surface from both sides: entering glass (eta = 1 / ior) and leaving it (eta =
ior), where many are beyond the critical angle, so that total internal reflection is tested.
Schlick's approximation is tried on pairs of angles that obey Snell's law, entering and
leaving. The student's functions are compared with their namesakes in
`reference_cpu.refraction` (``refract`` with its first result, the direction:
`refracted`), and the critical angle with the one measured on marchlab's ``refract``
(`measured_critical_angle`); how, in `marchlab.check.judge`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu import refraction as RF
from reference_cpu.shading import reflect as _reflect
from scene_model.geometry import dot

from .judge import CASES, SAMPLES, compare, unit_vectors
from .result import CheckResult

__all__ = ["refract", "fresnel_schlick", "beer_lambert", "critical_angle"]

IOR_RANGE = (1.0, 2.5)     # air to water (1.33), glass (1.5) and diamond (2.42)


def refracted(d, n_facing, cos_i, eta):
    """(N, 3): the refracted direction of `reference_cpu.refraction.refract`, zero where the
    reflection is total (its other two results, cos t and the flag, left out)."""
    return RF.refract(d, n_facing, cos_i, eta)[0]


def measured_critical_angle(ior):
    """(N,) radians: the smallest angle of incidence, from inside glass of index ``ior`` into
    air, at which marchlab's `reference_cpu.refraction.refract` reports total internal
    reflection, found by bisection to float64 resolution.

    A ray going up (+z) inside glass whose outward normal is +z leaves it;
    `reference_cpu.refraction.facing` turns the normal toward the ray.
    """
    ior = np.asarray(ior, np.float64)
    low, high = np.zeros_like(ior), np.full_like(ior, np.pi / 2)
    normal = np.tile([0.0, 0.0, 1.0], (len(ior), 1))
    for _ in range(64):             # pi/2 / 2^64 is below the float64 spacing of the angle
        angle = (low + high) / 2
        d = np.stack([np.sin(angle), np.zeros_like(angle), np.cos(angle)], axis=1)
        _, n_facing, cos_i = RF.facing(d, normal)
        total = RF.refract(d, n_facing, cos_i, ior)[2]
        low, high = np.where(total, low, angle), np.where(total, angle, high)
    return high


# --- refract ---------------------------------------------------------------------------------

def _surface_rays(rng, n=SAMPLES):
    """(d, n_facing, cos_i, eta): unit rays meeting a surface (d.n_facing < 0), every other one
    leaving glass (eta = ior), the rest entering it (eta = 1 / ior)."""
    n_facing = unit_vectors(rng, n)
    d = unit_vectors(rng, n)
    d = d * -np.sign(dot(d, n_facing))[:, None]           # toward the surface
    ior = rng.uniform(*IOR_RANGE, n)
    eta = np.where(np.arange(n) % 2 == 0, ior, 1 / ior)
    return d, n_facing, -dot(d, n_facing), eta


def _bent(d, n, cos_i, eta, cos_t):
    return eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * n


def _cos_t(cos_i, eta):
    return np.sqrt(1 - eta * eta * (1 - cos_i * cos_i))      # nan beyond the critical angle


def _refract_mistakes():
    total = lambda cos_i, eta: RF.refract_k(cos_i, eta) <= 0
    clamped = lambda cos_i, eta: np.sqrt(np.maximum(RF.refract_k(cos_i, eta), 0))
    return [
        (lambda d, n, c, e: _bent(d, n, c, e, _cos_t(c, e)),
         "total internal reflection is not handled: where k = 1 − η²(1 − cos²i) <= 0 (leaving "
         "glass beyond the critical angle) sin t would be more than 1, the square root is nan, "
         "and there is no refracted ray; return the zero vector there (np.where on k <= 0)."),
        (lambda d, n, c, e: _bent(d, n, c, e, clamped(c, e)),
         "where k = 1 − η²(1 − cos²i) <= 0 the reflection is total and there is no refracted "
         "ray: clamping k to 0 is not enough, return the zero vector there."),
        (lambda d, n, c, e: np.where(total(c, e)[:, None], _reflect(d, n),
                                     _bent(d, n, c, e, clamped(c, e))),
         "where the reflection is total, return the zero vector: the reflected ray is the "
         "tree's other child (reflect), traced anyway; refract only says there is no "
         "refracted one."),
        (lambda d, n, c, e: RF.refract(d, n, c, 1 / e)[0],
         "η is n1 / n2, the index the ray leaves over the one it enters, and Snell's law "
         "n1 sin i = n2 sin t makes sin t = η sin i: your function uses 1 / η (it divides "
         "where it should multiply, or takes η the other way up)."),
        (lambda d, n, c, e: np.where(total(c, e)[:, None], 0,
                                     _bent(d, n, c, e, -clamped(c, e))),
         "the refracted ray goes on through the surface, away from n_facing: its part along "
         "the normal is −cos t · n_facing, not +cos t · n_facing."),
        (lambda d, n, c, e: np.where(total(c, e)[:, None], 0, _bent(d, n, -c, e, clamped(c, e))),
         "cos i = −d·n_facing is positive, so the part of d along the surface is "
         "d + cos i · n_facing (not d − cos i · n_facing): check the sign in front of η cos i."),
    ]


def refract(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d, n_facing, cos_i, eta)`` (d, n_facing : (N, 3) unit, d.n_facing < 0;
    cos_i = -d.n_facing, eta = n1 / n2 : (N,)) -> (N, 3), the refracted directions, zero
    where the reflection is total."""
    rng = np.random.default_rng(seed)
    cases = [_surface_rays(rng) for _ in range(CASES)]
    return compare("refract", student, refracted, cases, _refract_mistakes())


# --- fresnel_schlick -------------------------------------------------------------------------

def _snell_pairs(rng, n=SAMPLES):
    """(cos_i, cos_t, n1, n2) of rays that refract: every other one leaving glass (below its
    critical angle), the rest entering it, from grazing to head-on."""
    ior = rng.uniform(*IOR_RANGE, n)
    leaving = np.arange(n) % 2 == 0
    n1, n2 = np.where(leaving, ior, 1.0), np.where(leaving, 1.0, ior)
    widest = np.arcsin(np.minimum(n2 / n1, 1.0))                 # the critical angle, or 90°
    # Steepest first, so that a verdict quotes an angle where the mistakes show.
    cos_i = np.cos(np.sort(rng.uniform(0, 1, n))[::-1] * widest)
    cos_t = np.sqrt(np.maximum(RF.refract_k(cos_i, n1 / n2), 0))
    return cos_i, cos_t, n1, n2


def _schlick(cos_i, cos_t, n1, n2, c=None, square=True, scale=True):
    r0 = (n1 - n2) / (n1 + n2)
    r0 = r0 * r0 if square else r0
    c = np.where(n1 > n2, cos_t, cos_i) if c is None else c
    return r0 + (1 - r0 if scale else 1) * (1 - c) ** 5


def _schlick_mistakes():
    lower = "the cosine on the side of the lower index (air)"
    return [
        (lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, c=ci),
         f"leaving glass (n1 > n2) Schlick's c is cos t, {lower}: with cos i, F would reach "
         "1 only at 90 degrees instead of at the critical angle, and total internal "
         "reflection would begin with a jump."),
        (lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, c=ct),
         f"entering glass (n1 < n2) Schlick's c is cos i, {lower}; cos t is the angle inside "
         "the glass."),
        (lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, c=np.where(n1 > n2, ci, ct)),
         f"cos i and cos t are the other way round: c is {lower}, cos i entering glass "
         "(n1 < n2) and cos t leaving it."),
        (lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, square=False),
         "R0 = ((n1 − n2) / (n1 + n2))²: the square is missing (head-on, glass of index 1.5 "
         "reflects 4%, not 20%)."),
        (lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, scale=False),
         "the grazing term is (1 − R0)(1 − c)⁵: without the factor (1 − R0), F is more than 1 "
         "at grazing angles."),
    ]


def fresnel_schlick(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(cos_i, cos_t, n1, n2)`` (all (N,), angles that obey Snell's law) ->
    (N,), Schlick's reflected fraction."""
    rng = np.random.default_rng(seed)
    cases = [_snell_pairs(rng) for _ in range(CASES)]
    return compare("fresnel_schlick", student, RF.fresnel_schlick, cases, _schlick_mistakes())


# --- beer_lambert ----------------------------------------------------------------------------

def beer_lambert(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(absorption, distance)`` (absorption (N, 3) per unit length, distance
    (N,)) -> (N, 3), the fraction of the light left."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(CASES):
        absorption = rng.uniform(0, 4, (SAMPLES, 3))
        absorption[rng.uniform(size=(SAMPLES, 3)) < 0.2] = 0.0      # clear channels too
        cases.append((absorption, rng.uniform(0, 3, SAMPLES)))
    mistakes = [
        (lambda a, s: np.exp(a * s[:, None]), "the sign: light fades, so the fraction left is "
         "exp(−σ s), at most 1."),
        (lambda a, s: np.exp(-a) * s[:, None], "the distance goes inside the exponential: "
         "exp(−σ s), so that each extra unit of distance takes the same share of the light."),
        (lambda a, s: 1 - a * s[:, None], "1 − σ s is only the start of exp(−σ s) (its "
         "first-order term); it goes negative where σ s > 1."),
        (lambda a, s: np.exp(-a * s[:, None] ** 2), "the exponent is −σ s, linear in the "
         "distance: each slice ds of the glass absorbs the same fraction σ ds."),
    ]
    return compare("beer_lambert", student, RF.beer_lambert, cases, mistakes)


# --- critical_angle --------------------------------------------------------------------------

def critical_angle(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(ior)`` (ior : (N,), at least 1.1) -> (N,) radians, the angle of
    incidence inside glass beyond which the reflection is total (`measured_critical_angle`).

    Indices near 1 are left out: there the critical angle nears 90 degrees, and k's rounding
    moves the measured one by more than the tolerance.
    """
    rng = np.random.default_rng(seed)
    cases = [(rng.uniform(1.1, 4.0, SAMPLES),) for _ in range(CASES)]
    mistakes = [
        (lambda ior: np.arcsin(ior), "sin θc = n2 / n1 = 1 / ior (the ray leaves the glass for "
         "air); arcsin(ior) is nan, as ior > 1."),
        (lambda ior: np.arccos(1 / ior), "at the critical angle sin t = 1, so sin θc = 1 / ior: "
         "arccos gives the complement, 90 degrees − θc."),
        (lambda ior: np.degrees(np.arcsin(1 / ior)), "the angle in radians, please "
         "(np.degrees is for printing)."),
        (lambda ior: np.arctan(1 / ior), "that is Brewster's angle (tan θB = n2 / n1), where "
         "the reflected light is fully polarised; the critical angle is where Snell's sin t "
         "reaches 1."),
    ]
    return compare("critical_angle", student, measured_critical_angle, cases, mistakes)
