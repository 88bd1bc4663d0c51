"""marchlab.check's physics checks: they pass marchlab's own answer, catch plausible mistakes
with a message that names the cause, and never raise, whatever the student's function does."""

import numpy as np
import pytest

from marchlab import check
from marchlab.check import physics as physics_checks
from physics import impulses, integrators


# --- a correct answer for every check, written from the formulas of lessons 06 and 07 ------

def restitution_impulse(v_a, v_b, normal, m_a, m_b, e):
    v_n = normal @ (v_a - v_b)
    return max(-(1 + e) * v_n / (1 / m_a + 1 / m_b), 0.0)


def wall_bounce(v, normal, e):
    v_n = v @ normal
    return v if v_n >= 0 else v - (1 + e) * v_n * normal


def coulomb_friction(v_tangent, k_tangent, limit):
    sticking = -v_tangent / k_tangent
    length = np.linalg.norm(sticking)
    return sticking * limit / length if length > limit else sticking


def impact_time(h0, e, n):
    """t0 (1 + 2 (e + ... + e^(n-1))), t0 = sqrt(2 h0 / g): the fall, then n - 1 flights."""
    t0 = np.sqrt(2 * h0 / 9.81)
    return t0 * (1 + 2 * sum(e ** k for k in range(1, n)))


def solid_sphere_energy(mass, radius, velocity, angular_velocity):
    inertia = 0.4 * mass * radius ** 2
    return 0.5 * np.sum(mass * np.sum(velocity ** 2, axis=1)
                        + inertia * np.sum(angular_velocity ** 2, axis=1))


CORRECT = {
    "collision_impulse": restitution_impulse,
    "bounce_velocity": wall_bounce,
    "friction_impulse": coulomb_friction,
    "effective_masses": impulses.effective_masses,
    "bounce_height": lambda h0, e, n: e ** (2 * n) * h0,
    "bounce_time": impact_time,
    "explicit_euler": integrators.explicit_euler,
    "semi_implicit_euler": integrators.semi_implicit_euler,
    "velocity_verlet": integrators.velocity_verlet,
    "kinetic_energy": solid_sphere_energy,
    "momentum": lambda mass, velocity: mass @ velocity,
}


def run(name, student, capsys):
    """The check's result and what it printed."""
    result = getattr(check, name)(student)
    return result, capsys.readouterr().out


def test_every_exported_check_has_a_correct_answer_here():
    assert sorted(physics_checks.__all__) == sorted(CORRECT)


@pytest.mark.parametrize("name", sorted(CORRECT))
def test_check_passes_the_correct_answer_with_error_below_1e_9_relative(name, capsys):
    result, out = run(name, CORRECT[name], capsys)
    assert result and result.passed, out
    assert out.startswith(f"{name}: passed (")
    assert result.samples >= 9 and result.max_error < 1e-9


@pytest.mark.parametrize("name", sorted(CORRECT))
def test_check_says_not_yet_for_a_template_raising_not_implemented(name, capsys):
    def template(*args, **kwargs):
        raise NotImplementedError("write this function")
    result, out = run(name, template, capsys)
    assert not result
    assert "not yet" in out and "NotImplementedError" in out


@pytest.mark.parametrize("name", sorted(CORRECT))
def test_check_reports_a_crashing_function_with_its_input_instead_of_raising(name, capsys):
    def crashing(*args, **kwargs):
        return 1 / 0
    result, out = run(name, crashing, capsys)
    assert not result
    assert "ZeroDivisionError" in out and "on input" in out


@pytest.mark.parametrize("name", sorted(CORRECT))
def test_check_refuses_a_value_that_is_not_a_function(name, capsys):
    result, out = run(name, 3.0, capsys)
    assert not result and "pass your function itself" in out


@pytest.mark.parametrize("name", sorted(CORRECT))
def test_check_fails_an_answer_one_part_in_a_million_off(name, capsys):
    def slightly_off(*args, **kwargs):
        return np.asarray(CORRECT[name](*args, **kwargs), float) * (1 + 1e-6)
    result, out = run(name, slightly_off, capsys)
    assert not result
    assert "expected" in out and "got" in out


# --- the mistakes each check recognises ----------------------------------------------------

def v_normal(v_a, v_b, normal):
    return normal @ (v_a - v_b)


MISTAKES = [
    ("collision_impulse", "forgot the (1 + e)",
     lambda v_a, v_b, normal, m_a, m_b, e:
         max(-v_normal(v_a, v_b, normal) / (1 / m_a + 1 / m_b), 0.0)),
    ("collision_impulse", "sign of the normal",
     lambda v_a, v_b, normal, m_a, m_b, e:
         (1 + e) * v_normal(v_a, v_b, normal) / (1 / m_a + 1 / m_b)),
    ("collision_impulse", "already separating",
     lambda v_a, v_b, normal, m_a, m_b, e:
         -(1 + e) * v_normal(v_a, v_b, normal) / (1 / m_a + 1 / m_b)),
    ("collision_impulse", "1/m_a + 1/m_b",
     lambda v_a, v_b, normal, m_a, m_b, e:
         max(-(1 + e) * v_normal(v_a, v_b, normal) / (m_a + m_b), 0.0)),
    ("collision_impulse", "a 3-vector",
     lambda v_a, v_b, normal, m_a, m_b, e: restitution_impulse(v_a, v_b, normal, m_a, m_b, e)
         * normal),
    ("bounce_velocity", "mirror reflection",
     lambda v, normal, e: v - 2 * min(v @ normal, 0) * normal),
    ("bounce_velocity", "tangential part",
     lambda v, normal, e: v if v @ normal >= 0 else -e * v),
    ("friction_impulse", "Coulomb limit",
     lambda v_tangent, k_tangent, limit: -v_tangent / k_tangent),
    ("friction_impulse", "opposes the sliding",
     lambda v_tangent, k_tangent, limit: -coulomb_friction(v_tangent, k_tangent, limit)),
    ("friction_impulse", "divide by |v_t|",
     lambda v_tangent, k_tangent, limit:
         -v_tangent / k_tangent * np.minimum(1.0, limit * k_tangent / np.linalg.norm(v_tangent))),
    ("effective_masses", "spin terms",
     lambda inverse_mass_a, inverse_mass_b, *rest: (inverse_mass_a + inverse_mass_b,) * 2),
    ("bounce_height", "square of the speed", lambda h0, e, n: e ** n * h0),
    ("bounce_height", "off by one bounce", lambda h0, e, n: e ** (2 * n - 2) * h0),
    ("bounce_velocity", "used (1 - e)",
     lambda v, normal, e: v if v @ normal >= 0 else v - (1 - e) * (v @ normal) * normal),
    ("bounce_velocity", "slows the tangential part",
     lambda v, normal, e: v if v @ normal >= 0 else e * (v - 2 * (v @ normal) * normal)),
    ("bounce_time", "up and comes down again",
     lambda h0, e, n: np.sqrt(2 * h0 / 9.81) * (1 + sum(e ** k for k in range(1, n)))),
    ("bounce_time", "ratio of the heights",
     lambda h0, e, n: np.sqrt(2 * h0 / 9.81) * (1 + 2 * sum(e ** (2 * k) for k in range(1, n)))),
    ("bounce_time", "one flight too many",
     lambda h0, e, n: np.sqrt(2 * h0 / 9.81) * (1 + 2 * sum(e ** k for k in range(1, n + 1)))),
    ("bounce_time", "first fall is missing",
     lambda h0, e, n: np.sqrt(2 * h0 / 9.81) * 2 * sum(e ** k for k in range(1, n))),
    ("bounce_time", "not sqrt(h0 / g)", lambda h0, e, n: impact_time(h0 / 2, e, n)),
    ("semi_implicit_euler", "explicit Euler", integrators.explicit_euler),
    ("explicit_euler", "semi-implicit Euler", integrators.semi_implicit_euler),
    ("velocity_verlet", "semi-implicit Euler", integrators.semi_implicit_euler),
    ("semi_implicit_euler", "forgot h", lambda x, v_old, v_new, h: x + v_new),
    ("velocity_verlet", "explicit Euler", integrators.explicit_euler),
    ("velocity_verlet", "a = (v_new - v_old) / h",
     lambda x, v_old, v_new, h: x + h * v_old + 0.5 * h * h * (v_new - v_old)),
    ("velocity_verlet", "twice their mean", lambda x, v_old, v_new, h: x + h * (v_old + v_new)),
    ("kinetic_energy", "rotational energy",
     lambda mass, radius, velocity, angular_velocity:
         0.5 * np.sum(mass * np.sum(velocity ** 2, axis=1))),
    ("kinetic_energy", "thin ring",
     lambda mass, radius, velocity, angular_velocity:
         0.5 * np.sum(mass * np.sum(velocity ** 2, axis=1)
                      + mass * radius ** 2 * np.sum(angular_velocity ** 2, axis=1))),
    ("momentum", "forgot the masses", lambda mass, velocity: velocity.sum(axis=0)),
]


@pytest.mark.parametrize("name, cause, wrong", MISTAKES,
                         ids=[f"{name}-{cause}" for name, cause, _ in MISTAKES])
def test_check_fails_a_plausible_mistake_and_names_its_cause(name, cause, wrong, capsys):
    result, out = run(name, wrong, capsys)
    assert not result
    assert out.startswith(f"{name}: not yet")
    assert cause in out, out


@pytest.mark.parametrize("name", sorted(CORRECT))
def test_check_says_a_function_without_return_returned_none(name, capsys):
    def forgot_return(*args, **kwargs):
        CORRECT[name](*args, **kwargs)
    result, out = run(name, forgot_return, capsys)
    assert not result and "returned None" in out


def test_bounce_time_tells_a_geometric_sum_divided_by_zero_at_e_1(capsys):
    """The closed form (1 - e^(n-1)) / (1 - e) is 0 / 0 at e = 1, which the check includes:
    with NumPy numbers it is nan and the hint says why, with Python ones the division raises
    and the verdict quotes the input."""
    def closed_form(h0, e, n):
        e = np.float64(e)
        with np.errstate(all="ignore"):
            return np.sqrt(2 * h0 / 9.81) * (1 + 2 * e * (1 - e ** (n - 1)) / (1 - e))
    result, out = run("bounce_time", closed_form, capsys)
    assert not result and "wrong on 4 of 16" in out and "0 / 0" in out, out

    def python_closed_form(h0, e, n):
        return (2 * h0 / 9.81) ** 0.5 * (1 + 2 * e * (1 - e ** (n - 1)) / (1 - e))
    result, out = run("bounce_time", python_closed_form, capsys)
    assert not result and "ZeroDivisionError" in out and "e=1" in out, out


def test_bounce_time_agrees_with_the_simulator_to_rounding(capsys):
    """The impact times measured in physics.simulate are the closed form to 1e-13 s."""
    result, out = run("bounce_time", impact_time, capsys)
    assert result and result.samples == 16 and result.max_error < 1e-13, out


def test_a_function_that_changes_its_argument_in_place_is_caught(capsys):
    def in_place(x, v_old, v_new, h):
        x += h * v_new
        return x
    result, out = run("semi_implicit_euler", in_place, capsys)
    assert not result and "in place" in out


def test_wrong_answers_show_the_first_failing_input_with_expected_and_got(capsys):
    result, out = run("collision_impulse", MISTAKES[0][2], capsys)
    lines = out.splitlines()
    assert lines[1].strip().startswith("input") and "e=" in lines[1]
    assert lines[2].strip().startswith("expected") and lines[3].strip().startswith("got")
    assert lines[4].strip().startswith("likely cause")
    assert result.message == out.rstrip("\n")


def test_checks_are_reproducible_from_their_seed(capsys):
    first, _ = run("collision_impulse", MISTAKES[0][2], capsys)
    second, _ = run("collision_impulse", MISTAKES[0][2], capsys)
    assert first.message == second.message


def test_arguments_are_passed_by_position_so_any_parameter_names_work(capsys):
    def my_j(va, vb, n, ma, mb, e):
        return restitution_impulse(va, vb, n, ma, mb, e)
    result, out = run("collision_impulse", my_j, capsys)
    assert result, out
