"""A ball dropped on the floor: bounce heights, time to rest, e = 0 and e = 1, tunnelling.

A ball dropped from h0 (its lowest point h0 above the floor) hits the floor at v0 = sqrt(2 g h0)
and leaves at e v0, so the n-th apex is h_n = e^(2n) h0. Each flight lasts twice as long as the
one before it times e, and the total time until the bounces die out is the geometric series

    T = t0 + 2 t0 (e + e^2 + ...) = t0 (1 + e) / (1 - e),   t0 = sqrt(2 h0 / g),

1.3546 s for h0 = 1 m, e = 0.5. Checked within 1% while the bounce speed is much larger than
g dt (the restitution threshold, 0.01 m/s by default, ends the series early: the tail it cuts
off is under 2 x 0.01 / (g (1 - e)) = 0.004 s).
"""

import numpy as np
import pytest

import physics

G = 9.81
RADIUS = 0.1


def drop(height, restitution, seconds, integrator="semi_implicit", dt=1 / 240, **settings):
    """A ball whose lowest point starts ``height`` above the floor y = 0, and its trajectory."""
    world = physics.World(dt=dt, integrator=integrator, **settings)
    world.add_plane((0, 1, 0), 0)
    world.add_sphere((0, RADIUS + height, 0), radius=RADIUS, restitution=restitution)
    return physics.simulate(world, seconds)


def apexes(trajectory):
    """Heights of the ball's lowest point at each recorded top of a flight (m)."""
    y = trajectory.positions[:, 0, 1] - RADIUS
    vy = trajectory.velocities[:, 0, 1]
    top = (vy[:-1] > 0) & (vy[1:] <= 0)
    return np.maximum(y[:-1][top], y[1:][top])


def test_bounce_apexes_are_e_to_the_2n_times_h0_within_1_percent():
    trajectory = drop(1.0, 0.5, 1.3)
    heights = apexes(trajectory)[:3]            # bounce speeds 2.2, 1.1, 0.55 m/s >> g dt
    assert np.allclose(heights, [0.25, 0.0625, 0.015625], rtol=0.01, atol=0)


def test_bounce_time_to_rest_is_t0_1_plus_e_over_1_minus_e_within_1_percent():
    trajectory = drop(1.0, 0.5, 2.0)
    t0 = np.sqrt(2 * 1.0 / G)
    expected = t0 * (1 + 0.5) / (1 - 0.5)
    assert expected == pytest.approx(1.3546, abs=1e-4)
    moving = np.flatnonzero(np.abs(trajectory.velocities[:, 0, 1]) > 0)
    at_rest = trajectory.times[moving[-1] + 1]
    assert at_rest == pytest.approx(expected, rel=0.01)
    assert trajectory.positions[-1, 0, 1] == pytest.approx(RADIUS, abs=1e-9)


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_restitution_zero_stops_on_first_contact_and_stays_within_1e_9(integrator, solver):
    trajectory = drop(1.0, 0.0, 2.0, integrator=integrator, solver=solver)
    vy = trajectory.velocities[:, 0, 1]
    y = trajectory.positions[:, 0, 1]
    assert np.all(vy <= 0), "never moves up: no bounce at all"
    assert len(trajectory.events) == 1 and trajectory.events["kind"][0] == "sphere-plane"
    landed = trajectory.steps >= trajectory.events["step"][0]
    assert np.all(np.abs(y[landed] - RADIUS) <= 1e-9)
    assert np.all(np.abs(vy[landed]) <= 1e-9)
    assert np.all(y >= RADIUS - 1e-9), "never sinks into the floor"


@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_restitution_one_keeps_apex_within_half_a_percent_over_20_bounces(integrator):
    flight = 2 * np.sqrt(2 * 1.0 / G)
    trajectory = drop(1.0, 1.0, 20.5 * flight, integrator=integrator)
    heights = apexes(trajectory)
    assert len(heights) >= 20
    assert np.all(np.abs(heights[:20] / 1.0 - 1) <= 0.005)


@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_sphere_at_200_m_per_s_with_dt_1_60_bounces_off_the_floor(integrator):
    world = physics.World(dt=1 / 60, integrator=integrator)
    world.add_plane((0, 1, 0), 0)
    world.add_sphere((0, 10, 0), velocity=(0, -200, 0), radius=RADIUS, restitution=0.5)
    trajectory = physics.simulate(world, 0.5)
    # 3.3 m per step, against a 0.1 m ball: without continuous collision it would pass through.
    assert trajectory.positions[:, 0, 1].min() >= RADIUS - 1e-9
    bounce = trajectory.events[0]
    assert bounce["kind"] == "sphere-plane" and bounce["speed"] == pytest.approx(200, rel=0.01)
    # It leaves at e times its arrival speed (a recorded velocity may lag by up to one g dt).
    assert abs(trajectory.velocities[:, 0, 1].max() - 0.5 * bounce["speed"]) <= G / 60
