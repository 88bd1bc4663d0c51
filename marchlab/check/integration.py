"""Checks for lesson 06's bounces and integrators: the apex after n bounces, measured in the
simulator, and the position step of each integrator in `physics.integrators`.

How the answers are compared and reported is in `marchlab.check.physics_judge`.
"""

from __future__ import annotations

import functools

import numpy as np

import physics
from physics import integrators

from .physics_judge import Mistake, verdict
from .result import CheckResult

__all__ = ["bounce_height", "explicit_euler", "semi_implicit_euler", "velocity_verlet"]

G = 9.81                          # m/s^2, the default gravity of physics.World


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
    return verdict("bounce_height", student, cases, expected, mistakes, " m",
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
        Mistake(lambda c: c["x"] + c["h"] * (c["v_new"] - c["v_old"]),
                "moved by the change of velocity; move by a velocity"),
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

