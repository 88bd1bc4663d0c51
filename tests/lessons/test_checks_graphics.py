"""The graphics self-checks of the lessons (marchlab.check.graphics) and `fastest_backend`.

For every check: marchlab's own function passes it; a plausibly wrong function (a squared
distance, a flipped sign, a missing clamp...) fails it with a message naming the likely cause;
a function that raises, returns None, returns the wrong shape or changes its input fails it
without the check raising. A check prints exactly the paragraph it returns.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from marchlab import check
from marchlab.check import graphics
from marchlab.check.glass import measured_critical_angle, refracted
from marchlab.check.marching import marched_steps
from reference_cpu import march as M, refraction as RF, sdf as S, shading as SH, shadows as SW
from reference_cpu.lights import attenuation
from scene_model.geometry import dot, normalize

REFERENCES = {
    "sdf_sphere": S.sdf_sphere, "sdf_box": S.sdf_box, "sdf_round_box": S.sdf_round_box,
    "sdf_plane": S.sdf_plane, "sdf_torus": S.sdf_torus,
    "sdf_capped_cylinder": S.sdf_capped_cylinder, "sdf_capsule": S.sdf_capsule,
    "sdf_cone": S.sdf_cone, "op_union": S.op_union, "op_intersection": S.op_intersection,
    "op_subtraction": S.op_subtraction, "op_smooth_union": S.op_smooth_union,
    "op_smooth_intersection": S.op_smooth_intersection,
    "op_smooth_subtraction": S.op_smooth_subtraction, "op_translate": S.op_translate,
    "op_rotate": S.op_rotate, "op_scale": S.op_scale, "op_repeat": S.op_repeat,
    "op_repeat_limited": S.op_repeat_limited,
    "reflect": SH.reflect, "diffuse": SH.diffuse, "specular_phong": SH.specular_phong,
    "specular_blinn_phong": SH.specular_blinn_phong, "shade_phong": SH.shade_phong,
    "shade_blinn_phong": SH.shade_blinn_phong, "attenuation": attenuation,
    "steps_to_floor": marched_steps,
    "hard_shadow": SW.hard_shadow, "soft_shadow": SW.soft_shadow,
    "refract": refracted, "critical_angle": measured_critical_angle,
    "fresnel_schlick": RF.fresnel_schlick, "beer_lambert": RF.beer_lambert,
}
# marchlab.render is also the name of the render function in marchlab/__init__.py
render_module = importlib.import_module("marchlab.render")

ALIASES = {"smooth_union": "op_smooth_union", "phong": "specular_phong",
           "blinn_phong": "specular_blinn_phong"}


def _lit(s, incoming, ambient, specular, tint=False, with_ambient=True,
         ambient_per_light=False, clamp=True):
    """Phong-style sum written out here, with switches for four classic mistakes."""
    color = s.ka[:, None] * s.albedo * ambient * with_ambient * (not ambient_per_light)
    for l, radiance in incoming:
        highlight = (s.ks * specular(s.normal, l, s.view, s.shininess))[:, None]
        cosine = SH.diffuse(s.normal, l) if clamp else dot(s.normal, l)
        color = color + radiance * (s.kd[:, None] * cosine[:, None] * s.albedo
                                    + highlight * (s.albedo if tint else 1))
        if ambient_per_light:
            color = color + s.ka[:, None] * s.albedo * ambient
    return color


def _cell(p, period):
    """The index of the repetition cell of each coordinate (0 on an axis of period 0)."""
    return np.where(period > 0, np.floor(p / np.where(period > 0, period, 1) + 0.5), 0)


def _fold(p, period, cell):
    """p moved back by ``cell`` periods."""
    return p - period * cell


def _repeat_dividing_by_zero(p, period, count):
    """The limited repetition without a case for period 0: p / 0 is ±inf, and nan at p = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return p - period * np.clip(np.floor(p / period + 0.5), -count, count)


def _steps_to_floor(height, angle, epsilon, max_steps, first=2):
    """The step count from the distances h (1 - sin a)^(i - 1); ``first=1`` forgets to count
    the evaluation that finds the hit."""
    ratio = np.log(epsilon / height) / np.log(1 - np.sin(angle))
    steps = np.where(height < epsilon, 1, np.floor(ratio) + first)
    return np.minimum(steps, max_steps)


def _soft_shadow_keeping_blocked(sdf, o, l, distance, max_steps, epsilon, far, k, over_t=True,
                                 zero=False):
    """Quilez's estimate without setting blocked rays to 0 (``zero=True`` sets them), and with
    ``over_t=False`` without dividing the clearance h by t."""
    visible = np.ones(len(o))

    def observe(index, t, h, step):
        if step > 1:
            visible[index] = np.minimum(visible[index], k * h / (t if over_t else 1))
    _, _, blocked = M.march(o, l, sdf, max_steps, epsilon, np.minimum(distance, far),
                            observe=observe)
    if zero:
        visible[blocked] = 0
    return np.clip(visible, 0, 1)


def _refract(d, n, cos_i, eta, total_to_zero=True, sign_t=1.0):
    """Snell's law written out, t = eta d + (eta cos_i - cos_t) n; without ``total_to_zero``
    the square root of a negative k is left as nan; ``sign_t=-1`` sends the ray back out."""
    with np.errstate(invalid="ignore"):
        cos_t = np.sqrt(1 - eta * eta * (1 - cos_i * cos_i))
    t = eta[:, None] * d + (eta * cos_i - sign_t * cos_t)[:, None] * n
    return np.where(np.isnan(cos_t)[:, None], 0.0, t) if total_to_zero else t


def _refract_reflecting_when_total(d, n, cos_i, eta):
    """Snell's law, with the mirror direction where the reflection is total."""
    t, _, total = RF.refract(d, n, cos_i, eta)
    return np.where(total[:, None], SH.reflect(d, n), t)


def _schlick(cos_i, cos_t, n1, n2, c=None, square=True):
    """Schlick's F with the cosine ``c`` chosen by the caller (default: the low-index side's)."""
    r0 = ((n1 - n2) / (n1 + n2)) ** (2 if square else 1)
    c = np.where(n1 > n2, cos_t, cos_i) if c is None else c
    return r0 + (1 - r0) * (1 - c) ** 5


# (check, a plausible wrong answer, words the verdict must contain)
WRONG = [
    ("sdf_sphere", lambda p, r: dot(p, p) - r * r, "squared"),
    ("sdf_box", lambda p, b: S.length(np.maximum(np.abs(p) - b, 0)), "inside"),
    ("sdf_round_box", lambda p, b, r: S.sdf_box(p, b) - r, "shrunk"),
    ("sdf_plane", lambda p, n, h: dot(p, n) - h, "unit length"),
    ("sdf_torus", lambda p, big, small: S.sdf_torus(p, small, big), "swapped"),
    ("sdf_capped_cylinder", lambda p, r, h: S.length2(p[:, 0], p[:, 2]) - r, "infinite"),
    ("sdf_capsule", lambda p, a, b, r: S.length(
        p - a - (dot(p - a, b - a) / dot(b - a, b - a))[:, None] * (b - a)) - r, "clamped"),
    ("sdf_cone", lambda p, r, h: -S.sdf_cone(p, r, h), "sign is flipped"),
    ("op_union", lambda a, b: np.maximum(a, b), "intersection"),
    ("op_intersection", lambda a, b: np.minimum(a, b), "union"),
    ("op_subtraction", lambda a, b: np.maximum(-a, b), "shape 1 minus shape 2"),
    ("op_smooth_union", lambda a, b, k: _smooth_union_plus(a, b, k), "wrong sign"),
    ("op_smooth_intersection", lambda a, b, k: np.maximum(a, b), "no blending"),
    ("op_smooth_subtraction", lambda a, b, k: _without_fillet_subtraction(a, b, k), "missing"),
    ("op_translate", lambda p, o: p + o, "opposite way"),
    ("op_rotate", lambda p, m: p @ m.T, "Rᵀ"),
    ("op_scale", lambda p, s: p * s, "p / s"),
    ("op_repeat", lambda p, c: np.where(c > 0, np.mod(p, np.where(c > 0, c, 1)), p),
     "not centred"),
    ("op_repeat_limited", lambda p, c, n: S.op_repeat(p, c), "clamp the cell index"),
    ("op_repeat_limited", lambda p, c, n: _fold(p, c, np.minimum(np.abs(_cell(p, c)), n)),
     "sign of the cell index is lost"),
    ("op_repeat_limited", lambda p, c, n: _fold(p, c, np.where(np.abs(_cell(p, c)) > n, 0,
                                                               _cell(p, c))),
     "measure it from the nearest copy, the last one"),
    ("op_repeat_limited", lambda p, c, n: _repeat_dividing_by_zero(p, c, n),
     "p / 0 is nan where the coordinate is 0"),
    ("op_repeat_limited", lambda p, c, n: _fold(p, c, np.clip(_cell(p, c), 0, n)),
     "not [0, count]"),
    ("op_repeat_limited", lambda p, c, n: np.where(
        c > 0, S.op_repeat(np.clip(p, -c * (n + 0.5), c * (n + 0.5)), c), p),
     "clamp the cell index instead"),
    ("op_subtraction", lambda a, b: np.minimum(a, -b), "inside 1 *or* outside 2"),
    ("op_smooth_subtraction", lambda a, b, k: S.op_smooth_union(-a, b, k), "negated again"),
    ("op_smooth_subtraction", lambda a, b, k: -S.op_smooth_union(a, -b, k),
     "cut shape 1 out of shape 2"),
    ("op_smooth_subtraction", lambda a, b, k: S.op_smooth_union(a, -b, k),
     "inside 1 *or* outside 2"),
    ("op_smooth_intersection", lambda a, b, k: S.op_smooth_union(-a, -b, k), "negated again"),
    ("op_smooth_intersection", lambda a, b, k: S.op_smooth_union(a, b, k),
     "that is the smooth union"),
    ("specular_blinn_phong", lambda n, l, v, a: np.where(
        dot(n, l) > 0, np.maximum(dot(n, normalize(v - l)), 0) ** a, 0), "not V − L"),
    ("specular_blinn_phong", lambda n, l, v, a: np.where(
        dot(n, l) > 0, np.maximum(dot(n, normalize(l + v)), 0), 0), "shininess is missing"),
    ("shade_phong", lambda s, i, a: _lit(s, i, a, SH.specular_phong, ambient_per_light=True),
     "once per light"),
    ("shade_phong", lambda s, i, a: _lit(s, i, a, SH.specular_phong, clamp=False),
     "diffuse cosine is not clamped"),
    ("soft_shadow", lambda *args: _soft_shadow_keeping_blocked(*args, over_t=False, zero=True),
     "divided by the distance t"),
    ("reflect", lambda d, n: d - dot(d, n)[:, None] * n, "factor 2"),
    ("diffuse", lambda n, l: dot(n, l), "not clamped"),
    ("specular_phong", lambda n, l, v, a: np.where(
        dot(n, l) > 0, np.maximum(dot(SH.reflect(l, n), v), 0) ** a, 0), "reflect(−L, N)"),
    ("specular_blinn_phong", lambda n, l, v, a: np.where(
        dot(n, l) > 0, np.maximum(dot(n, l + v), 0) ** a, 0), "normalize"),
    ("shade_phong", lambda s, i, a: _lit(s, i, a, SH.specular_phong, tint=True), "albedo"),
    ("shade_blinn_phong", lambda s, i, a: _lit(s, i, a, SH.specular_blinn_phong,
                                               with_ambient=False), "ambient"),
    ("attenuation", lambda d, c, l, q: c + l * d + q * d * d, "divides"),
    ("steps_to_floor", lambda *args: _steps_to_floor(*args, first=1),
     "counts every SDF evaluation, the last one too"),
    ("hard_shadow", lambda *args: 1 - SW.hard_shadow(*args), "other way round"),
    ("soft_shadow", _soft_shadow_keeping_blocked, "set the visibility of blocked rays to 0"),
    ("refract", lambda *a: _refract(*a, total_to_zero=False),
     "total internal reflection is not handled"),
    ("refract", lambda d, n, c, e: RF.refract(d, n, c, 1 / e)[0], "your function uses 1 / η"),
    ("refract", _refract_reflecting_when_total, "return the zero vector"),
    ("refract", lambda *a: _refract(*a, sign_t=-1.0), "away from n_facing"),
    ("critical_angle", lambda ior: np.arctan(1 / ior), "Brewster's angle"),
    ("critical_angle", lambda ior: np.degrees(np.arcsin(1 / ior)), "in radians"),
    ("fresnel_schlick", lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, c=ci),
     "leaving glass (n1 > n2) Schlick's c is cos t"),
    ("fresnel_schlick", lambda ci, ct, n1, n2: _schlick(ci, ct, n1, n2, c=ct),
     "entering glass (n1 < n2) Schlick's c is cos i"),
    ("fresnel_schlick", lambda *a: _schlick(*a, square=False), "the square is missing"),
    ("beer_lambert", lambda a, s: np.exp(a * s[:, None]), "the sign"),
    ("beer_lambert", lambda a, s: 1 - a * s[:, None], "first-order term"),
]


def _smooth_union_plus(a, b, k):
    """Quilez's smooth minimum with its fillet k h (1 - h) added instead of subtracted."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0, 1)
    return b + (a - b) * h + k * h * (1 - h)


def _without_fillet_subtraction(a, b, k):
    """The smooth subtraction's mix of d1 and -d2 without its k h (1 - h) term."""
    h = np.clip(0.5 - 0.5 * (a + b) / k, 0, 1)
    return a + (-b - a) * h


def run(name, function, capsys=None):
    """Run one check; with capsys, also assert that it printed exactly its message."""
    result = getattr(check, name)(function)
    if capsys is not None:
        assert capsys.readouterr().out == result.message + "\n"
    return result


def test_every_check_is_exported_and_tested():
    checks = {name for name in graphics.__all__ if name not in ("CheckResult", "TOLERANCE")}
    assert checks == set(REFERENCES) | set(ALIASES)
    assert {name for name, _, _ in WRONG} == set(REFERENCES)
    for alias, name in ALIASES.items():
        assert getattr(check, alias) is getattr(check, name)


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_reference_function_passes_its_own_check(name, capsys):
    result = run(name, REFERENCES[name], capsys)
    assert result.passed and bool(result)
    assert result.samples >= 500
    assert result.max_error == 0.0              # the same function on the same inputs
    assert result.message.startswith(f"{name}: passed.")


@pytest.mark.parametrize("name, wrong, cause", WRONG, ids=[w[0] for w in WRONG])
def test_plausible_mistake_fails_with_its_likely_cause(name, wrong, cause, capsys):
    result = run(name, wrong, capsys)
    assert not result.passed and not bool(result)
    assert result.message.startswith(f"{name}: not yet.")
    flat = " ".join(result.message.split())       # the paragraph is wrapped at 96 columns
    assert "Likely cause" in flat and cause in flat, flat


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_a_function_that_raises_is_reported_not_raised(name, capsys):
    def broken(*args):
        raise ValueError("operands could not be broadcast")

    result = run(name, broken, capsys)
    assert not result.passed
    assert "raised ValueError: operands could not be broadcast" in " ".join(result.message.split())


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_an_exercise_template_gets_a_not_yet_message(name, capsys):
    def template(*args):
        raise NotImplementedError("write it here")

    result = run(name, template, capsys)
    assert not result.passed
    assert result.message.startswith(f"{name}: not yet. Your function still raises "
                                     "NotImplementedError")


def test_missing_return_is_reported():
    result = run("sdf_torus", lambda p, big, small: None)
    assert not result.passed and "forget the `return`" in " ".join(result.message.split())


def test_one_number_for_all_points_is_reported_as_a_shape_error():
    result = run("sdf_sphere", lambda p, r: np.linalg.norm(p) - r)   # norm of the whole array
    flat = " ".join(result.message.split())
    assert not result.passed and "shape ()" in flat and "axis=-1" in flat


def test_changing_the_input_in_place_is_reported():
    def moves_p(p, offset):
        p -= offset
        return p

    result = run("op_translate", moves_p)
    flat = " ".join(result.message.split())
    assert not result.passed and "changed its input `p` in place" in flat


@pytest.mark.parametrize("seed", range(6))
def test_steps_to_floor_follows_the_geometric_sequence_of_distances_for_every_seed(seed):
    """The textbook march's step counts to a floor are exactly the closed form."""
    result = check.steps_to_floor(_steps_to_floor, seed=seed)
    assert result.passed and result.max_error == 0.0 and result.samples > 900


def test_steps_to_floor_that_ignores_max_steps_is_told_so():
    def unlimited(height, angle, epsilon, max_steps):
        return _steps_to_floor(height, angle, epsilon, np.inf)

    result = run("steps_to_floor", unlimited)
    flat = " ".join(result.message.split())
    assert not result.passed and "never more than max_steps" in flat


def test_smooth_intersection_and_subtraction_derived_from_the_smooth_union_pass():
    """Lesson 02's route: max(a, b) = -min(-a, -b) turns the smooth union into the others,
    equal to marchlab's within the tolerance."""
    smin = S.op_smooth_union
    for name, derived in (("op_smooth_intersection", lambda a, b, k: -smin(-a, -b, k)),
                          ("op_smooth_subtraction", lambda a, b, k: -smin(-a, b, k))):
        result = run(name, derived)
        assert result.passed and result.max_error <= graphics.TOLERANCE


def test_op_repeat_limited_passes_a_clamped_round_and_fails_an_unclamped_one_beyond_the_copies():
    """Clamping the rounded cell index is right; without the clamp only the points inside the
    last copy agree, and the check finds the others (half its points lie beyond)."""
    def clamped(p, period, count):
        index = np.clip(np.round(p / np.where(period > 0, period, 1)), -count, count)
        return p - np.where(period > 0, period * index, 0)

    assert run("op_repeat_limited", clamped).passed
    result = run("op_repeat_limited", lambda p, period, count: S.op_repeat(p, period))
    assert not result.passed
    wrong = int(" ".join(result.message.split()).split("wrong at ")[1].split()[0])
    assert 0.3 * result.samples < wrong < result.samples


def test_first_failing_input_is_quoted_with_expected_and_got():
    result = run("sdf_sphere", lambda p, r: S.length(p) - r + 0.25)
    flat = " ".join(result.message.split())
    assert "For p = (" in flat and "radius = " in flat and "marchlab gives" in flat
    assert "off by the same constant 0.25" in flat


def test_checks_are_deterministic_for_a_seed():
    wrong = lambda p, big, small: S.sdf_torus(p, big, small) * 1.5
    assert run("sdf_torus", wrong).message == run("sdf_torus", wrong).message
    assert check.sdf_torus(wrong, seed=1).message != check.sdf_torus(wrong, seed=2).message


def test_a_correct_rewrite_passes_within_the_tolerance():
    # The same formulas, written differently from reference_cpu (order of operations differs).
    def torus(p, big, small):
        ring = np.hypot(p[:, 0], p[:, 2]) - big
        return np.sqrt(ring ** 2 + p[:, 1] ** 2) - small

    def blinn(n, l, v, shininess):
        h = normalize(l + v)
        lobe = np.clip(np.einsum("ij,ij->i", n, h), 0, None) ** shininess
        return np.where(np.einsum("ij,ij->i", n, l) > 0, lobe, 0.0)

    for name, function in (("sdf_torus", torus), ("specular_blinn_phong", blinn)):
        result = run(name, function)
        assert result.passed and result.max_error <= graphics.TOLERANCE


# --- glass (lesson 08) ---------------------------------------------------------------------

def test_refract_written_from_the_two_parts_of_the_lesson_passes_within_the_tolerance():
    """Lesson 08's route: eta times the part of d along the surface, minus cos t along n."""
    def refract(d, n, cos_i, eta):
        k = 1 - eta ** 2 * (1 - cos_i ** 2)
        t = (eta[:, None] * (d + cos_i[:, None] * n)
             - np.sqrt(np.clip(k, 0, None))[:, None] * n)
        return np.where((k <= 0)[:, None], 0.0, t)

    result = run("refract", refract)
    assert result.passed and result.max_error <= graphics.TOLERANCE


def test_refract_is_checked_where_the_reflection_is_total():
    """A third or more of the check's rays are beyond the critical angle: a function that is
    right everywhere else but forgets them fails on those rays and no others."""
    result = run("refract", lambda *a: _refract(*a, total_to_zero=False))
    wrong = int(" ".join(result.message.split()).split("wrong at ")[1].split()[0])
    assert 0.3 * result.samples < wrong < 0.5 * result.samples


def test_critical_angle_measured_on_refract_is_arcsin_of_one_over_ior_within_1e_15():
    """The bisection on marchlab's refract finds Snell's sin i = 1 / ior to float64 rounding."""
    ior = np.linspace(1.1, 4.0, 300)
    np.testing.assert_allclose(measured_critical_angle(ior), np.arcsin(1 / ior), rtol=0,
                               atol=1e-15)
    assert run("critical_angle", lambda ior: np.arcsin(1 / ior)).max_error < 1e-15


def test_fresnel_schlick_cases_refract_both_ways_below_the_critical_angle():
    """Half the check's pairs enter glass and half leave it, all obeying Snell's law, so the
    choice of the cosine is tested both ways."""
    from marchlab.check.glass import _snell_pairs
    cos_i, cos_t, n1, n2 = _snell_pairs(np.random.default_rng(0))
    assert (n1 > n2).sum() == (n1 < n2).sum() == len(n1) // 2
    sin_i, sin_t = np.sqrt(1 - cos_i ** 2), np.sqrt(1 - cos_t ** 2)
    np.testing.assert_allclose(n1 * sin_i, n2 * sin_t, atol=1e-12)


# --- fastest_backend (marchlab/render.py) ------------------------------------------------------

def test_fastest_backend_is_the_first_working_of_gpu_opencl_numpy():
    working = [b for b in ("gpu", "opencl") if render_module.backend_problem(b) is None]
    expected = working[0] if working else "numpy"
    assert render_module.fastest_backend() == expected


@pytest.mark.parametrize("broken, expected", [((), "gpu"), (("gpu",), "opencl"),
                                              (("gpu", "opencl"), "numpy")])
def test_fastest_backend_skips_backends_with_a_problem(broken, expected, monkeypatch):
    monkeypatch.setattr(render_module, "backend_problem",
                        lambda b: "missing here" if b in broken else None)
    render_module.fastest_backend.cache_clear()
    try:
        assert render_module.fastest_backend() == expected
    finally:
        render_module.fastest_backend.cache_clear()


def test_fastest_backend_asks_only_once(monkeypatch):
    asked = []
    monkeypatch.setattr(render_module, "backend_problem", lambda b: asked.append(b) or None)
    render_module.fastest_backend.cache_clear()
    try:
        assert render_module.fastest_backend() == render_module.fastest_backend() == "gpu"
        assert asked == ["gpu"]
    finally:
        render_module.fastest_backend.cache_clear()
