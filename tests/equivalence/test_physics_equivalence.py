"""The GPU physics step (gpu_shader.physics) against the CPU ground truth, trajectory by trajectory.

Scenes without chaotic multi-body contact (balls bouncing with e = 0, 0.5, 0.9 and 1, a head-on
pair, a ball sliding into rolling) are run for 5 s on the GPU in float32 and on the CPU in
float32 and float64, all with the "simultaneous" solver, and must agree to 1e-4 m at every
recorded step, with their contact events at the same steps. The bodies of these scenes are
far apart, so they share one world and one run per backend.

A break (15 balls in a triangle struck by a cue ball) is chaotic: a rounding difference grows
until the balls take different paths. There the suite reports when the GPU and CPU runs first
differ by more than one radius, and checks what must hold whatever the path: horizontal
momentum kept on a frictionless floor, energy never rising, everything at rest at the end.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from marchlab.simulation import simulate
import physics
from required_backends import need_backend

DT = 1 / 120                   # 5 s with half the steps of the default 1/240
RADIUS = 0.1
RESTITUTIONS = (0.0, 0.5, 0.9, 1.0)


@pytest.fixture(autouse=True)
def _needs_gpu():
    need_backend("gpu")


def quiet_scenes(dtype, integrator="semi_implicit") -> physics.World:
    """Bouncing balls (bodies 0-3), a head-on pair (4, 5) and a sliding ball (6), 2 m apart."""
    world = physics.World(dt=DT, solver="simultaneous", integrator=integrator, dtype=dtype)
    world.add_plane((0, 1, 0), 0, restitution=0.0, friction=0.3)
    for k, e in enumerate(RESTITUTIONS):
        world.add_sphere((2.0 * k, 1.0, 0), radius=RADIUS, restitution=e, friction=0.3)
    # the pair floats (no floor under z = 10 is touched: they start 1 m up and collide at
    # t = 0.1 s, long before they land) and meets head-on at 2 m/s each
    world.add_sphere((0.0, 1.0, 10.0), velocity=(2, 0, 0), radius=RADIUS, restitution=0.8,
                     mass=1.0)
    world.add_sphere((0.6, 1.0, 10.0), velocity=(-2, 0, 0), radius=RADIUS, restitution=0.8,
                     mass=2.0)
    # slides at v0 = 5 m/s with mu = sqrt(0.3 * 0.3) = 0.3 and no spin: rolls from 0.485 s
    world.add_sphere((0.0, RADIUS, -10.0), velocity=(5, 0, 0), radius=RADIUS, friction=0.3)
    return world


QUIET_GROUPS = {"bouncing": [0, 1, 2, 3], "head_on_pair": [4, 5], "sliding_to_rolling": [6]}


@functools.cache
def quiet_runs():
    """(GPU float32, CPU float32, CPU float64) trajectories of `quiet_scenes` over 5 s."""
    gpu = simulate(quiet_scenes("float32"), 5.0, record_every=4, backend="gpu")
    cpu32 = physics.simulate(quiet_scenes("float32"), 5.0, record_every=4)
    cpu64 = physics.simulate(quiet_scenes("float64"), 5.0, record_every=4)
    return gpu, cpu32, cpu64


def contact_steps(events, bodies) -> list:
    """(step, kind, body, other) of the contact events that involve ``bodies``, in order."""
    keep = np.isin(events["body"], bodies)
    return [(int(e["step"]), str(e["kind"]), int(e["body"]), int(e["other"]))
            for e in events[keep]]


@pytest.mark.parametrize("reference", ["float32", "float64"])
@pytest.mark.parametrize("group", list(QUIET_GROUPS))
def test_gpu_positions_match_cpu_within_1e_4_m_over_5_s(group, reference):
    gpu, cpu32, cpu64 = quiet_runs()
    cpu = cpu32 if reference == "float32" else cpu64
    bodies = QUIET_GROUPS[group]
    assert gpu.times[-1] == pytest.approx(5.0)
    np.testing.assert_array_equal(gpu.steps, cpu.steps)
    error = np.abs(gpu.positions[:, bodies].astype(np.float64) - cpu.positions[:, bodies])
    worst = error.max(axis=(1, 2))
    assert worst.max() <= 1e-4, (f"{group}: GPU and CPU {reference} differ by "
                                 f"{worst.max():.3g} m at t = {gpu.times[worst.argmax()]:.3f} s")


@pytest.mark.parametrize("group", ["bouncing", "head_on_pair"])   # sliding: resting contact only
def test_gpu_contact_events_at_the_same_steps_as_cpu(group):
    gpu, cpu32, cpu64 = quiet_runs()
    bodies = QUIET_GROUPS[group]
    expected = contact_steps(cpu32.events, bodies)
    assert expected, "the scene must have contacts for this test to mean anything"
    assert contact_steps(gpu.events, bodies) == expected
    # and float64 sees the same collisions at the same steps
    assert contact_steps(cpu64.events, bodies) == expected


def test_gpu_sliding_ball_ends_rolling_at_five_sevenths_of_v0_within_1e_5():
    gpu, _, _ = quiet_runs()
    speed = gpu.velocities[-1, 6, 0]
    spin = gpu.angular_velocities[-1, 6, 2]
    assert speed == pytest.approx(5 / 7 * 5.0, abs=1e-5)
    assert -spin * RADIUS == pytest.approx(speed, abs=1e-5)      # rolling: v = -w_z r


@pytest.mark.parametrize("integrator", list(physics.INTEGRATORS))
def test_gpu_free_fall_and_bounce_matches_cpu_within_1e_4_m_for_each_integrator(integrator):
    def ball():
        world = physics.World(dt=1 / 240, solver="simultaneous", integrator=integrator,
                              dtype="float32")
        world.add_plane((0, 1, 0), 0)
        world.add_sphere((0, 1.0, 0), radius=RADIUS, restitution=0.5)
        return world
    gpu = simulate(ball(), 1.5, record_every=2, backend="gpu")
    cpu = physics.simulate(ball(), 1.5, record_every=2)
    assert np.abs(gpu.positions - cpu.positions).max() <= 1e-4
    assert contact_steps(gpu.events, [0]) == contact_steps(cpu.events, [0])
    # the free-fall part follows the integrator's own closed form (integrators.py), in float32
    t = gpu.times[gpu.times < 0.3]
    offset = {"explicit": +0.5, "semi_implicit": -0.5, "verlet": 0.0}[integrator]
    exact = 1.0 - 0.5 * 9.81 * t * t + offset * 9.81 * (1 / 240) * t
    assert np.abs(gpu.positions[: len(t), 0, 1] - exact).max() <= 1e-5


# --- the chaotic break ---------------------------------------------------------------------

BREAK_SECONDS = 6.0


def pool_break(dtype) -> physics.World:
    """15 balls racked in a triangle on a frictionless floor (ball-ball friction only), struck
    head-on by a cue ball at 6 m/s. No walls: the balls roll away and are stopped by nothing
    but the ground contact, so horizontal momentum must be conserved."""
    world = physics.World(dt=DT, solver="simultaneous", dtype=dtype, seed=1)
    world.add_plane((0, 1, 0), 0, restitution=0.0, friction=0.0)
    r = 0.0286                                         # a pool ball (m)
    rack = []
    for row in range(5):
        for k in range(row + 1):
            rack.append((row * r * np.sqrt(3), r, (k - row / 2) * 2 * r))
    world.add_spheres(np.array(rack) + [1.0, 0, 0], radius=r, mass=0.17, restitution=0.9,
                      friction=0.1)
    world.add_sphere((0.0, r, 0.001), velocity=(6.0, 0, 0), radius=r, mass=0.17,
                     restitution=0.9, friction=0.1)
    return world


@functools.cache
def break_runs():
    gpu = simulate(pool_break("float32"), BREAK_SECONDS, record_every=1, backend="gpu")
    cpu = physics.simulate(pool_break("float32"), BREAK_SECONDS, record_every=1)
    cpu64 = physics.simulate(pool_break("float64"), BREAK_SECONDS, record_every=1)
    return gpu, cpu, cpu64


@pytest.mark.parametrize("reference", ["float32", "float64"])
def test_break_reports_when_gpu_and_cpu_first_differ_by_one_radius(reference, capsys):
    gpu, cpu32, cpu64 = break_runs()
    cpu = cpu32 if reference == "float32" else cpu64
    radius = 0.0286
    apart = np.sqrt(np.sum((gpu.positions - cpu.positions) ** 2, axis=2)).max(axis=1)
    beyond = np.flatnonzero(apart > radius)
    moment = gpu.times[beyond[0]] if len(beyond) else np.inf
    with capsys.disabled():
        print(f"\n[break] GPU float32 vs CPU {reference}: first differ by more than one radius "
              f"at t = {moment:.4f} s (never: inf); largest gap {apart.max():.3g} m over "
              f"{BREAK_SECONDS} s")
    # they must at least agree until the cue ball has struck the rack (t ~ 0.15 s) and the
    # first ball has left it
    assert moment > 0.3


def test_break_on_gpu_keeps_horizontal_momentum_within_1e_4_relative():
    gpu, _, _ = break_runs()
    assert gpu.active.all()
    horizontal = gpu.momentum[:, [0, 2]]
    start = 0.17 * 6.0
    assert np.abs(horizontal - horizontal[0]).max() <= 1e-4 * start


def test_break_on_gpu_energy_never_rises_by_more_than_1e_3_j_a_step():
    # 1e-3 J is 2.6e-4 of the 3.8 J of the break. While the rack settles (t < 0.15 s) the
    # Jacobi resting passes leave its energy swinging by +-6e-4 J from step to step: the CPU
    # does the same in float64, so it is the solver's, not the GPU's.
    gpu, _, _ = break_runs()
    rise = np.diff(gpu.energy)
    assert rise.max() <= 1e-3, (f"energy rose by {rise.max():.3g} J at "
                                f"t = {gpu.times[rise.argmax() + 1]:.3f} s")
    assert gpu.energy[-1] < 0.5 * gpu.energy[0]        # the collisions did take energy


def test_break_on_gpu_vertical_motion_at_rest_by_the_end():
    # frictionless floor: balls keep rolling, but every bounce off the floor has died out
    gpu, _, _ = break_runs()
    assert np.abs(gpu.velocities[-1, :, 1]).max() <= 1e-3
    assert np.abs(gpu.positions[-1, :, 1] - 0.0286).max() <= 1e-3
