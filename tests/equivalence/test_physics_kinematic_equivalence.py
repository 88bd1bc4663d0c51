"""The GPU physics step against the CPU with kinematic objects: walls, platforms, a paddle and
a turntable moved by a `scene_model.motion.Motion`, constant or keyframed.

Every scene is one of tests/test_kinematic.py's or tests/test_keyframed_motion.py's, made
with the "simultaneous" solver and `marchlab.simulation.build_world` in float32 (so that the
CPU's shapes, too, are the float32 SDF with the float32 normal step), then stepped
by the CPU (`physics.World.step`, which places each moving shape with ``Shape.at(time)`` at
the start of a step) and by the GPU (`gpu_shader.physics.GpuStepper`, which writes the pose
into the shader's parameter block before each step). The GPU's positions must agree with the
CPU's within TOLERANCE at every recorded step, its contact events must be the CPU's (kind,
step, body and shape, in order), and the closed forms of the CPU tests must hold on the GPU.

The CPU applies a pose in float64 and rounds the point it gives; the GPU rounds the pose to
float32 and applies it in float32, so the two need not agree bit for bit. Measured on
llvmpipe (Mesa 22.3, LLVM 15), largest position difference over the run: 0 m for the walls
struck by a sinusoidal or keyframed motion, the paddle and the keyframed rising platform,
6.0e-8 m for the platform moving up and down (3 s) and for the balls dropped onto it, 8.6e-7
m for the turntable (6 s; 2.8e-6 m over the CPU test's 12 s). On an NVIDIA H200 (driver 580)
the same, but 1.2e-7 m for the ball dropped at e = 0 and 1.35e-6 m for the turntable.
TOLERANCE is the plane and shape suites' 1e-4 m, which also leaves room for a GPU whose sqrt
and fused products round differently.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from gpu_shader.physics import world_shape_code
from gpu_shader.physics_shapes import pose_rows
import physics
from marchlab.colliders import primitive_coefficients, shape_objects
from marchlab.simulation import build_world, simulate
from required_backends import need_backend
from scene_model.builder import (Body, Material, PhysicsSettings, Scene, box, capped_cylinder,
                                 plane)
from scene_model.motion import Motion, motion_pose

from .conftest import contact_steps, evaluate_shape_code, position_difference

TOLERANCE = 1e-4               # m, at every recorded step
G = 9.81
SIMULTANEOUS = dict(solver="simultaneous")


@pytest.fixture(autouse=True)
def _needs_gpu():
    need_backend("gpu")


def struck_wall(e: float, motion: Motion) -> Scene:
    """No gravity, no friction: the wall box(0.1, 1, 1) touches a resting ball (r = 0.1) at
    x = 0.2 when ``motion`` sets off."""
    return Scene(materials={"default": Material(),
                            "wall": Material(restitution=e, friction=0.0)},
                 objects=(box(0.1, 1, 1, material="wall"),), motions=(motion,),
                 physics=PhysicsSettings(gravity=(0, 0, 0), **SIMULTANEOUS),
                 bodies=(Body(position=(0.2, 0, 0), radius=0.1, restitution=0.0,
                              friction=0.0),))


def platform(motion: Motion, height: float = 0.6, restitution: float = 0.0) -> Scene:
    """A ball (r = 0.1) at ``height`` above a box whose top (y = 0.5) ``motion`` moves: resting
    on it at 0.6."""
    return Scene(materials={"default": Material()}, objects=(box(1, 0.1, 1).at(0, 0.4, 0),),
                 motions=(motion,),
                 physics=PhysicsSettings(restitution=restitution,
                                         plane_restitution=restitution, **SIMULTANEOUS),
                 bodies=(Body(position=(0.2, height, 0.1), radius=0.1,
                              restitution=restitution),))


SINE_SPEED = 0.2 * 2 * math.pi           # m/s: the sinusoidal wall's speed at t = 0
KEYED_SPEED = 2.0                        # m/s: the keyframed wall, 0.5 m in 0.25 s
RISE = 0.3                               # m/s: the keyframed platform, 0.3 m in 1 s
TURNTABLE_RATE = math.radians(60.0)      # rad/s
# The paddle: 2 m long, 10 cm thick, turning at 90 degrees/s about the vertical axis through
# its middle; the ball's centre is (0.7, -0.3) from that axis.
PADDLE = box(1.0, 0.1, 0.05, material="paddle").at(0, 0.1, 0)

CASES = {
    # a wall moving as 0.2 sin(2 pi t) strikes a resting ball (0.1 s)
    **{f"sine_wall_e_{e}": (struck_wall(e, Motion(object=0, amplitude=(0.2, 0, 0),
                                                  period=1.0)), 0.1, 1)
       for e in (0.0, 0.5, 1.0)},
    # a wall keyframed at a constant 2 m/s strikes a resting ball (0.2 s)
    **{f"keyframed_wall_e_{e}": (struck_wall(e, Motion(object=0, times=(0.0, 0.25),
                                                       offsets=((0, 0, 0), (0.5, 0, 0)))),
                                 0.2, 1)
       for e in (0.5, 1.0)},
    # a platform moving up and down as 0.05 sin(2 pi t), a ball riding it (3 s)
    "platform_up_and_down": (platform(Motion(object=0, amplitude=(0, 0.05, 0), period=1.0)),
                             3.0, 1),
    # a ball dropped from 0.7 m above it onto that platform: each bounce (e = 0.5), or the
    # landing (e = 0), is met by the continuous test, on the platform where it is at the
    # start of the step (2 s)
    **{f"ball_dropped_on_platform_up_and_down_e_{e}": (
        platform(Motion(object=0, amplitude=(0, 0.05, 0), period=1.0), 1.3, e), 2.0, 1)
       for e in (0.0, 0.5)},
    # a platform keyframed to rise 0.3 m between t = 0.5 and 1.5 s, then stop (2.5 s)
    "keyframed_rising_platform": (platform(Motion(object=0, times=(0.5, 1.5),
                                                  offsets=((0, 0, 0), (0, RISE, 0)))),
                                  2.5, 1),
    # a paddle turning about y sweeps a ball lying in its way, on a floor (1 s)
    "turning_paddle": (Scene(materials={"default": Material(friction=0.0),
                                        "paddle": Material(restitution=1.0, friction=0.0)},
                             objects=(plane(), PADDLE),
                             motions=(Motion(object=1, pivot=(0, 0.1, 0), spin=(0, 90, 0)),),
                             physics=PhysicsSettings(restitution=1.0, friction=0.0,
                                                     plane_friction=0.0, **SIMULTANEOUS),
                             bodies=(Body(position=(0.7, 0.1, -0.3), radius=0.1,
                                          restitution=1.0, friction=0.0),)), 1.0, 1),
    # a ball set down on a turntable spinning at 60 degrees/s: slips, then rolls (6 s,
    # recorded every 6 steps)
    "turntable": (Scene(materials={"default": Material(friction=1.0)},
                        objects=(capped_cylinder(2.0, 0.05).at(0, 0.05, 0),),
                        motions=(Motion(object=0, spin=(0, 60.0, 0)),),
                        physics=PhysicsSettings(friction=1.0, restitution=0.0, **SIMULTANEOUS),
                        bodies=(Body(position=(0.5, 0.2, 0.0), radius=0.1,
                                     restitution=0.0),)), 6.0, 6),
}


@functools.cache
def runs(case: str):
    """(GPU, CPU) float32 trajectories of ``case``."""
    scene, seconds, every = CASES[case]
    cpu = physics.simulate(build_world(scene, np.float32), seconds, record_every=every)
    gpu = simulate(build_world(scene, np.float32), seconds, record_every=every,
                   backend="gpu", scene=scene)
    return gpu, cpu


@pytest.mark.parametrize("case", list(CASES))
def test_gpu_positions_match_cpu_within_tolerance_at_every_step(case, capsys):
    gpu, cpu = runs(case)
    error = position_difference(gpu, cpu)
    with capsys.disabled():
        print(f"\n[kinematic] {case}: GPU and CPU float32 positions differ by at most "
              f"{error:.3g} m")
    assert error <= TOLERANCE


# The cases whose balls are struck or land (the turntable's ball is set down touching it and
# records no event).
IMPACTS = [case for case in CASES if case != "turntable"]


@pytest.mark.parametrize("case", IMPACTS)
def test_gpu_contact_events_are_the_cpus_in_kind_step_and_order(case):
    gpu, cpu = runs(case)
    expected = contact_steps(cpu.events)
    assert any(kind == "sphere-shape" for _, kind, _, _ in expected), "no shape was hit"
    assert contact_steps(gpu.events) == expected


# --- the closed forms of tests/test_kinematic.py and test_keyframed_motion.py, on the GPU ---

@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_gpu_ball_struck_by_a_sinusoidal_wall_leaves_at_one_plus_e_times_its_speed(e):
    # An immovable wall gives the ball (1 + e) times the wall's normal speed, 1.2566 m/s at
    # t = 0; in float32 to 1e-6 relative (measured: the float32 rounding of the answer).
    gpu, _ = runs(f"sine_wall_e_{e}")
    assert gpu.velocities[-1, 0, 0] == pytest.approx((1 + e) * SINE_SPEED, rel=1e-6)
    assert contact_steps(gpu.events) == [(1, "sphere-shape", 0, 0)]


@pytest.mark.parametrize("e", [0.5, 1.0])
def test_gpu_ball_struck_by_a_keyframed_wall_leaves_at_one_plus_e_times_its_speed(e):
    gpu, _ = runs(f"keyframed_wall_e_{e}")
    assert gpu.velocities[-1, 0, 0] == pytest.approx((1 + e) * KEYED_SPEED, rel=1e-6)


def test_gpu_ball_rides_a_platform_moving_up_and_down_within_1e_3_m():
    # The platform's acceleration, at most 0.05 (2 pi)^2 = 1.97 m/s^2, is less than g, so
    # the ball stays on its top, 0.5 + 0.05 sin(2 pi t) (measured: within 1.9e-4 m, and
    # 3e-9 m sideways).
    gpu, _ = runs("platform_up_and_down")
    top = 0.5 + 0.05 * np.sin(2 * np.pi * gpu.times)
    np.testing.assert_allclose(gpu.positions[:, 0, 1], top + 0.1, atol=1e-3)
    assert np.abs(gpu.positions[:, 0, [0, 2]] - [0.2, 0.1]).max() < 1e-6


def test_gpu_paddle_sweeps_the_ball_away_at_twice_its_face_speed_within_1e_3():
    # The face meets the ball at the point sqrt(|c|^2 - 0.15^2) = 0.747 m from the axis,
    # moving at w times that; at e = 1 without friction the ball leaves at twice that.
    gpu, _ = runs("turning_paddle")
    assert any(e["kind"] == "sphere-shape" for e in gpu.events)
    lever = math.sqrt(0.7 ** 2 + 0.3 ** 2 - (0.1 + 0.05) ** 2)
    speed = np.linalg.norm(gpu.velocities[-1, 0].astype(np.float64))
    assert speed == pytest.approx(2 * (math.pi / 2) * lever, rel=1e-3)
    assert gpu.positions[-1, 0, 2] < -0.3                   # pushed toward -z, away from it


def test_gpu_ball_rolling_on_a_turntable_turns_its_velocity_at_two_sevenths_its_rate():
    # Once it rolls (t > 1 s), dv/dt = 2/7 W x v (Weltner, Am. J. Phys. 47, 984 (1979)). In
    # float32 the turn rate from differences of the recorded velocity's angle is within
    # 2.6e-5 of -2/7 W (measured; the CPU's float64 test holds 1e-5), hence 1e-4.
    gpu, _ = runs("turntable")
    v = gpu.velocities[:, 0].astype(np.float64)
    turn = np.gradient(np.unwrap(np.arctan2(v[:, 2], v[:, 0])), gpu.times)
    rolling = gpu.times > 1.0
    np.testing.assert_allclose(turn[rolling], -2 / 7 * TURNTABLE_RATE, rtol=1e-4)
    assert np.abs(gpu.positions[:, 0, 1] - 0.2).max() < 1e-6          # never leaves the disc


def test_gpu_ball_on_a_keyframed_rising_platform_rides_it_then_flies_on_when_it_stops():
    # While the platform rises at u the ball moves up at u (measured: exactly, in float32)
    # within one step's rise of its top (1.25 mm); when it stops dead the ball flies on and
    # peaks u^2 / 2g - u h / 2 above it (7.5e-5 m off, measured; the slop is 1e-4 m), then
    # lands and rests there.
    gpu, _ = runs("keyframed_rising_platform")
    rising = (gpu.times > 0.7) & (gpu.times < 1.45)
    np.testing.assert_allclose(gpu.velocities[rising, 0, 1], RISE, atol=1e-6)
    top = 0.5 + RISE * np.clip(gpu.times - 0.5, 0, 1)
    on_top = gpu.times < 1.5
    np.testing.assert_allclose(gpu.positions[on_top, 0, 1], top[on_top] + 0.1, atol=1.3e-3)
    peak = gpu.positions[gpu.times > 1.5, 0, 1].max()
    assert peak == pytest.approx(0.8 + 0.1 + RISE ** 2 / (2 * G) - RISE / 240 / 2, abs=1e-4)
    assert gpu.positions[-1, 0, 1] == pytest.approx(0.9, abs=1e-3)
    assert abs(gpu.velocities[-1, 0, 1]) < 1e-5


# --- the generated code of a moving shape -----------------------------------------------

def evaluate_moving_shape_on_gpu(scene, t, points):
    """shape_distance, shape_surface's restitution, shape_normal and shape_velocity of the
    first shape of ``scene``, placed where its motion has it at time ``t`` as GpuStepper
    places it (`pose_rows`), at ``points`` (N, 3) float32."""
    world = build_world(scene, np.float32)
    node = shape_objects(scene)[0]
    code = world_shape_code(world, [node], [primitive_coefficients(node, scene, scene.physics)])
    parameters = code.parameters.copy()
    pose = pose_rows(scene.motions[0], t)
    parameters[code.pose_rows[0]:code.pose_rows[0] + len(pose)] = pose
    results = evaluate_shape_code(code.source, parameters, points, [
        "vec4(shape_distance(0, p), shape_surface(0, p), 0.0)",
        "vec4(shape_normal(0, p), 0.0)", "vec4(shape_velocity(0, p), 0.0)"])
    return results[:, 0, 0], results[:, 0, 1], results[:, 1, :3], results[:, 2, :3]


RUBBER = Material(restitution=0.9, friction=0.8)
MOVING_SHAPES = {
    # turning about a tilted axis through an off-centre pivot while moving back and forth
    "spinning_and_oscillating": Motion(object=0, pivot=(0.3, 0.1, -0.2), spin=(10, 90, 30),
                                       amplitude=(0, 0.2, 0.1), period=2.0),
    # keyed turns and offsets, slerped by smoothstep
    "keyframed_turns": Motion(object=0, pivot=(0.5, 0.0, -0.2), times=(0.0, 1.0, 3.0),
                              offsets=((0, 0, 0), (1, 0, 0), (1, 2, 0)),
                              turns=((0, 0, 0), (0, 90, 0), (0, 90, 90)),
                              interpolation="smoothstep"),
}


@pytest.mark.parametrize("case", list(MOVING_SHAPES))
def test_generated_moving_shape_is_the_cpus_shape_at_the_same_time(case, capsys):
    """The GPU's distance, normal, surface velocity and material of a moving shape against
    ``Shape.at(t)`` on the CPU, at 20000 points and three times: a box with a rubber peg, so
    that two materials are met. The CPU applies the pose in float64 and rounds the point it
    gives, the GPU in float32, so a point's place on the shape differs by a rounding. Measured
    on llvmpipe: distances within 4.8e-7 m, velocities within 4.8e-7 m/s, normals within
    1.7e-4 (their differences are divided by 2 h = 2e-3 m) and the same material at every
    point; on an NVIDIA H200 the same, but normals within 2.4e-4. The bounds leave room for
    a point on a boundary between faces or materials, which a rounding may move across."""
    motion = MOVING_SHAPES[case]
    scene = Scene(materials={"default": Material(), "rubber": RUBBER},
                  objects=(box(0.6, 0.3, 0.4) | box(0.1, 0.6, 0.1, material="rubber"),),
                  motions=(motion,),
                  physics=PhysicsSettings(plane_restitution=0.25, **SIMULTANEOUS))
    shape = build_world(scene, np.float32).shapes[0]
    points = np.random.default_rng(11).uniform(-1.5, 1.5, (20000, 3)).astype(np.float32)
    for t in (0.0, 0.37, 1.9):
        placed = shape.at(t)
        near = points + motion_pose(motion, t)[1].astype(np.float32)   # around it now
        distance, restitution, normal, velocity = evaluate_moving_shape_on_gpu(scene, t, near)
        distance_error = np.abs(distance - placed.distance(near)).max()
        velocity_error = np.abs(velocity - placed.surface_velocity(near)).max()
        normal_error = np.abs(normal - placed.normal(near)).max(axis=1)
        same = restitution == placed.coefficients(near)[0]
        with capsys.disabled():
            print(f"\n[kinematic] {case} at t = {t}: distance {distance_error:.2g} m, velocity "
                  f"{velocity_error:.2g} m/s, normal {normal_error.max():.2g}, "
                  f"{np.count_nonzero(~same)} other materials")
        assert distance_error <= 1e-6
        assert velocity_error <= 2e-6
        assert np.mean(normal_error > 1e-3) <= 1e-3
        assert same.mean() >= 0.999
        assert set(np.unique(restitution).tolist()) == {np.float32(0.25), np.float32(0.9)}
