"""Friction with spin, and resting contact.

Sliding to rolling: a solid ball (I = 2/5 m r^2) set sliding at v0 on a floor with friction mu
slows by mu g while friction spins it up, until its contact point stops slipping. Angular
momentum about the contact point, m v r + I w, is conserved (friction acts at that point, and
gravity and the normal force pass through it), so rolling starts at

    v = m v0 r / (m r + I / r) = 5/7 v0 = 3.5714 m/s          for v0 = 5 m/s,

at t* = 2 v0 / (7 mu g) = 0.4854 s for mu = 0.3, after x = v0 t* - mu g t*^2 / 2 = 2.0800 m.
The discrete impulses conserve that angular momentum step by step too, so the final speed is
5/7 v0 to rounding (checked to 1e-6 for every dt; it holds to ~1e-13). t*
and the distance carry an O(dt) error: checked within one step and 0.5%.
"""

import numpy as np
import pytest

import physics

G = 9.81
RADIUS = 0.1
V0, MU = 5.0, 0.3


def sliding_ball(dt, solver="sequential", integrator="semi_implicit"):
    world = physics.World(dt=dt, solver=solver, integrator=integrator)
    world.add_plane((0, 1, 0), 0, friction=MU)
    world.add_sphere((0, RADIUS, 0), velocity=(V0, 0, 0), radius=RADIUS, friction=MU)
    return physics.simulate(world, 0.8)


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
@pytest.mark.parametrize("dt", [1 / 60, 1 / 240, 1 / 1000])
def test_sliding_ball_rolls_at_five_sevenths_v0_within_1e_6_for_any_dt(dt, solver):
    trajectory = sliding_ball(dt, solver)
    assert trajectory.velocities[-1, 0, 0] == pytest.approx(5 / 7 * V0, abs=1e-6)
    assert 5 / 7 * V0 == pytest.approx(3.5714, abs=1e-4)
    # Rolling: the contact point is at rest, v + w x (-r y) = 0, i.e. v_x = -r w_z.
    assert trajectory.angular_velocities[-1, 0, 2] == pytest.approx(-5 / 7 * V0 / RADIUS,
                                                                    abs=1e-5)
    assert np.abs(trajectory.positions[:, 0, 1] - RADIUS).max() <= 1e-12, "stays on the floor"


@pytest.mark.parametrize("dt", [1 / 240, 1 / 1000])
def test_sliding_ball_starts_rolling_at_t_star_within_one_step_after_2_080_m_within_half_percent(
        dt):
    trajectory = sliding_ball(dt)
    slip = trajectory.velocities[:, 0, 0] + RADIUS * trajectory.angular_velocities[:, 0, 2]
    rolling = np.argmax(np.abs(slip) < 1e-9)
    t_star = 2 * V0 / (7 * MU * G)
    assert t_star == pytest.approx(0.4854, abs=1e-4)
    assert abs(trajectory.times[rolling] - t_star) <= dt
    distance = V0 * t_star - 0.5 * MU * G * t_star ** 2
    assert distance == pytest.approx(2.080, abs=5e-4)
    assert trajectory.positions[rolling, 0, 0] == pytest.approx(distance, rel=0.005)


def test_without_the_spin_term_the_ball_would_stop_instead_of_rolling():
    """Guard for the angular terms: a frictional ball must not simply skid to a halt."""
    trajectory = sliding_ball(1 / 240)
    assert trajectory.velocities[:, 0, 0].min() > 3.5
    assert trajectory.angular_velocities[-1, 0, 2] < -30


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_resting_ball_for_10_s_keeps_speed_below_1e_6_and_drift_below_1e_6(integrator, solver):
    world = physics.World(integrator=integrator, solver=solver)
    world.add_plane((0, 1, 0), 0, restitution=0.9)
    world.add_sphere((0.3, RADIUS, -0.2), radius=RADIUS, restitution=0.9)
    trajectory = physics.simulate(world, 10.0, record_every=24)
    speed = np.sqrt(np.sum(trajectory.velocities[:, 0] ** 2, axis=1))
    assert speed.max() < 1e-6
    drift = np.sqrt(np.sum((trajectory.positions[:, 0] - (0.3, RADIUS, -0.2)) ** 2, axis=1))
    assert drift.max() < 1e-6
    assert len(trajectory.events) == 0, "resting contact never registers as a collision"


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_stack_of_three_balls_comes_to_rest_within_1e_3_m_per_s(solver):
    """Three balls stacked (e = 0.5) settle: speed < 1e-3 m/s and each within 1 mm of its
    resting height after 3 s; no energy appears (it never exceeds the start by 1e-9 J)."""
    world = physics.World(solver=solver)
    world.add_plane((0, 1, 0), 0)
    for k in range(3):
        world.add_sphere((0, RADIUS + 2 * RADIUS * k, 0), radius=RADIUS)
    trajectory = physics.simulate(world, 3.0)
    assert np.abs(trajectory.velocities[-1]).max() < 1e-3
    heights = trajectory.positions[-1, :, 1]
    assert heights == pytest.approx([RADIUS, 3 * RADIUS, 5 * RADIUS], abs=1e-3)
    assert trajectory.energy.max() <= trajectory.energy[0] + 1e-9
