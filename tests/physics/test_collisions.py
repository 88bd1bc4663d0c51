"""Collisions between spheres against the textbook answers (no gravity, no friction effects).

Head-on in 1-D (masses m1, m2, velocities u1, u2, restitution e):

    v1 = (m1 u1 + m2 u2 + m2 e (u2 - u1)) / (m1 + m2)
    v2 = (m1 u1 + m2 u2 + m1 e (u1 - u2)) / (m1 + m2)

momentum is conserved, and the kinetic energy lost is mu (1 - e^2) (u1 - u2)^2 / 2 with the
reduced mass mu = m1 m2 / (m1 + m2). Checked to 1e-12 relative: only rounding remains.
"""

import numpy as np
import pytest

import physics

SOLVERS = list(physics.SOLVERS)
RADIUS = 0.1


def head_on(m1, m2, u1, u2, e, solver):
    world = physics.World(gravity=(0, 0, 0), solver=solver)
    world.add_sphere((-0.3, 0, 0), velocity=(u1, 0, 0), radius=RADIUS, mass=m1, restitution=e)
    world.add_sphere((0.3, 0, 0), velocity=(u2, 0, 0), radius=RADIUS, mass=m2, restitution=e)
    return world


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("e", [0.0, 0.3, 0.5, 1.0])
@pytest.mark.parametrize("m1, m2, u1, u2", [(1.0, 1.0, 3.0, -1.0), (2.0, 5.0, 4.0, -1.5),
                                            (10.0, 0.5, 1.0, 0.0)])
def test_head_on_velocities_momentum_and_energy_loss_within_1e_12(m1, m2, u1, u2, e, solver):
    world = head_on(m1, m2, u1, u2, e, solver)
    momentum, energy = world.momentum(), world.energy()
    world.step(120)                               # 0.5 s: they meet within 0.4 s
    v1 = (m1 * u1 + m2 * u2 + m2 * e * (u2 - u1)) / (m1 + m2)
    v2 = (m1 * u1 + m2 * u2 + m1 * e * (u1 - u2)) / (m1 + m2)
    scale = abs(u1) + abs(u2)
    assert world.velocity[:, 0] == pytest.approx([v1, v2], rel=0, abs=1e-12 * scale)
    assert np.all(world.velocity[:, 1:] == 0)
    assert np.max(np.abs(world.momentum() - momentum)) <= 1e-12 * np.abs(momentum).max()
    mu = m1 * m2 / (m1 + m2)
    lost = 0.5 * mu * (1 - e * e) * (u1 - u2) ** 2
    assert energy - world.energy() == pytest.approx(lost, rel=0, abs=1e-12 * energy)
    assert len(world.events) == 1 and world.events["kind"][0] == "sphere-sphere"


@pytest.mark.parametrize("solver", SOLVERS)
def test_equal_masses_at_e_1_swap_velocities_within_1e_12(solver):
    world = head_on(1.0, 1.0, 2.5, -0.5, 1.0, solver)
    world.step(120)
    assert world.velocity[:, 0] == pytest.approx([-0.5, 2.5], rel=0, abs=1e-12)


def newtons_cradle(solver, striker_speed=2.0):
    """Five touching balls of 0.1 m on the x axis, e = 1; ball 0 comes in from the left."""
    world = physics.World(gravity=(0, 0, 0), solver=solver)
    world.add_sphere((-0.25, 0, 0), velocity=(striker_speed, 0, 0), radius=RADIUS,
                     restitution=1.0)
    for k in range(4):
        world.add_sphere((2 * RADIUS * k, 0, 0), radius=RADIUS, restitution=1.0)
    return world


@pytest.mark.parametrize("solver", SOLVERS)
def test_newtons_cradle_last_ball_leaves_with_the_strikers_speed_within_1e_12(solver):
    """Both solvers send ball 5 off at the striker's speed and stop balls 1-4.

    Sequential: contacts 1-2, 2-3, 3-4, 4-5 in order within one sweep, each a two-ball swap.
    Simultaneous: the same swaps, one per sweep, because only one contact of the row is closing
    at a time, so no mass is shared (physics/solvers.py explains, and shows what sharing the
    mass among all touching contacts would do instead).
    """
    world = newtons_cradle(solver)
    momentum, energy = world.momentum(), world.energy()
    world.step(60)
    assert world.velocity[:, 0] == pytest.approx([0, 0, 0, 0, 2.0], rel=0, abs=1e-12)
    assert world.energy() == pytest.approx(energy, rel=1e-12)
    assert world.momentum() == pytest.approx(momentum, rel=1e-12)
    events = world.events
    assert list(zip(events["body"], events["other"])) == [(0, 1), (1, 2), (2, 3), (3, 4)]
    assert len(set(events["step"])) == 1, "the whole row is resolved within one step"


def ball_dropped_between_two(solver):
    """A ball moving at 1 m/s straight down onto two touching balls, exactly between them."""
    world = physics.World(gravity=(0, 0, 0), solver=solver)
    world.add_sphere((0, 2 * RADIUS * np.sqrt(3) / 2 + 1e-3, 0), velocity=(0, -1, 0),
                     radius=RADIUS, restitution=1.0, friction=0.0)
    world.add_sphere((-RADIUS, 0, 0), radius=RADIUS, restitution=1.0, friction=0.0)
    world.add_sphere((RADIUS, 0, 0), radius=RADIUS, restitution=1.0, friction=0.0)
    return world


def test_simultaneous_impact_sequential_is_lopsided_and_keeps_energy_within_1e_12():
    """Sequential: the striker meets ball 1 first as if ball 2 were absent, then ball 2."""
    world = ball_dropped_between_two("sequential")
    energy = world.energy()
    world.step(30)
    assert world.velocity[1, 0] != pytest.approx(-world.velocity[2, 0], abs=0.1)
    assert world.energy() == pytest.approx(energy, rel=1e-12)
    assert np.abs(world.momentum() - [0, -1, 0]).max() <= 1e-12


def test_simultaneous_impact_simultaneous_is_symmetric_and_loses_a_third_of_the_energy():
    """Simultaneous: both contacts from the same velocities, the striker's mass shared by two.

    The result is mirror-symmetric (to 1e-12) and the averaging over the two copies of the
    striker loses energy: exactly 1/3 here (checked to 1e-12); energy never rises.
    """
    world = ball_dropped_between_two("simultaneous")
    energy = world.energy()
    world.step(30)
    v = world.velocity
    assert v[1, 0] == pytest.approx(-v[2, 0], abs=1e-12)
    assert v[1, 1] == pytest.approx(v[2, 1], abs=1e-12)
    assert abs(v[0, 0]) <= 1e-12
    assert world.energy() == pytest.approx(2 / 3 * energy, rel=1e-12)
    assert np.abs(world.momentum() - [0, -1, 0]).max() <= 1e-12


@pytest.mark.parametrize("solver", SOLVERS)
def test_spheres_at_200_m_per_s_with_dt_1_60_cannot_pass_through_each_other(solver):
    world = physics.World(dt=1 / 60, gravity=(0, 0, 0), solver=solver)
    world.add_sphere((-5, 0, 0), velocity=(200, 0, 0), radius=RADIUS, restitution=1.0)
    world.add_sphere((5, 0, 0), velocity=(-200, 0, 0), radius=RADIUS, restitution=1.0)
    trajectory = physics.simulate(world, 0.2)
    x = trajectory.positions[:, :, 0]
    assert np.all(x[:, 1] - x[:, 0] >= 2 * RADIUS - 1e-9), "never overlap, never cross"
    assert world.velocity[:, 0] == pytest.approx([-200, 200], rel=1e-12)
