"""Self-checks for the physics exercises: impulses, friction, bounces, integrators, energy.

Each check takes the student's function, calls it on seeded random inputs and compares every
answer with marchlab's own (the functions of ``physics/``, or the simulator itself), then
prints one verdict: passed (how many samples, the largest error) or "not yet", with the first
input that went wrong, the expected and the received answer, and a likely cause when the
answer matches a known mistake (a flipped normal, a forgotten 1 + e, ...). A check never
raises, whatever the student's function does; it returns a `CheckResult`, which is truthy
when the check passed. Arguments are passed by position, so any parameter names will do.

The student's functions have the signatures of the lessons' exercises (06, 07); where
``physics`` has a function of the same name (``friction_impulse``, ``semi_implicit_euler``,
``effective_masses``) the signature is the same, for one contact instead of K.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

import physics
from physics import impulses, integrators

from .result import CheckResult

__all__ = ["collision_impulse", "bounce_velocity", "friction_impulse", "effective_masses",
           "bounce_height", "explicit_euler", "semi_implicit_euler", "velocity_verlet",
           "kinetic_energy", "momentum"]

RTOL, ATOL = 1e-9, 1e-12          # agreement asked of float64 arithmetic: rounding only
G = 9.81                          # m/s^2, the default gravity of physics.World


@dataclass
class Mistake:
    """A plausible wrong answer, ``answer(sample)``, and what to tell a student who gave it."""
    answer: Callable[[dict], object]
    hint: str


# --- the machinery shared by every check --------------------------------------------------

def _verdict(name, student, samples, expected, mistakes=(), units="", rtol=RTOL, atol=ATOL,
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
        return finish(False, f"not yet: pass your function itself, e.g. marchlab.check.{name}(my_{name})"
                             f", not {type(student).__name__} (a call's result?)")
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


def _unit(rng):
    """A random unit vector (3,), uniform over directions."""
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _mass(rng):
    """A random mass (kg), log-uniform from 0.1 to 10."""
    return float(np.exp(rng.uniform(np.log(0.1), np.log(10.0))))


# --- impulses --------------------------------------------------------------------------

def _marchlab_collision(v_rel, normal, e, inverse_mass_a, inverse_mass_b):
    """physics.impulses.collision_impulse for one frictionless contact of point masses:
    returns (impulse P on a (3,), its normal part j)."""
    k_normal, k_tangent = impulses.effective_masses(
        np.array([inverse_mass_a]), np.array([inverse_mass_b]), np.zeros(1), np.zeros(1),
        np.zeros(1), np.zeros(1))
    impulse, j, _ = impulses.collision_impulse(
        v_rel[None], normal[None], np.zeros(1), np.array([e]), np.zeros(1), k_normal,
        k_tangent, threshold=0.0)
    return impulse[0], j[0]


def collision_impulse(student, samples: int = 200, seed: int = 0) -> CheckResult:
    """Check ``student(v_a, v_b, normal, m_a, m_b, e) -> j``, the restitution impulse.

    v_a, v_b : (3,) velocities (m/s); normal : (3,) unit, from b toward a; m_a, m_b : kg;
    e : restitution in [0, 1]. j (N s, a number) is the size of the impulse j n on a (and
    -j n on b): j = -(1 + e) v_N / (1/m_a + 1/m_b) with v_N = n . (v_a - v_b) when the bodies
    approach (v_N < 0), and 0 when they separate. Compared with
    physics.impulses.collision_impulse (no friction) within 1e-9 relative.
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for k in range(samples):
        normal = _unit(rng)
        v_a, v_b = rng.normal(0, 3, 3), rng.normal(0, 3, 3)
        v_n = normal @ (v_a - v_b)
        if (k % 5 != 4) == (v_n > 0):          # 4 in 5 approach, 1 in 5 separate
            v_a, v_b = v_b, v_a
        e = [0.0, 1.0][k] if k < 2 else round(float(rng.uniform()), 3)
        case = dict(v_a=v_a, v_b=v_b, normal=normal, m_a=_mass(rng), m_b=_mass(rng), e=e)
        cases.append(case)
        expected.append(np.asarray(_marchlab_collision(v_a - v_b, normal, e, 1 / case["m_a"],
                                                       1 / case["m_b"])[1]))

    def formula(c, numerator=lambda c, v_n: -(1 + c["e"]) * v_n,
                mass=lambda c: 1 / (1 / c["m_a"] + 1 / c["m_b"]), clamp=True):
        v_n = c["normal"] @ (c["v_a"] - c["v_b"])
        j = numerator(c, v_n) * mass(c)
        return max(j, 0.0) if clamp else j

    mistakes = [
        Mistake(lambda c: -formula(c, clamp=False),
                "the sign of the normal: with n from b to a an approaching pair has v_N = "
                "n . (v_a - v_b) < 0, so j = -(1 + e) v_N / (1/m_a + 1/m_b) is positive"),
        Mistake(lambda c: max(-formula(c, clamp=False), 0.0),
                "the sign of the normal: with n from b to a an approaching pair has v_N = "
                "n . (v_a - v_b) < 0; yours treats approaching pairs as separating"),
        Mistake(lambda c: -formula(c),
                "the sign: j must push the bodies apart, so it is positive when they approach"),
        Mistake(lambda c: formula(c, clamp=False),
                "a pair that is already separating (v_N > 0) needs no impulse: return 0 there "
                "(a negative j would pull the bodies together)"),
        Mistake(lambda c: formula(c, numerator=lambda c, v_n: -v_n),
                "forgot the (1 + e): this j only stops the approach (e = 0 for everyone)"),
        Mistake(lambda c: formula(c, numerator=lambda c, v_n: -c["e"] * v_n),
                "used e where (1 + e) belongs: the 1 stops the approach, the e sends the bodies "
                "apart at e times the approach speed"),
        Mistake(lambda c: formula(c, numerator=lambda c, v_n: -2 * v_n),
                "used 2 where (1 + e) belongs: that is a perfectly elastic bounce whatever e is"),
        Mistake(lambda c: formula(c, mass=lambda c: 1 / (c["m_a"] + c["m_b"])),
                "the masses: divide by 1/m_a + 1/m_b (the inverse masses add), not by m_a + m_b"),
        Mistake(lambda c: formula(c, mass=lambda c: c["m_a"] + c["m_b"]),
                "the masses: divide by 1/m_a + 1/m_b, do not multiply by m_a + m_b"),
        Mistake(lambda c: formula(c, mass=lambda c: c["m_a"]),
                "the masses: both bodies move, so the denominator is 1/m_a + 1/m_b, not 1/m_a"),
        Mistake(lambda c: formula(c, numerator=lambda c, v_n: (1 + c["e"]) * np.sign(-v_n)
                                  * np.linalg.norm(c["v_a"] - c["v_b"])),
                "used the whole relative speed |v_a - v_b|; only its part along the normal, "
                "v_N = n . (v_a - v_b), takes part in the collision"),
    ]
    return _verdict("collision_impulse", student, cases, expected, mistakes, " N s")


def bounce_velocity(student, samples: int = 200, seed: int = 1) -> CheckResult:
    """Check ``student(v, normal, e) -> v_after`` (3,): a frictionless bounce off a static wall.

    v : (3,) m/s; normal : (3,) unit, out of the wall; e in [0, 1]. The normal part of an
    approaching v comes back e times as fast, the tangential part is unchanged:
    v - (1 + e)(v . n) n; a ball already leaving (v . n >= 0) keeps v. With e = 1 it is the
    mirror reflection of lesson 05. Compared with physics.impulses.collision_impulse (the wall
    has infinite mass, the ball 1 kg, no friction).
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for k in range(samples):
        normal, v = _unit(rng), rng.normal(0, 3, 3)
        if (k % 5 != 4) == (v @ normal > 0):
            v = -v
        e = [0.0, 1.0][k] if k < 2 else round(float(rng.uniform()), 3)
        cases.append(dict(v=v, normal=normal, e=e))
        expected.append(v + _marchlab_collision(v, normal, e, 1.0, 0.0)[0])

    def bounce(c, factor=lambda e: 1 + e, clamp=True):
        v_n = c["v"] @ c["normal"]
        if clamp and v_n >= 0:
            return c["v"]
        return c["v"] - factor(c["e"]) * v_n * c["normal"]

    mistakes = [
        Mistake(lambda c: bounce(c, lambda e: 2),
                "that is the mirror reflection v - 2 (v . n) n, right only for e = 1: the normal "
                "part must come back e times as fast, v - (1 + e)(v . n) n"),
        Mistake(lambda c: bounce(c, lambda e: e),
                "used e where (1 + e) belongs: subtract (1 + e)(v . n) n"),
        Mistake(lambda c: bounce(c, lambda e: -(1 + e)),
                "the sign: v . n < 0 for a ball approaching the wall, so v - (1 + e)(v . n) n "
                "adds speed along +n"),
        Mistake(lambda c: c["v"] if c["v"] @ c["normal"] >= 0 else -c["e"] * c["v"],
                "only the normal part reverses; without friction the tangential part of v is "
                "unchanged"),
        Mistake(lambda c: bounce(c, clamp=False),
                "a ball already leaving the wall (v . n >= 0) must keep its velocity"),
    ]
    return _verdict("bounce_velocity", student, cases, expected, mistakes, " m/s")


def friction_impulse(student, samples: int = 200, seed: int = 2) -> CheckResult:
    """Check ``student(v_tangent, k_tangent, limit) -> J`` (3,), Coulomb friction for one contact.

    v_tangent : (3,) tangential relative velocity (m/s); k_tangent : 1/kg, the change of that
    velocity per unit tangential impulse; limit : mu j (N s). J = -v_t / k_t (the impulse that
    stops the sliding), shortened to length ``limit`` if it is longer. Compared with
    physics.impulses.friction_impulse within 1e-9 relative.
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for k in range(samples):
        v_t = np.zeros(3) if k % 25 == 24 else rng.normal(0, 2, 3)
        k_t = float(np.exp(rng.uniform(np.log(0.1), np.log(50))))
        stop = np.linalg.norm(v_t) / k_t               # length of the sticking impulse
        limit = stop * float(rng.uniform(1.1, 3) if k % 2 else rng.uniform(0, 0.9))
        cases.append(dict(v_tangent=v_t, k_tangent=k_t, limit=limit))
        expected.append(impulses.friction_impulse(v_t[None], np.array([k_t]),
                                                  np.array([limit]))[0])

    def coulomb(c, sticking=lambda c: -c["v_tangent"] / c["k_tangent"], clamp="length"):
        J = sticking(c)
        length = np.linalg.norm(J)
        if clamp == "length" and length > c["limit"]:
            return J * c["limit"] / length
        if clamp == "components":
            return np.clip(J, -c["limit"], c["limit"])
        return J

    mistakes = [
        Mistake(lambda c: coulomb(c, clamp=None),
                "no Coulomb limit: friction can give at most mu j, so shorten the impulse to "
                "length `limit` when -v_t / k_t is longer (the contact keeps sliding)"),
        Mistake(lambda c: coulomb(c, lambda c: c["v_tangent"] / c["k_tangent"]),
                "the sign: friction opposes the sliding, so the impulse points along -v_t"),
        Mistake(lambda c: coulomb(c, lambda c: -c["v_tangent"]),
                "forgot to divide by k_t: an impulse J changes the sliding velocity by k_t J, so "
                "the impulse that stops it is -v_t / k_t"),
        Mistake(lambda c: coulomb(c, lambda c: -c["v_tangent"] * c["k_tangent"]),
                "multiplied by k_t: the impulse that stops the sliding is -v_t / k_t"),
        Mistake(lambda c: coulomb(c, clamp="components"),
                "clamped each component: the limit is on the length of the impulse vector"),
        Mistake(lambda c: -c["limit"] * c["v_tangent"] / np.linalg.norm(c["v_tangent"]),
                "always the full mu j: when -v_t / k_t is shorter than the limit the contact "
                "sticks and the impulse is -v_t / k_t itself (static friction)"),
        Mistake(lambda c: (np.full(3, np.nan) if not c["v_tangent"].any() else coulomb(c)),
                "with v_t = 0 nothing slides and the impulse is zero: do not divide by |v_t| "
                "(or by the length of the impulse) when it is 0"),
    ]
    return _verdict("friction_impulse", student, cases, expected, mistakes, " N s")


def effective_masses(student, samples: int = 100, seed: int = 3) -> CheckResult:
    """Check ``student(inverse_mass_a, inverse_mass_b, inverse_inertia_a, inverse_inertia_b,
    radius_a, radius_b) -> (k_normal, k_tangent)`` for one contact of two solid spheres.

    k_n = 1/m_a + 1/m_b and k_t = k_n + r_a^2 / I_a + r_b^2 / I_b (1/kg): the change of the
    contact's relative velocity per unit impulse along the normal and along a tangent.
    Compared with physics.impulses.effective_masses.
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for k in range(samples):
        m_a, m_b = _mass(rng), _mass(rng)
        r_a, r_b = rng.uniform(0.02, 0.5, 2)
        static = k % 4 == 3                             # b is the floor: no mass, no radius
        case = dict(inverse_mass_a=1 / m_a, inverse_mass_b=0.0 if static else 1 / m_b,
                    inverse_inertia_a=1 / (0.4 * m_a * r_a ** 2),
                    inverse_inertia_b=0.0 if static else 1 / (0.4 * m_b * r_b ** 2),
                    radius_a=float(r_a), radius_b=0.0 if static else float(r_b))
        cases.append(case)
        expected.append(np.array([float(x[0]) for x in impulses.effective_masses(
            *(np.array([v]) for v in case.values()))]))

    def k_pair(c, lever=lambda r, ii: r * r * ii):
        k_n = c["inverse_mass_a"] + c["inverse_mass_b"]
        return [k_n, k_n + lever(c["radius_a"], c["inverse_inertia_a"])
                + lever(c["radius_b"], c["inverse_inertia_b"])]

    mistakes = [
        Mistake(lambda c: [k_pair(c)[0]] * 2,
                "k_t has the spin terms too: pushing the contact point sideways also turns the "
                "spheres, k_t = k_n + r_a^2/I_a + r_b^2/I_b"),
        Mistake(lambda c: k_pair(c, lambda r, ii: r * ii),
                "the spin term is r^2 / I (the lever arm enters twice: torque r J, then the "
                "point's speed r w), not r / I"),
        Mistake(lambda c: k_pair(c, lambda r, ii: ii / (r * r) if r else 0.0),
                "the spin term is r^2 / I, i.e. r^2 times the inverse inertia"),
    ]
    return _verdict("effective_masses", student, cases, expected, mistakes, " 1/kg")


# --- bounces, measured by the simulator ---------------------------------------------------

@functools.lru_cache(maxsize=None)
def _measured_apexes(h0: float, e: float, count: int) -> tuple:
    """Apex heights (m) of the lowest point of a ball dropped from h0 onto a floor, after
    bounces 1..count, from physics.simulate.

    Velocity Verlet keeps the recorded velocity exact in free flight and the plane test finds
    the exact moment of impact (physics/continuous.py), so y + v_y^2 / 2g just after each
    bounce is the apex to rounding.
    """
    radius = 0.05
    world = physics.World(dt=1 / 240, integrator="verlet")
    world.add_plane((0, 1, 0), 0.0, restitution=0.0)       # the pair bounces with max(e, 0)
    world.add_sphere((0, radius + h0, 0), radius=radius, restitution=e)
    t0 = np.sqrt(2 * h0 / G)
    run = physics.simulate(world, t0 * (1 + 2 * sum(e ** n for n in range(1, count + 1))) + 0.05)
    after = run.events["step"][run.events["kind"] == "sphere-plane"][:count]
    y, v = run.positions[after, 0, 1] - radius, run.velocities[after, 0, 1]
    return tuple((y + v * v / (2 * G)).tolist())


def bounce_height(student, seed: int = 4) -> CheckResult:
    """Check ``student(h0, e, n) -> h_n``: the apex after n bounces of a ball dropped from h0.

    Compared with apexes measured in the simulator (three drops, bounces 1 to 3) within 1e-9
    relative; the answer is e^(2n) h0, since a bounce multiplies the speed by e and the height
    goes with the square of the speed (h = v^2 / 2g).
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for e in (0.4, 0.6, 0.8):
        h0 = round(float(rng.uniform(0.3, 1.0)), 2)
        for n, apex in enumerate(_measured_apexes(h0, e, 3), start=1):
            cases.append(dict(h0=h0, e=e, n=n))
            expected.append(np.asarray(apex))
    mistakes = [
        Mistake(lambda c: c["e"] ** c["n"] * c["h0"],
                "e^n: a bounce multiplies the speed by e, and the height goes with the square "
                "of the speed (h = v^2 / 2g), so each bounce multiplies it by e^2"),
        Mistake(lambda c: c["e"] ** (2 * c["n"] - 2) * c["h0"],
                "off by one bounce: n = 1 is the apex after the first bounce, e^2 h0"),
        Mistake(lambda c: c["e"] ** 2 * c["h0"],
                "forgot n: every bounce multiplies the height by e^2 again, e^(2n) h0"),
        Mistake(lambda c: (1 - c["e"]) ** (2 * c["n"]) * c["h0"],
                "used 1 - e: e is the fraction of the speed that is kept"),
    ]
    return _verdict("bounce_height", student, cases, expected, mistakes, " m",
                    note="; measured in physics.simulate")


# --- integrators ---------------------------------------------------------------------------

_SCHEMES = {
    "explicit_euler": ("x + h v_old: explicit Euler, which moves with the velocity at the "
                       "start of the step", integrators.explicit_euler),
    "semi_implicit_euler": ("x + h v_new: semi-implicit Euler, which moves with the velocity "
                            "at the end of the step", integrators.semi_implicit_euler),
    "velocity_verlet": ("x + h (v_old + v_new) / 2: velocity Verlet, which moves with the mean "
                        "of the two", integrators.velocity_verlet),
}


def _integrator_check(name, student, samples, seed) -> CheckResult:
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for _ in range(samples):
        count = int(rng.integers(1, 4))
        case = dict(x=rng.normal(0, 2, (count, 3)), v_old=rng.normal(0, 3, (count, 3)),
                    v_new=rng.normal(0, 3, (count, 3)), h=float(rng.uniform(1e-3, 0.1)))
        cases.append(case)
        expected.append(_SCHEMES[name][1](**case))
    mistakes = [Mistake(lambda c, f=f: f(**c), f"your step is {text}")
                for other, (text, f) in _SCHEMES.items() if other != name]
    mistakes += [
        Mistake(lambda c: c["x"] + c["v_new"], "forgot h: a velocity times a time is a distance"),
        Mistake(lambda c: c["x"] + c["v_old"], "forgot h: a velocity times a time is a distance"),
        Mistake(lambda c: c["x"] + c["h"] * (c["v_new"] - c["v_old"]),
                "moved by the change of velocity; move by a velocity"),
    ]
    return _verdict(name, student, cases, expected, mistakes, " m",
                    note=f"; x_new = {_SCHEMES[name][0].split(':')[0]}")


def explicit_euler(student, samples: int = 100, seed: int = 5) -> CheckResult:
    """Check ``student(x, v_old, v_new, h) -> x_new`` (N, 3) against physics.integrators."""
    return _integrator_check("explicit_euler", student, samples, seed)


def semi_implicit_euler(student, samples: int = 100, seed: int = 6) -> CheckResult:
    """Check ``student(x, v_old, v_new, h) -> x_new`` (N, 3) against physics.integrators."""
    return _integrator_check("semi_implicit_euler", student, samples, seed)


def velocity_verlet(student, samples: int = 100, seed: int = 7) -> CheckResult:
    """Check ``student(x, v_old, v_new, h) -> x_new`` (N, 3) against physics.integrators."""
    return _integrator_check("velocity_verlet", student, samples, seed)


# --- what must hold on every path: energy and momentum ----------------------------------

def _random_world(rng) -> physics.World:
    """A few spheres, far apart, with random masses, radii, velocities and spins."""
    count = int(rng.integers(1, 6))
    world = physics.World()
    world.add_spheres(np.arange(count)[:, None] * [3.0, 0, 0], rng.normal(0, 2, (count, 3)),
                      radius=rng.uniform(0.05, 0.5, count),
                      mass=np.exp(rng.uniform(np.log(0.1), np.log(10), count)),
                      angular_velocities=rng.normal(0, 10, (count, 3)))
    return world


def kinetic_energy(student, samples: int = 100, seed: int = 8) -> CheckResult:
    """Check ``student(mass, radius, velocity, angular_velocity) -> K`` (J) for N solid spheres.

    mass, radius : (N,); velocity, angular_velocity : (N, 3). K = sum of 1/2 m |v|^2 +
    1/2 I |w|^2 with I = 2/5 m r^2; compared with physics.World.kinetic_energy.
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for _ in range(samples):
        w = _random_world(rng)
        cases.append(dict(mass=w.mass, radius=w.radius, velocity=w.velocity,
                          angular_velocity=w.angular_velocity))
        expected.append(np.asarray(w.kinetic_energy()))

    def energy(c, inertia=0.4, half=0.5, spin=True):
        m, r, v, w = c["mass"], c["radius"], c["velocity"], c["angular_velocity"]
        rotation = np.sum(inertia * m * r * r * np.sum(w * w, axis=1)) if spin else 0.0
        return half * (np.sum(m * np.sum(v * v, axis=1)) + rotation)

    mistakes = [
        Mistake(lambda c: energy(c, spin=False),
                "forgot the rotational energy 1/2 I |w|^2 (I = 2/5 m r^2 for a solid sphere)"),
        Mistake(lambda c: energy(c, inertia=1.0),
                "I = m r^2 is a thin ring; a solid sphere has I = 2/5 m r^2"),
        Mistake(lambda c: energy(c, inertia=2 / 3),
                "I = 2/3 m r^2 is a hollow shell; a solid sphere has I = 2/5 m r^2"),
        Mistake(lambda c: energy(c, half=1.0), "forgot the 1/2 in 1/2 m v^2"),
    ]
    return _verdict("kinetic_energy", student, cases, expected, mistakes, " J")


def momentum(student, samples: int = 100, seed: int = 9) -> CheckResult:
    """Check ``student(mass, velocity) -> p`` (3,), the total linear momentum of N spheres
    (mass (N,) kg, velocity (N, 3) m/s); compared with physics.World.momentum."""
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for _ in range(samples):
        w = _random_world(rng)
        cases.append(dict(mass=w.mass, velocity=w.velocity))
        expected.append(w.momentum())
    mistakes = [
        Mistake(lambda c: np.sum(c["velocity"], axis=0),
                "forgot the masses: p = sum of m v"),
        Mistake(lambda c: np.sum(c["mass"]) * np.mean(c["velocity"], axis=0),
                "the total mass times the mean velocity is right only for equal masses; sum "
                "m v body by body"),
        Mistake(lambda c: c["mass"] @ np.linalg.norm(c["velocity"], axis=1) * np.ones(3),
                "momentum is a vector: sum m v, not m |v|"),
    ]
    return _verdict("momentum", student, cases, expected, mistakes, " kg m/s")
