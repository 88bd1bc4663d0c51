"""Kinematic objects: scene objects moved along a prescribed path push the bodies.

A `scene_model.motion.Motion` turns an object about a pivot and moves it back and forth;
the physics step collides with it where it is and gives the bodies its surface velocity
(physics/colliders.py, `Shape.at`). Closed forms: a ball struck by a moving wall leaves at
(1 + e) times the wall's speed; a ball resting on a platform that moves up and down (less
than g of acceleration) rides it; the pose of an object is the renderers' and the physics'.
"""

import math

import numpy as np
import pytest

import physics
from marchlab.simulation import build_world
from scene_model.builder import (Body, Material, PhysicsSettings, Scene, box, capped_cylinder,
                                 plane)
from scene_model.errors import SceneError
from scene_model.geometry import rotation_matrix
from scene_model.motion import Motion, euler_degrees, motion_pose, motion_velocity
from scene_model.scene import scene_at

G = 9.81


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_a_ball_struck_by_a_moving_wall_leaves_at_one_plus_e_times_its_speed_to_1e_12(e):
    """No gravity, no friction: the wall x = 0.1 moves as 0.2 sin(2 pi t), 1.2566 m/s at
    t = 0 when it touches the ball; an immovable wall gives the ball (1 + e) times its own
    normal speed."""
    amplitude, period = 0.2, 1.0
    wall = box(0.1, 1, 1, material="wall")
    scene = Scene(materials={"default": Material(),
                             "wall": Material(restitution=e, friction=0.0)},
                  objects=(wall,),
                  motions=(Motion(object=0, amplitude=(amplitude, 0, 0), period=period),),
                  physics=PhysicsSettings(gravity=(0, 0, 0)),
                  bodies=(Body(position=(0.2, 0, 0), radius=0.1, restitution=0.0,
                               friction=0.0),))
    run = physics.simulate(build_world(scene), 0.1)
    speed = amplitude * 2 * math.pi / period
    assert run.velocities[-1, 0, 0] == pytest.approx((1 + e) * speed, rel=1e-12)
    assert run.events["kind"][0] == "sphere-shape"


def test_a_ball_resting_on_a_platform_moving_up_and_down_rides_it_within_1e_3_m():
    """The platform's top moves as 0.05 sin(2 pi t): its acceleration, at most
    0.05 (2 pi)^2 = 1.97 m/s^2, is less than g, so the ball never leaves it."""
    amplitude = 0.05
    scene = Scene(materials={"default": Material()},
                  objects=(box(1, 0.1, 1).at(0, 0.4, 0),),
                  motions=(Motion(object=0, amplitude=(0, amplitude, 0), period=1.0),),
                  physics=PhysicsSettings(restitution=0.0, plane_restitution=0.0),
                  bodies=(Body(position=(0.2, 0.6, 0.1), radius=0.1, restitution=0.0),))
    run = physics.simulate(build_world(scene), 3.0)
    top = 0.5 + amplitude * np.sin(2 * np.pi * run.times)
    np.testing.assert_allclose(run.positions[:, 0, 1], top + 0.1, atol=1e-3)
    assert np.abs(run.positions[:, 0, [0, 2]] - [0.2, 0.1]).max() < 1e-6


def test_a_paddle_turning_about_y_sweeps_a_resting_ball_away():
    """A paddle 2 m long and 10 cm thick turns at w = 90 degrees/s about the vertical axis
    through its middle; a ball (r = 0.1) lying in its way with its centre c = (0.7, -0.3) from
    the axis is struck by the face when the face is r + 0.05 from c, at the point of the face
    sqrt(|c|^2 - 0.15^2) = 0.747 m from the axis, which moves at w times that along the
    face's normal; at e = 1 without friction the ball leaves at twice that, 2.347 m/s
    (within 1e-3: the face is met at the start of a step)."""
    paddle = box(1.0, 0.1, 0.05, material="paddle").at(0, 0.1, 0)
    scene = Scene(materials={"default": Material(friction=0.0),
                             "paddle": Material(restitution=1.0, friction=0.0)},
                  objects=(plane(), paddle),
                  motions=(Motion(object=1, pivot=(0, 0.1, 0), spin=(0, 90, 0)),),
                  physics=PhysicsSettings(restitution=1.0, friction=0.0, plane_friction=0.0),
                  bodies=(Body(position=(0.7, 0.1, -0.3), radius=0.1, restitution=1.0,
                               friction=0.0),))
    run = physics.simulate(build_world(scene), 1.0)
    hit = run.events[run.events["kind"] == "sphere-shape"]
    assert len(hit) >= 1
    speed = np.linalg.norm(run.velocities[-1, 0])
    lever = math.sqrt(0.7 ** 2 + 0.3 ** 2 - (0.1 + 0.05) ** 2)
    assert speed == pytest.approx(2 * (math.pi / 2) * lever, rel=1e-3)
    assert run.positions[-1, 0, 2] < -0.3                 # pushed toward -z, away from it


def test_a_ball_rolling_on_a_turntable_turns_its_velocity_at_two_sevenths_its_rate():
    """A solid ball set down on a turntable spinning at W = 60 degrees/s slips for a moment,
    then rolls without slipping; from then on its velocity turns at 2/7 W, the other way
    (Weltner, "Stable circular orbits of freely moving balls on rotating discs", Am. J. Phys.
    47, 984 (1979)): friction at the contact is the only horizontal force, and rolling ties
    the ball's spin to it so that dv/dt = 2/7 W x v. Measured: 0.2991991 against 0.2991993
    rad/s (7e-7 relative), constant to 1e-14 rad/s."""
    rate = math.radians(60.0)
    scene = Scene(materials={"default": Material(friction=1.0)},
                  objects=(capped_cylinder(2.0, 0.05).at(0, 0.05, 0),),
                  motions=(Motion(object=0, spin=(0, 60.0, 0)),),
                  physics=PhysicsSettings(friction=1.0, restitution=0.0),
                  bodies=(Body(position=(0.5, 0.2, 0.0), radius=0.1, restitution=0.0),))
    run = physics.simulate(build_world(scene), 12.0, record_every=6)
    v = run.velocities[:, 0]
    turn = np.gradient(np.unwrap(np.arctan2(v[:, 2], v[:, 0])), run.times)
    rolling = run.times > 1.0
    np.testing.assert_allclose(turn[rolling], -2 / 7 * rate, rtol=1e-5)
    assert np.abs(run.positions[:, 0, 1] - 0.2).max() < 1e-9          # never leaves the disc


def test_the_pose_is_a_rotation_and_the_renderers_euler_angles_give_it_to_1e_15():
    motion = Motion(object=0, pivot=(1, 0, 0), spin=(10, 20, 30), amplitude=(0, 0.5, 0),
                    period=2)
    for t in (0.0, 0.3, 1.7, 12.0):
        rotation, shift = motion_pose(motion, t)
        np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-15)
        np.testing.assert_allclose(rotation_matrix(euler_degrees(rotation)), rotation,
                                   atol=1e-15)
        np.testing.assert_allclose(shift, [0, 0.5 * math.sin(math.pi * t), 0], atol=1e-15)
    # The velocity is the derivative of the path of a point, by central differences.
    point = np.array([[0.3, -0.2, 0.9]])
    t, h = 0.7, 1e-6
    path = [rotation @ (point[0] - [1, 0, 0]) + [1, 0, 0] + shift
            for rotation, shift in (motion_pose(motion, t + h), motion_pose(motion, t - h))]
    rotation, shift = motion_pose(motion, t)
    now = rotation @ (point[0] - [1, 0, 0]) + [1, 0, 0] + shift
    np.testing.assert_allclose(motion_velocity(motion, t, now[None])[0],
                               (path[0] - path[1]) / (2 * h), atol=1e-8)


def test_the_drawn_scene_has_the_object_where_the_physics_has_it():
    scene = Scene(materials={"default": Material()}, objects=(box(1, 0.1, 0.05),),
                  motions=(Motion(object=0, spin=(0, 45, 0), amplitude=(0, 0.2, 0),
                                  period=4.0),))
    world = build_world(scene)
    from reference_cpu.scene_sdf import build_scene_sdf
    points = np.random.default_rng(3).uniform(-1.5, 1.5, (500, 3))
    for t in (0.0, 1.0, 2.5):
        drawn = build_scene_sdf(scene_at(scene, np.zeros((0, 3)), t).objects)(points)[0]
        np.testing.assert_allclose(world.shapes[0].at(t).distance(points), drawn, atol=1e-12)


def test_a_motion_of_an_object_that_is_not_there_is_refused_in_one_line():
    with pytest.raises(SceneError, match=r"there is no objects\[2\] to move") as caught:
        Scene(materials={"default": Material()}, objects=(box(1),),
              motions=(Motion(object=2),))
    assert "\n" not in str(caught.value)


