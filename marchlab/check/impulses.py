"""Checks for the impulse exercises of lessons 05 and 06: restitution, a bounce off a wall,
Coulomb friction and the effective masses of a contact.

Each student's function handles one contact; marchlab's (`physics.impulses`) handles K at once,
so the check calls it with K = 1. How the answers are compared and reported is in
`marchlab.check.physics_judge`.
"""

from __future__ import annotations

import numpy as np

from physics import impulses

from .physics_judge import Mistake, random_mass, unit_vector, verdict
from .result import CheckResult

__all__ = ["collision_impulse", "bounce_velocity", "friction_impulse", "effective_masses"]


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
        normal = unit_vector(rng)
        v_a, v_b = rng.normal(0, 3, 3), rng.normal(0, 3, 3)
        v_n = normal @ (v_a - v_b)
        if (k % 5 != 4) == (v_n > 0):          # 4 in 5 approach, 1 in 5 separate
            v_a, v_b = v_b, v_a
        e = [0.0, 1.0][k] if k < 2 else round(float(rng.uniform()), 3)
        case = dict(v_a=v_a, v_b=v_b, normal=normal, m_a=random_mass(rng),
                    m_b=random_mass(rng), e=e)
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
    return verdict("collision_impulse", student, cases, expected, mistakes, " N s")


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
        normal, v = unit_vector(rng), rng.normal(0, 3, 3)
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
        Mistake(lambda c: bounce(c, lambda e: 1 - e),
                "used (1 - e) where (1 + e) belongs: removing v_N n stops the ball, and e v_N n "
                "more sends it back, v - (1 + e)(v . n) n"),
        Mistake(lambda c: c["v"] if c["v"] @ c["normal"] >= 0 else c["e"] * bounce(c, lambda e: 2),
                "e times the mirror direction slows the tangential part too; without friction "
                "only the normal part changes: v - (1 + e)(v . n) n"),
    ]
    return verdict("bounce_velocity", student, cases, expected, mistakes, " m/s")


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
    return verdict("friction_impulse", student, cases, expected, mistakes, " N s")


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
        m_a, m_b = random_mass(rng), random_mass(rng)
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
    return verdict("effective_masses", student, cases, expected, mistakes, " 1/kg")

