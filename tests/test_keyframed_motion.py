"""Keyframed kinematic objects: a pose at each key time, interpolated, pushing the bodies.

scene_model/motion.py: the shift is interpolated and the turn slerped between keys, linearly
or by smoothstep; the surface velocity is the derivative of that pose. Closed forms: poses at
the keys, the half-way turn, velocities against central differences, and a ball struck by a
wall keyframed at constant speed u leaving at (1 + e) u.
"""

import math

import numpy as np
import pytest

import physics
from marchlab.simulation import build_world
from scene_model.builder import Body, Material, PhysicsSettings, Scene, box
from scene_model.errors import SceneError
from scene_model.geometry import rotation_matrix
from scene_model.motion import Motion, motion_pose, motion_velocity
from scene_model.scenefile import scene_from_dict

KEYS = dict(object=0, pivot=(0.5, 0.0, -0.2), times=(0.0, 1.0, 3.0),
            offsets=((0, 0, 0), (1, 0, 0), (1, 2, 0)),
            turns=((0, 0, 0), (0, 90, 0), (0, 90, 90)))


@pytest.mark.parametrize("interpolation", ["linear", "smoothstep"])
def test_the_pose_at_each_key_time_is_that_keys_pose_to_1e_12(interpolation):
    motion = Motion(**KEYS, interpolation=interpolation)
    for time, offset, turn in zip(KEYS["times"], KEYS["offsets"], KEYS["turns"]):
        rotation, shift = motion_pose(motion, time)
        np.testing.assert_allclose(shift, offset, rtol=0, atol=1e-12)
        np.testing.assert_allclose(rotation, rotation_matrix(turn), rtol=0, atol=1e-12)


def test_half_way_between_keys_the_shift_is_the_mean_and_the_turn_half_the_angle():
    """Linear: at t = 0.5 the shift is (0.5, 0, 0) and the turn 45 degrees about y (1e-12);
    at t = 2 the turn is half-way from 'y 90' to 'y 90 then z 90': 45 degrees about the world
    z axis after the first turn (the single axis joining the two keys)."""
    motion = Motion(**KEYS)
    rotation, shift = motion_pose(motion, 0.5)
    np.testing.assert_allclose(shift, (0.5, 0, 0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(rotation, rotation_matrix((0, 45, 0)), rtol=0, atol=1e-12)
    rotation, _ = motion_pose(motion, 2.0)
    np.testing.assert_allclose(rotation, rotation_matrix((0, 0, 45)) @ rotation_matrix((0, 90, 0)),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("interpolation", ["linear", "smoothstep"])
@pytest.mark.parametrize("time", [0.3, 0.77, 1.4, 2.9])
def test_the_surface_velocity_is_the_time_derivative_of_the_pose(interpolation, time):
    """v(x) = w x (x - pivot - s) + s' against a central difference of the pose over
    +-1e-6 s: 1e-6 relative (the difference's own error is about 1e-9)."""
    motion = Motion(**KEYS, interpolation=interpolation)
    body_points = np.array([[0.5, 0.1, -0.2], [1.3, -0.4, 0.9], [-2.0, 0.5, 0.0]])
    pivot = np.asarray(KEYS["pivot"])

    def where(t):
        rotation, shift = motion_pose(motion, t)
        return (body_points - pivot) @ rotation.T + pivot + shift

    h = 1e-6
    difference = (where(time + h) - where(time - h)) / (2 * h)
    velocity = motion_velocity(motion, time, where(time))
    np.testing.assert_allclose(velocity, difference, rtol=1e-6, atol=1e-8)


def test_smoothstep_starts_and_stops_at_rest_at_every_key_and_linear_does_not():
    smooth, linear = Motion(**KEYS, interpolation="smoothstep"), Motion(**KEYS)
    points = np.array([[1.0, 1.0, 1.0]])
    for time in (1e-9, 1.0 - 1e-9, 1.0 + 1e-9, 3.0 - 1e-9):
        assert np.abs(motion_velocity(smooth, time, points)).max() < 1e-6
    assert np.abs(motion_velocity(linear, 0.5, points)).max() > 1.0


def test_before_the_first_key_and_after_the_last_the_pose_holds_and_is_still():
    motion = Motion(**dict(KEYS, times=(1.0, 2.0, 3.0)))
    for time, key in ((0.0, 0), (0.5, 0), (5.0, 2), (1e5, 2)):
        rotation, shift = motion_pose(motion, time)
        np.testing.assert_allclose(shift, KEYS["offsets"][key], atol=1e-12)
        np.testing.assert_allclose(rotation, rotation_matrix(KEYS["turns"][key]), atol=1e-12)
        assert not motion_velocity(motion, time, np.ones((1, 3))).any()


def test_a_looping_motion_repeats_every_last_minus_first_seconds():
    motion = Motion(**KEYS, loop=True)
    for time in (0.25, 1.5, 2.75):
        for turns in (1, 7):
            again = motion_pose(motion, time + turns * 3.0)
            np.testing.assert_allclose(again[0], motion_pose(motion, time)[0], atol=1e-12)
            np.testing.assert_allclose(again[1], motion_pose(motion, time)[1], atol=1e-9)


@pytest.mark.parametrize("e", [0.5, 1.0])
def test_a_ball_struck_by_a_wall_keyframed_at_constant_speed_leaves_at_one_plus_e_times_it(e):
    """No gravity, no friction: the wall's keys move it 0.5 m in 0.25 s (u = 2 m/s, linear);
    it touches the resting ball at t = 0, and an immovable wall gives the ball (1 + e) u
    (to 1e-12)."""
    wall = box(0.1, 1, 1, material="wall")
    scene = Scene(materials={"default": Material(),
                             "wall": Material(restitution=e, friction=0.0)},
                  objects=(wall,),
                  motions=(Motion(object=0, times=(0.0, 0.25),
                                  offsets=((0, 0, 0), (0.5, 0, 0))),),
                  physics=PhysicsSettings(gravity=(0, 0, 0)),
                  bodies=(Body(position=(0.2, 0, 0), radius=0.1, restitution=0.0,
                               friction=0.0),))
    run = physics.simulate(build_world(scene), 0.2)
    assert run.velocities[-1, 0, 0] == pytest.approx((1 + e) * 2.0, rel=1e-12)


def test_a_ball_on_a_platform_keyframed_to_rise_rides_it_and_flies_on_when_it_stops():
    """The platform's keys lift it 0.3 m in 1 s (u = 0.3 m/s, linear), then hold. While it
    rises the resting ball moves up at u (1e-9) on its top (within one step's rise, 1.25 mm:
    the platform starts at full speed and is met at the start of a step); when it stops
    dead the ball flies on and peaks u^2 / 2g - u h / 2 = 3.96 mm above it (the sum of
    semi-implicit Euler's steps, h = 1/240 s, physics/integrators.py; to 1e-4 m, the slop),
    then lands and rests there."""
    u, g = 0.3, 9.81
    scene = Scene(materials={"default": Material()},
                  objects=(box(1, 0.1, 1).at(0, 0.4, 0),),
                  motions=(Motion(object=0, times=(0.5, 1.5),
                                  offsets=((0, 0, 0), (0, u, 0))),),
                  physics=PhysicsSettings(restitution=0.0, plane_restitution=0.0),
                  bodies=(Body(position=(0.2, 0.6, 0.1), radius=0.1, restitution=0.0),))
    run = physics.simulate(build_world(scene), 2.5)
    rising = (run.times > 0.7) & (run.times < 1.45)
    np.testing.assert_allclose(run.velocities[rising, 0, 1], u, atol=1e-9)
    top = 0.5 + u * np.clip(run.times - 0.5, 0, 1)
    on_top = run.times < 1.5
    np.testing.assert_allclose(run.positions[on_top, 0, 1], top[on_top] + 0.1, atol=1.3e-3)
    peak = run.positions[run.times > 1.5, 0, 1].max()
    assert peak == pytest.approx(0.8 + 0.1 + u * u / (2 * g) - u / 240 / 2, abs=1e-4)
    assert run.positions[-1, 0, 1] == pytest.approx(0.9, abs=1e-3)
    assert abs(run.velocities[-1, 0, 1]) < 1e-6


@pytest.mark.parametrize("fields, blamed, words", [
    (dict(times=(0.0, 1.0), offsets=((0, 0, 0),)), "offsets", "one value per key time"),
    (dict(times=(1.0, 1.0), offsets=((0, 0, 0), (1, 0, 0))), "times[1]", "must increase"),
    (dict(times=(0.0, 1.0), turns=((0, 0, 0), (0, 9, 0)), spin=(0, 5, 0)), "spin",
     "no constant spin"),
    (dict(offsets=((0, 0, 0),)), "offsets", "needs key times"),
    (dict(times=(0.0,), loop=True), "loop", "at least two"),
    (dict(times=(-1.0, 1.0)), "times", "between 0 and"),
])
def test_bad_keys_are_refused_in_one_line_naming_the_field(fields, blamed, words):
    with pytest.raises(SceneError) as error:
        scene_from_dict({"objects": [{"type": "sphere"}],
                         "motions": [dict(object=0, **fields)]})
    message = str(error.value)
    assert f"motions[0].{blamed}" in message and words in message and "\n" not in message


def test_keyframes_read_from_a_scene_file_table():
    """The scene format spells keys as lists: times = [...], offsets = [[x, y, z], ...]."""
    scene = scene_from_dict({"objects": [{"type": "sphere"}],
                             "motions": [{"object": 0, "times": [0, 2],
                                          "turns": [[0, 0, 0], [0, 0, 90]],
                                          "interpolation": "smoothstep"}]})
    rotation, _ = motion_pose(scene.motions[0], 1.0)
    np.testing.assert_allclose(rotation, rotation_matrix((0, 0, 45)), atol=1e-12)
    assert math.isclose(motion_velocity(scene.motions[0], 1.0, np.array([[1.0, 0, 0]]))[0, 1],
                        math.radians(90) * 1.5 / 2, rel_tol=1e-12)
