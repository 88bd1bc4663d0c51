"""Checks for lesson 07's invariants, what must hold on every path of a simulation: the
kinetic energy (spin included) and the momentum of a set of spheres, against `physics.World`.

How the answers are compared and reported is in `marchlab.check.physics_judge`.
"""

from __future__ import annotations

import numpy as np

import physics

from .physics_judge import Mistake, verdict
from .result import CheckResult

__all__ = ["kinetic_energy", "momentum"]


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
    return verdict("kinetic_energy", student, cases, expected, mistakes, " J")


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
    return verdict("momentum", student, cases, expected, mistakes, " kg m/s")
