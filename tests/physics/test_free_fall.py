"""Free fall, where each integrator has an exact closed form for its own discrete trajectory.

Summing the steps (physics/integrators.py) gives, with g = 9.81 and t_n = n h:

    explicit Euler        y_n = y0 + v0 t_n - g t_n^2 / 2 + g h t_n / 2
    semi-implicit Euler   y_n = y0 + v0 t_n - g t_n^2 / 2 - g h t_n / 2
    velocity Verlet       y_n = y0 + v0 t_n - g t_n^2 / 2

and v_n = v0 - g t_n for all three. The simulated values must match to 1e-12 (relative to the
size of the numbers involved: only rounding separates them). The energy per unit mass then
drifts by exactly +g^2 h t / 2 (explicit: gains), -g^2 h t / 2 (semi-implicit: loses) and 0
(Verlet), checked to 1e-9 J/kg.
"""

import numpy as np
import pytest

import physics

G = 9.81
H = 1 / 240
Y0, V0, VX = 50.0, 3.0, 1.5
SECONDS = 2.0

CLOSED_FORM_OFFSET = {"explicit": +0.5, "semi_implicit": -0.5, "verlet": 0.0}   # x g h t_n
ENERGY_DRIFT = {"explicit": +0.5, "semi_implicit": -0.5, "verlet": 0.0}         # x g^2 h t_n


def falling_ball(integrator):
    world = physics.World(dt=H, integrator=integrator)
    world.add_sphere((0.0, Y0, 0.0), velocity=(VX, V0, 0.0), radius=0.1, mass=2.0)
    return physics.simulate(world, SECONDS)


@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_free_fall_matches_each_integrators_closed_form_within_1e_12(integrator):
    trajectory = falling_ball(integrator)
    t = trajectory.steps * H
    y = trajectory.positions[:, 0, 1]
    expected = Y0 + V0 * t - 0.5 * G * t * t + CLOSED_FORM_OFFSET[integrator] * G * H * t
    scale = np.max(np.abs(expected))
    assert np.max(np.abs(y - expected)) <= 1e-12 * scale
    assert np.max(np.abs(trajectory.velocities[:, 0, 1] - (V0 - G * t))) <= 1e-12 * G * SECONDS
    # Horizontal motion is uniform in every scheme.
    assert np.max(np.abs(trajectory.positions[:, 0, 0] - VX * t)) <= 1e-12 * VX * SECONDS


@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_free_fall_energy_drift_is_plus_or_minus_half_g2_h_t_within_1e_9(integrator):
    trajectory = falling_ball(integrator)
    t = trajectory.steps * H
    drift_per_kg = (trajectory.energy - trajectory.energy[0]) / 2.0
    expected = ENERGY_DRIFT[integrator] * G * G * H * t
    assert np.max(np.abs(drift_per_kg - expected)) <= 1e-9


def test_explicit_euler_gains_and_semi_implicit_loses_energy():
    explicit = falling_ball("explicit").energy
    semi = falling_ball("semi_implicit").energy
    # +-g^2 h t / 2 per kg over 2 s with m = 2 kg is 0.80 J either way.
    assert explicit[-1] - explicit[0] > 0.75 and semi[-1] - semi[0] < -0.75
