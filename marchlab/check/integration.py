"""Checks for lesson 06's bounces and integrators: the apex after n bounces and the time of
the n-th impact, both measured in the simulator, and the position step of each integrator in
`physics.integrators`.

How the answers are compared and reported is in `marchlab.check.physics_judge`.
"""

from __future__ import annotations

import functools

import numpy as np

import physics
from physics import integrators

from .physics_judge import Mistake, verdict
from .result import CheckResult

__all__ = ["bounce_height", "bounce_time", "explicit_euler", "semi_implicit_euler",
           "velocity_verlet"]

G = 9.81                          # m/s^2, the default gravity of physics.World


@functools.lru_cache(maxsize=None)
def _after_bounces(h0: float, e: float, count: int) -> tuple:
    """``(time, y, v)`` (s, m, m/s) at the end of each of the steps in which bounces 1..count
    of a ball dropped from rest (lowest point h0 above a floor) happened, from
    physics.simulate; y is the height of the ball's lowest point, v its vertical velocity.

    Velocity Verlet keeps the recorded velocity exact in free flight and the plane test finds
    the exact moment of impact (physics/continuous.py), so each state lies, to rounding, on the
    parabola that leaves the floor at that bounce.
    """
    radius = 0.05
    world = physics.World(dt=1 / 240, integrator="verlet")
    world.add_plane((0, 1, 0), 0.0, restitution=0.0)       # the pair bounces with max(e, 0)
    world.add_sphere((0, radius + h0, 0), radius=radius, restitution=e)
    t0 = np.sqrt(2 * h0 / G)
    run = physics.simulate(world, t0 * (1 + 2 * sum(e ** n for n in range(1, count + 1))) + 0.05)
    after = run.events["step"][run.events["kind"] == "sphere-plane"][:count]
    y, v = run.positions[after, 0, 1] - radius, run.velocities[after, 0, 1]
    return run.times[after], y, v


def _measured_apexes(h0: float, e: float, count: int) -> tuple:
    """Apex heights (m) after bounces 1..count (`_after_bounces`): y + v^2 / 2g."""
    _, y, v = _after_bounces(h0, e, count)
    return tuple((y + v * v / (2 * G)).tolist())


def _measured_impacts(h0: float, e: float, count: int) -> tuple:
    """Times (s) of impacts 1..count (`_after_bounces`): the end of the step, less the time
    tau the ball has flown since it left the floor, y = v tau + g tau^2 / 2 with v its
    velocity now."""
    time, y, v = _after_bounces(h0, e, count)
    return tuple((time - (np.sqrt(v * v + 2 * G * y) - v) / G).tolist())


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
    return verdict("bounce_height", student, cases, expected, mistakes, " m",
                   note="; measured in physics.simulate")


def bounce_time(student, seed: int = 10) -> CheckResult:
    """Check ``student(h0, e, n) -> t_n``: the time (s) of the n-th impact of a ball dropped
    from rest at t = 0 with its lowest point h0 above the floor.

    Compared with impact times measured in the simulator (drops with e from 0.3 to 1, impacts
    1 to 4) within 1e-9 relative. The answer is t0 (1 + 2 (e + e^2 + ... + e^(n-1))) with
    t0 = sqrt(2 h0 / g): the ball leaves bounce k at e^k times the landing speed g t0, so that
    flight lasts 2 e^k t0. With e = 1 that is t0 (2n - 1), where the closed form of the
    geometric sum, (1 - e^n) / (1 - e), is 0 / 0.
    """
    rng = np.random.default_rng(seed)
    cases, expected = [], []
    for e in (0.3, 0.55, 0.8, 1.0):
        h0 = round(float(rng.uniform(0.3, 1.5)), 2)
        for n, time in enumerate(_measured_impacts(h0, e, 4), start=1):
            cases.append(dict(h0=h0, e=e, n=n))
            expected.append(np.asarray(time))

    def impacts(c, fall=lambda h0: np.sqrt(2 * h0 / G), ratio=lambda e: e, flights=2,
                last=lambda n: n - 1, first=1.0):
        t0 = fall(c["h0"])
        return t0 * (first + flights * sum(ratio(c["e"]) ** k for k in range(1, last(c["n"]) + 1)))

    def closed_form(c):
        e, t0 = np.float64(c["e"]), np.sqrt(2 * c["h0"] / G)      # nan, not an error, at e = 1
        with np.errstate(all="ignore"):
            return t0 * (1 + 2 * e * (1 - e ** (c["n"] - 1)) / (1 - e))

    mistakes = [
        Mistake(lambda c: impacts(c, flights=1),
                "each flight goes up and comes down again: the flight after bounce k lasts "
                "2 e^k t0, twice the time to its apex"),
        Mistake(lambda c: impacts(c, ratio=lambda e: e * e),
                "e^2 is the ratio of the heights; a flight's time goes with the speed "
                "(t = 2 v / g), which a bounce multiplies by e"),
        Mistake(lambda c: impacts(c, ratio=lambda e: np.sqrt(e)),
                "a bounce multiplies the speed by e, and a flight's time goes with the speed "
                "(t = 2 v / g): the ratio of two flights is e, not sqrt(e)"),
        Mistake(lambda c: impacts(c, last=lambda n: n),
                "one flight too many: the n-th impact ends the flight after bounce n - 1, so "
                "the flights are those after bounces 1 .. n - 1"),
        Mistake(lambda c: impacts(c, first=0.0),
                "the first fall is missing: the ball takes t0 = sqrt(2 h0 / g) to reach the "
                "floor the first time"),
        Mistake(lambda c: impacts(c, fall=lambda h0: np.sqrt(h0 / G)),
                "the fall takes t0 = sqrt(2 h0 / g) (from h0 = g t0^2 / 2), not sqrt(h0 / g)"),
        Mistake(lambda c: impacts(c, fall=lambda h0: np.sqrt(2 * h0 * G)),
                "sqrt(2 g h0) is the landing speed; the time of the fall is "
                "t0 = sqrt(2 h0 / g)"),
        Mistake(closed_form,
                "with e = 1 the closed form of the geometric sum, (1 - e^n) / (1 - e), is 0 / 0; "
                "every flight then lasts 2 t0, so t_n = t0 (2n - 1): handle e = 1 apart, or "
                "add the terms up"),
    ]
    return verdict("bounce_time", student, cases, expected, mistakes, " s",
                   note="; measured in physics.simulate")


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
        Mistake(lambda c: c["x"] + 0.5 * (c["v_old"] + c["v_new"]),
                "forgot h: a velocity times a time is a distance"),
        Mistake(lambda c: c["x"] + c["h"] * (c["v_new"] - c["v_old"]),
                "moved by the change of velocity; move by a velocity"),
        Mistake(lambda c: c["x"] + c["h"] * (c["v_old"] + c["v_new"]),
                "moved by the sum of the two velocities, twice their mean"),
        Mistake(lambda c: c["x"] + c["h"] * c["v_old"] + 0.5 * c["h"] ** 2 * (c["v_new"]
                                                                            - c["v_old"]),
                "x + h v + h^2 a / 2 is right, but the acceleration is a = (v_new - v_old) / h, "
                "not v_new - v_old"),
    ]
    return verdict(name, student, cases, expected, mistakes, " m",
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

