"""Live playback (marchlab/playback.py): the fixed-dt world stepped by a clock of frames, and
what a viewer's buttons, sliders and mouse do to it, checked without a window.

Hand-built scenes use dt = 1/256 s and frames of 1/64 s, both exact in binary, so a frame is
exactly 4 steps and step counts can be compared with ==. The bundled `bounce` scene (six
bodies over a floor, dt = 1/240 s) is used where contacts must happen.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from required_backends import need_backend

import physics
from marchlab import MarchlabError, load_scene
from marchlab.playback import Playback
from marchlab.simulation import build_world
from scene_model.bodies import Body, PhysicsSettings
from scene_model.builder import Material, Scene, plane

DT = 1 / 256                      # s: exact in binary
FRAME = 1 / 64                    # s: exactly 4 steps
G = 9.81
IRREGULAR_FRAMES = (0.013, 0.021, 0.0007, 0.034, 0.0166, 0.002, 0.05, 0.009)


def make_scene(*bodies: Body, floor: bool = False, **settings) -> Scene:
    settings = {"dt": DT, **settings}
    return Scene(materials={"default": Material()}, objects=(plane(),) if floor else (),
                 physics=PhysicsSettings(**settings), bodies=bodies)


def with_physics(scene: Scene, **settings) -> Scene:
    return dataclasses.replace(scene, physics=dataclasses.replace(scene.physics, **settings))


def state(world: physics.World) -> tuple[np.ndarray, ...]:
    return world.position, world.velocity, world.angular_velocity, world.orientation


def assert_same_state(a: physics.World, b: physics.World) -> None:
    for x, y in zip(state(a), state(b)):
        np.testing.assert_array_equal(x, y)


@pytest.fixture(scope="module")
def bounce() -> Scene:
    return load_scene("bounce")


# --- The clock -----------------------------------------------------------------------------------

def test_irregular_frames_give_bit_identical_states_to_the_same_number_of_steps(bounce):
    playback = Playback(bounce)
    playback.play()
    for frame in IRREGULAR_FRAMES * 6:                   # 0.95 s: balls bounce and collide
        playback.advance(frame)
    reference = build_world(bounce)
    reference.step(playback.steps)
    assert 0 <= sum(IRREGULAR_FRAMES * 6) - playback.time < reference.dt   # only a remainder left
    assert len(reference.events) > 0                     # contacts: the test has teeth
    assert_same_state(playback.world, reference)
    assert playback.time == reference.time


def test_time_scale_2_takes_twice_the_steps_for_the_same_frames():
    scene = make_scene(Body(position=(0, 5, 0)))
    normal, fast = Playback(scene), Playback(scene)
    fast.time_scale = 2
    for playback in (normal, fast):
        playback.play()
        taken = [playback.advance(FRAME) for _ in range(10)]
        assert taken == [4 * playback.time_scale] * 10
    assert fast.steps == 2 * normal.steps == 80


def test_paused_advance_takes_no_step_and_step_takes_exactly_one():
    playback = Playback(make_scene(Body(position=(0, 5, 0))))
    assert not playback.playing                          # starts paused
    assert playback.advance(1.0) == 0 and playback.steps == 0
    playback.step()
    assert playback.steps == 1 and playback.time == DT
    assert playback.advance(1.0) == 0 and playback.steps == 1   # time did not pile up
    playback.play()
    assert playback.advance(FRAME) == 4


def test_per_frame_cap_holds_and_the_dropped_time_is_counted_exactly():
    playback = Playback(make_scene(Body(position=(0, 5, 0))), max_steps_per_frame=5)
    playback.play()
    assert playback.advance(1.0) == 5                    # 256 steps fit, 5 taken
    assert playback.dropped_seconds == 251 * DT
    assert playback.advance(2 * DT) == 2                 # nothing left over from the stall
    assert playback.dropped_seconds == 251 * DT


def test_time_scale_outside_its_range_is_refused_in_one_line():
    playback = Playback(make_scene(Body()))
    with pytest.raises(MarchlabError, match="time_scale must be between 0.1 and 4"):
        playback.time_scale = 10
    assert playback.time_scale == 1


def test_blended_positions_lag_the_clock_by_one_step_exactly_in_uniform_motion():
    # Fiedler's final touch: between the last two states by alpha, the accumulator's remainder.
    playback = Playback(make_scene(Body(position=(0, 0, 0), velocity=(1, 0, 0)),
                                   gravity=(0, 0, 0)))
    playback.play()
    assert playback.advance(FRAME + DT / 2) == 4 and playback.alpha == 0.5
    assert playback.positions()[0, 0] == pytest.approx(4 * DT, abs=1e-15)
    assert playback.positions(blend=True)[0, 0] == pytest.approx(3.5 * DT, abs=1e-15)


def test_reset_returns_exactly_the_initial_state_settings_and_time_0(bounce):
    playback = Playback(bounce)
    playback.play()
    playback.set_gravity((1.0, -3.0, 0.0))
    playback.set_restitution(0.2)
    playback.kick(50.0, seed=1)
    playback.grab(2)
    playback.drag_to((0.0, 3.0, 0.0))
    for _ in range(20):
        playback.advance(1 / 60)
    playback.reset()
    assert_same_state(playback.world, build_world(bounce))
    assert playback.time == 0 and playback.steps == 0 and playback.dropped_seconds == 0
    assert playback.settings == bounce.physics
    np.testing.assert_array_equal(playback.world.restitution, build_world(bounce).restitution)
    np.testing.assert_array_equal(playback.world.gravity, bounce.physics.gravity)
    assert len(playback.history) == 1


# --- Kick ----------------------------------------------------------------------------------------

def floating_balls() -> Scene:
    """Three balls of different masses far apart, without gravity: nothing touches."""
    return make_scene(Body(position=(-3, 0, 0), mass=1.0), Body(position=(0, 0, 0), mass=2.5),
                      Body(position=(3, 0, 0), mass=0.4), gravity=(0, 0, 0))


def test_kick_with_the_same_seed_is_reproducible_and_another_seed_differs():
    a, b, c = (Playback(floating_balls()) for _ in range(3))
    a.kick(2.0, seed=7)
    b.kick(2.0, seed=7)
    c.kick(2.0, seed=8)
    np.testing.assert_array_equal(a.world.velocity, b.world.velocity)
    assert not np.array_equal(a.world.velocity, c.world.velocity)


def test_kick_changes_momentum_by_the_sum_of_impulses_within_1e_12():
    playback = Playback(floating_balls())
    before = playback.momentum()
    impulses = playback.kick(2.0, seed=3)
    np.testing.assert_allclose(np.linalg.norm(impulses, axis=1), 2.0, rtol=1e-12)
    np.testing.assert_allclose(playback.momentum() - before, impulses.sum(axis=0), atol=1e-12)
    playback.play()
    playback.advance(0.5)                                # free flight: momentum is kept
    np.testing.assert_allclose(playback.momentum() - before, impulses.sum(axis=0), atol=1e-12)


# --- Energy and momentum -------------------------------------------------------------------------

def test_energy_never_increases_with_restitution_at_most_1_within_1e_12_relative(bounce):
    """Every ball of `bounce` bounces (e up to 1) and two collide head on, over 1.2 s.

    With velocity Verlet, exact in free fall, the energy may only fall. (Semi-implicit Euler
    loses g^2 h t / 2 per kg in flight, integrators.py, and a bounce puts the ball back on its
    exact parabola, so its energy rises there, but never above where it started.)
    """
    playback = Playback(with_physics(bounce, integrator="verlet"))
    playback.play()
    for _ in range(72):
        playback.advance(1 / 60)
    energy = playback.history[:, 1]
    assert len(energy) == 73
    assert np.diff(energy).max() <= 1e-12 * energy[0]
    assert energy[-1] < 0.9 * energy[0]                  # the bounces lost energy: teeth


def test_energy_of_a_falling_ball_is_m_g_h_plus_half_m_v2_within_1e_9_relative():
    # Semi-implicit Euler from rest: y_n = y0 - g t^2 / 2 - g h t / 2, v_n = -g t (integrators.py)
    y0 = 10.0
    playback = Playback(make_scene(Body(position=(0, y0, 0), radius=0.2), gravity=(0, -G, 0)))
    mass = float(playback.world.mass[0])
    for _ in range(128):
        playback.step()
    t = playback.time
    y = y0 - G * t * t / 2 - G * DT * t / 2
    v = -G * t
    assert playback.energy() == pytest.approx(mass * G * y + mass * v * v / 2, rel=1e-9)
    # ... which is m g y0 less the scheme's known drift, m g^2 h t / 2
    assert playback.energy() == pytest.approx(mass * G * y0 - mass * G * G * DT * t / 2, rel=1e-9)
    np.testing.assert_allclose(playback.momentum(), [0, mass * v, 0], rtol=1e-9)


def test_history_keeps_the_last_samples_only():
    playback = Playback(make_scene(Body(position=(0, 5, 0))), history=50)
    for _ in range(60):
        playback.step()
    history = playback.history
    assert history.shape == (50, 3)
    assert history[-1, 0] == playback.time and history[0, 0] == 11 * DT


# --- Sliders -------------------------------------------------------------------------------------

def apex_after_next_bounce(playback: Playback) -> float:
    """Step through the next bounce to the top of the flight after it; the centre's height."""
    while playback.world.velocity[0, 1] <= 0:            # down to the floor and off it
        playback.step()
    while playback.world.velocity[0, 1] > 0:             # up to the top
        playback.step()
    return float(playback.world.position[0, 1])


def test_new_restitution_keeps_the_state_and_the_next_bounce_rises_e2_squared_within_1_percent():
    """A ball dropped 1 m onto a floor rises to e^2 h; e is changed at the top of a flight."""
    radius, h0 = 0.1, 1.0
    playback = Playback(make_scene(Body(position=(0, radius + h0, 0), radius=radius),
                                   floor=True, restitution=0.8, integrator="verlet"))
    h1 = apex_after_next_bounce(playback) - radius
    assert h1 == pytest.approx(0.8 ** 2 * h0, rel=0.01)
    before = [array.copy() for array in state(playback.world)]
    playback.set_restitution(0.5)
    for x, y in zip(before, state(playback.world)):
        np.testing.assert_array_equal(x, y)              # the state is untouched
    h2 = apex_after_next_bounce(playback) - radius
    assert h2 == pytest.approx(0.5 ** 2 * h1, rel=0.01)


def test_settings_refused_with_the_scene_files_ranges_and_paths():
    playback = Playback(make_scene(Body()))
    with pytest.raises(MarchlabError, match=r"physics\.restitution: must be between 0 and 1"):
        playback.set_restitution(1.5)
    with pytest.raises(MarchlabError, match=r"physics\.gravity\[1\]"):
        playback.set_gravity((0, -5000, 0))
    with pytest.raises(MarchlabError, match=r"physics\.friction"):
        playback.set_friction(-1)


def test_set_gravity_to_zero_stops_the_fall_but_keeps_the_velocity():
    playback = Playback(make_scene(Body(position=(0, 5, 0))))
    for _ in range(8):
        playback.step()
    velocity = playback.world.velocity.copy()
    playback.set_gravity((0, 0, 0))
    for _ in range(8):
        playback.step()
    np.testing.assert_array_equal(playback.world.velocity, velocity)


# --- The mouse -----------------------------------------------------------------------------------

def test_a_released_ball_flies_with_the_drags_last_velocity_within_1e_12():
    playback = Playback(make_scene(Body(position=(0, 2, 0)), floor=True))
    playback.play()
    playback.grab(0)
    first, second = np.array([0.0, 2.5, 0.0]), np.array([0.3, 2.6, -0.1])
    playback.drag_to(first)
    playback.advance(FRAME)
    np.testing.assert_array_equal(playback.positions()[0], first)     # held: no falling
    playback.drag_to(second)
    playback.advance(FRAME)
    playback.release()
    drag_velocity = (second - first) / FRAME
    np.testing.assert_allclose(playback.world.velocity[0], drag_velocity, rtol=0, atol=1e-12)
    playback.step()                                      # then it is thrown, under gravity
    np.testing.assert_allclose(playback.world.velocity[0], drag_velocity + (0, -G * DT, 0),
                               rtol=0, atol=1e-12)


def test_a_ball_dragged_while_paused_is_placed_at_rest():
    playback = Playback(make_scene(Body(position=(0, 2, 0), velocity=(1, 0, 0))))
    playback.grab(0)
    playback.drag_to((1.0, 3.0, 0.0))
    np.testing.assert_array_equal(playback.positions()[0], [1.0, 3.0, 0.0])
    np.testing.assert_array_equal(playback.world.velocity[0], [0.0, 0.0, 0.0])


def test_pick_returns_the_nearest_ball_along_the_ray_or_none():
    playback = Playback(make_scene(Body(position=(0, 0, 0), radius=1.0),
                                   Body(position=(0, 0, 3), radius=0.3),
                                   Body(position=(0, 0, -3), radius=0.5)))
    eye = (0.0, 0.0, 10.0)
    assert playback.pick(eye, (0, 0, -1)) == 1
    assert playback.pick((0.0, 0.0, 2.0), (0, 0, -1)) == 0           # past ball 1
    assert playback.pick((0.0, 0.0, -3.0), (0, 0, 1)) == 2           # from inside ball 2
    assert playback.pick(eye, (0, 0, 1)) is None                      # looking away
    assert playback.pick(eye, (0.2, 0, -1)) is None                   # passing beside them all


def test_pick_goes_by_where_the_ray_meets_a_surface_not_by_the_nearest_centre():
    # Seen from the origin along +z, ball 0's centre is nearer (10.04 m vs 10.12 m), but the
    # ray enters big ball 1 at z = 8.48 and ball 0 only at z = 9.56. The balls do not touch.
    playback = Playback(make_scene(Body(position=(0.9, 0, 10), radius=1.0),
                                   Body(position=(-4.99, 0, 8.8), radius=5.0)))
    assert playback.pick((0, 0, 0), (0, 0, 1)) == 1


# --- The GPU stepper -----------------------------------------------------------------------------

def test_gpu_playback_follows_the_cpu_within_1e_4_m_and_sees_kicks_and_sliders():
    need_backend("gpu")
    scene = make_scene(Body(position=(0, 1, 0)), Body(position=(2, 1, 0), restitution=0.9),
                       floor=True, solver="simultaneous")
    gpu, cpu = Playback(scene, "gpu"), Playback(scene)
    for playback in (gpu, cpu):
        playback.play()
        for frame in IRREGULAR_FRAMES * 3:               # 0.46 s: both balls bounce
            playback.advance(frame)
        playback.set_gravity((0.0, 0.0, 0.0))            # each sent to the shader before it steps
        playback.set_restitution(1.0)
        playback.kick(30.0, seed=5)
        playback.grab(1)
        playback.drag_to((2.0, 1.5, 0.0))
        for frame in IRREGULAR_FRAMES:
            playback.advance(frame)
    assert gpu.steps == cpu.steps
    assert len(cpu.world.events) > 0
    assert np.abs(gpu.positions() - cpu.positions()).max() <= 1e-4
    assert np.abs(gpu.world.velocity - cpu.world.velocity).max() <= 1e-4


def test_gpu_backend_refuses_the_sequential_solver_in_one_line(bounce):
    need_backend("gpu")
    with pytest.raises(MarchlabError, match='"simultaneous" solver only') as error:
        Playback(bounce, "gpu")
    assert "\n" not in str(error.value)
