"""The solvers' array helpers (physics/impulses.py) compute what the textbook formulas say, to
the bit where the arithmetic is the same, whatever the memory layout of their arguments.

The solvers store (K, 3) arrays column by column and add impulses through one scattered add
of velocity and spin together; these tests hold each helper to a plain per-contact loop or to
NumPy's own routine on the same numbers.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from physics.impulses import (SHORTEST, SolverBodies, apply_impulse, contact_rows, cross,
                              friction_impulse, relative_velocity)


def random_bodies(rng, n, dtype=np.float64):
    """N random bodies plus the static row N (zero motion, zero inverse mass)."""
    motion = np.zeros((n + 1, 6), dtype)
    motion[:n] = rng.normal(size=(n, 6))
    inverse_mass = np.append(rng.uniform(0.5, 2.0, n), 0).astype(dtype)
    inverse_inertia = np.append(rng.uniform(10, 200, n), 0).astype(dtype)
    return SolverBodies(motion, inverse_mass, inverse_inertia)


def random_contacts(rng, n, k, dtype=np.float64):
    """K contacts among N bodies, bodies repeating, a third of them with the static row."""
    a = rng.integers(0, n, k)
    b = np.where(rng.random(k) < 1 / 3, n, (a + rng.integers(1, n, k)) % n)
    normal = rng.normal(size=(k, 3))
    normal /= np.sqrt(np.sum(normal ** 2, axis=1))[:, None]
    radius_a = rng.uniform(0.05, 0.2, k).astype(dtype)
    radius_b = np.where(b == n, 0, rng.uniform(0.05, 0.2, k)).astype(dtype)
    return a, b, normal.astype(dtype), radius_a, radius_b


@pytest.mark.parametrize("order", ["C", "F"])
def test_cross_equals_numpys_cross_to_the_bit_in_either_layout(order):
    rng = np.random.default_rng(0)
    p = np.asarray(rng.normal(size=(50, 3)), order=order)
    q = np.asarray(rng.normal(size=(50, 3)), order=order)
    np.testing.assert_array_equal(cross(p, q), np.cross(p, q))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_one_scattered_add_equals_adding_each_contact_in_turn(dtype):
    """Bodies in several contacts get every contact's share, a's side of all contacts first
    and then b's, each element summed in that order: the same bits as a loop. The static
    row stays zero."""
    rng = np.random.default_rng(1)
    bodies = random_bodies(rng, 12, dtype)
    a, b, normal, radius_a, radius_b = random_contacts(rng, 12, 40, dtype)
    impulse = rng.normal(size=(40, 3)).astype(dtype)
    expected = bodies.motion.copy()
    im, ii = bodies.inverse_mass, bodies.inverse_inertia
    turn = np.cross(normal, impulse)
    for k in range(40):                                   # a's side of every contact ...
        expected[a[k], :3] += impulse[k] * im[a[k]]
        expected[a[k], 3:] += turn[k] * -(radius_a[k] * ii[a[k]])
    for k in range(40):                                   # ... then b's
        expected[b[k], :3] += impulse[k] * -im[b[k]]
        expected[b[k], 3:] += turn[k] * -(radius_b[k] * ii[b[k]])
    apply_impulse(bodies, a, b, normal, radius_a, radius_b, impulse)
    np.testing.assert_array_equal(bodies.motion, expected)
    assert not bodies.motion[12].any()


def test_relative_velocity_is_that_of_the_contact_points():
    """v_rel = (v_a + w_a x (-r_a n)) - (v_b + w_b x (r_b n)), less a moving surface's
    velocity, to rounding (np.cross here, the solver's own written-out product there)."""
    rng = np.random.default_rng(2)
    bodies = random_bodies(rng, 10)
    a, b, normal, radius_a, radius_b = random_contacts(rng, 10, 30)
    surface = rng.normal(size=(30, 3))
    v, w = bodies.velocity, bodies.spin
    expected = ((v[a] + np.cross(w[a], -radius_a[:, None] * normal))
                - (v[b] + np.cross(w[b], radius_b[:, None] * normal)) - surface)
    rows = contact_rows(bodies, a, b, radius_a, radius_b, normal)
    np.testing.assert_allclose(relative_velocity(bodies, rows, surface), expected,
                               rtol=0, atol=1e-13)


def test_bodies_given_row_by_row_are_stored_by_column_and_their_halves_write_through():
    rng = np.random.default_rng(3)
    motion = np.ascontiguousarray(rng.normal(size=(5, 6)))
    bodies = SolverBodies(motion, np.ones(5), np.ones(5))
    assert bodies.motion.flags.f_contiguous
    np.testing.assert_array_equal(bodies.motion, motion)
    bodies.velocity[2] = 7.0
    bodies.spin[3] = -1.0
    assert (bodies.motion[2, :3] == 7).all() and (bodies.motion[3, 3:] == -1).all()


def test_friction_is_cut_to_its_limit_and_zero_when_the_limit_or_the_sliding_is_zero():
    """Coulomb's cap: |J| <= limit, the direction kept; an impulse within the cap unchanged;
    no normal impulse, no friction; no sliding, no impulse, and no warning on the way."""
    v_tangent = np.array([[3.0, 0, 4], [0.3, 0, 0.4], [1, 2, 2], [0, 0, 0], [0, 0, 0]])
    k_tangent = np.array([1.0, 1.0, 2.0, 1.0, 1.0])
    limit = np.array([2.5, 10.0, 0.0, 1.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        impulse = friction_impulse(v_tangent, k_tangent, limit)
    np.testing.assert_allclose(impulse[0], [-1.5, 0, -2.0], rtol=1e-15)   # |J| = 2.5
    np.testing.assert_array_equal(impulse[1], [-0.3, 0, -0.4])           # within the cap
    np.testing.assert_array_equal(impulse[2:], 0)
    assert SHORTEST > np.finfo(np.float32).tiny      # a normal float32: no GPU flushes it
