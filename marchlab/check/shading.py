"""Checks for lesson 03's lighting terms: reflect, Lambert, Phong, Blinn-Phong, attenuation.

Lesson 05 (reflections) checks ``reflect`` again: a mirror ray is the same formula. The
vectors are unit ``(N, 3)`` arrays, with the view near the light's mirror direction half the
time so that highlights are really tested; the ``shade_*`` checks take a
`reference_cpu.shading.Surface` and one to three lights. The student's function is compared
with its namesake in `reference_cpu.shading` (how, in `marchlab.check.judge`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_cpu import shading as SH
from reference_cpu.lights import attenuation as _attenuation
from scene_model.geometry import dot, normalize

from .judge import CASES, SAMPLES, compare, random_points, unit_vectors
from .result import CheckResult

__all__ = ["reflect", "diffuse", "specular_phong", "specular_blinn_phong", "phong",
           "blinn_phong", "shade_phong", "shade_blinn_phong", "attenuation"]


def _lighting_vectors(rng, n=SAMPLES):
    """Unit n, l, v with v near the mirror direction of the light half the time."""
    normal, to_light = unit_vectors(rng, n), unit_vectors(rng, n)
    mirror = SH.reflect(-to_light, normal)
    near = normalize(mirror + 0.3 * rng.normal(size=(n, 3)))
    view = np.where((np.arange(n) % 2 == 0)[:, None], near, unit_vectors(rng, n))
    return normal, to_light, view


def reflect(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(d, n)`` (d, n : (N, 3), n unit) -> (N, 3), the mirror direction."""
    rng = np.random.default_rng(seed)
    cases = [(unit_vectors(rng) * rng.uniform(0.5, 2), unit_vectors(rng)) for _ in range(CASES)]
    mistakes = [
        (lambda d, n: d + 2 * dot(d, n)[:, None] * n, "the sign: subtract 2(d·n)n."),
        (lambda d, n: d - dot(d, n)[:, None] * n, "the factor 2 is missing: d − (d·n)n only "
         "removes the normal part (a projection onto the surface), it does not mirror it."),
        (lambda d, n: 2 * dot(d, n)[:, None] * n - d, "that is −reflect(d, n): the result "
         "points back the way it came."),
    ]
    return compare("reflect", student, SH.reflect, cases, mistakes)


def diffuse(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(n, l)`` (unit (N, 3)) -> (N,), Lambert's max(N·L, 0)."""
    rng = np.random.default_rng(seed)
    cases = [(unit_vectors(rng), unit_vectors(rng)) for _ in range(CASES)]
    mistakes = [(lambda n, l: dot(n, l), "not clamped: where the light is behind the surface "
                 "N·L < 0, and light cannot be negative; use max(N·L, 0)."),
                (lambda n, l: np.abs(dot(n, l)), "abs(N·L) lights the back of the surface "
                 "too; use max(N·L, 0).")]
    return compare("diffuse", student, SH.diffuse, cases, mistakes)


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
        mistakes += [
            (mask(lambda n, l, v, a: np.maximum(dot(n, l + v), 0) ** a),
             "H = normalize(L + V): without normalising, N·H is not a cosine."),
            (mask(lambda n, l, v, a: np.maximum(dot(n, normalize(v - l)), 0) ** a),
             "H = normalize(L + V): both L and V point away from the surface (toward the light "
             "and the eye), so the half vector is their sum, not V − L."),
        ]
    mistakes.append((mask(lambda n, l, v, a: np.maximum(cosine(n, l, v), 0)),
                     "the shininess is missing: raise the clamped cosine to the power alpha."))
    return mistakes


def specular_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(n, l, v, shininess)`` (unit (N, 3); shininess (N,)) -> (N,)."""
    return compare("specular_phong", student, SH.specular_phong, _specular_cases(seed),
                   _specular_mistakes("phong"))


def specular_blinn_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(n, l, v, shininess)`` -> (N,), max(N·H, 0)^shininess."""
    return compare("specular_blinn_phong", student, SH.specular_blinn_phong,
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
        s = SH.Surface(position=random_points(rng, 2.0), normal=normal, view=view,
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
            with_radiance=True, ambient_per_light=False, clamp=True):
        base = s.ka[:, None] * (s.albedo if albedo_ambient else 1) * ambient * with_ambient
        color = 0 * base if ambient_per_light else base
        for l, radiance in incoming:
            sp = (s.ks * specular(s.normal, l, s.view, s.shininess))[:, None]
            cosine = SH.diffuse(s.normal, l) if clamp else dot(s.normal, l)
            term = s.kd[:, None] * cosine[:, None] * s.albedo + sp * (s.albedo if tint else 1)
            color = color + (radiance if with_radiance else 1) * term
            color = color + (base if ambient_per_light else 0)
        return color
    return [
        (lambda *a: lit(*a, ambient_per_light=True), "the ambient term is added once per "
         "light; it stands for the light of the whole room and is added once, outside the sum "
         "over the lights."),
        (lambda *a: lit(*a, clamp=False), "the diffuse cosine is not clamped: N·L < 0 (a light "
         "behind the surface) would subtract light; use max(N·L, 0)."),
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
    return compare("shade_phong", student, SH.shade_phong, _surfaces(seed),
                   _shade_mistakes(SH.specular_phong))


def shade_blinn_phong(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(surface, incoming, ambient)`` -> (N, 3), with the Blinn highlight."""
    return compare("shade_blinn_phong", student, SH.shade_blinn_phong, _surfaces(seed),
                   _shade_mistakes(SH.specular_blinn_phong))


def attenuation(student: Callable, seed: int = 0) -> CheckResult:
    """Check ``student(distance, constant, linear, quadratic)`` (distance (N,)) -> (N,)."""
    rng = np.random.default_rng(seed)
    cases = [(rng.uniform(0, 20, SAMPLES), *rng.uniform(0.2, 1, 1), *rng.uniform(0, 0.3, 2))
             for _ in range(CASES)]
    mistakes = [(lambda d, c, l, q: c + l * d + q * d * d, "attenuation divides: "
                 "1 / (constant + linear·d + quadratic·d²).")]
    return compare("attenuation", student, _attenuation, cases, mistakes)
