"""Orbit, pan, zoom and fly (scene_model/camera_motion.py) against their geometry.

Each motion is checked against what it must do exactly: an orbit keeps the pivot and the
distance and turns the eye by the angle asked; a pan carries the pivot to a known place on
the screen; a zoom scales the distance; flying is independent of the frame rate. Tolerances
are 1e-9 relative to the scene's size (a few float64 roundings through sin and cos).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from scene_model.camera import camera_basis, camera_rays
from scene_model.camera_motion import (MIN_DISTANCE, POLE_MARGIN, fly, orbit, pan,
                                       rotate_about, zoom)
from scene_model.fields import MAX_COORDINATE
from scene_model.scene import Camera

TOL = 1e-9
START = Camera(position=(0.0, 1.0, 5.0), look_at=(0.0, 1.0, 0.0), up=(0.0, 1.0, 0.0), fov=60.0)


def eye(camera):
    return np.asarray(camera.position)


def pivot(camera):
    return np.asarray(camera.look_at)


def polar_degrees(camera):
    """The eye's angle from the up axis through the pivot."""
    offset = eye(camera) - pivot(camera)
    up = np.asarray(camera.up) / np.linalg.norm(camera.up)
    return math.degrees(math.acos(offset @ up / np.linalg.norm(offset)))


def screen_position(camera, point):
    """(sx, sy) in tangent units of the camera model: the pixel that sees ``point``."""
    forward, right, up = camera_basis(camera)
    v = np.asarray(point) - eye(camera)
    return np.array([v @ right, v @ up]) / (v @ forward)


def test_a_yaw_of_90_degrees_takes_the_eye_from_plus_z_to_plus_x_around_the_pivot():
    turned = orbit(START, 90.0, 0.0)
    np.testing.assert_allclose(eye(turned), (5.0, 1.0, 0.0), atol=TOL * 5)
    assert turned.look_at == START.look_at


def test_a_full_turn_of_yaw_comes_back_to_the_start():
    camera = START
    for _ in range(8):
        camera = orbit(camera, 45.0, 0.0)
    np.testing.assert_allclose(eye(camera), eye(START), atol=TOL * 5)


def test_a_positive_pitch_raises_the_eye_by_exactly_that_angle():
    raised = orbit(START, 0.0, 30.0)
    assert polar_degrees(raised) == pytest.approx(60.0, abs=1e-9)
    np.testing.assert_allclose(eye(raised), (0.0, 1.0 + 5 * math.sin(math.radians(30)),
                                             5 * math.cos(math.radians(30))), atol=TOL * 5)


@pytest.mark.parametrize("pitch", [89.5, 90.0, 1000.0, -1000.0])
def test_pitch_stops_short_of_the_poles_and_the_camera_stays_valid(pitch):
    camera = orbit(START, 0.0, pitch)
    polar = polar_degrees(camera)
    assert POLE_MARGIN - 1e-9 <= polar <= 180 - POLE_MARGIN + 1e-9
    if abs(pitch) > 90:
        assert polar == pytest.approx(POLE_MARGIN if pitch > 0 else 180 - POLE_MARGIN, abs=1e-9)
    origin, directions = camera_rays(camera, 8, 6)
    assert np.all(np.isfinite(directions))


@given(yaw=st.floats(-720, 720), pitch=st.floats(-200, 200))
def test_an_orbit_keeps_the_pivot_and_the_distance(yaw, pitch):
    camera = orbit(START, yaw, pitch)
    assert camera.look_at == START.look_at
    assert np.linalg.norm(eye(camera) - pivot(camera)) == pytest.approx(5.0, rel=TOL)


@pytest.mark.parametrize("right, up", [(0.25, 0.0), (0.0, -0.5), (0.1, 0.3)])
def test_after_a_pan_the_old_pivot_appears_where_the_drag_put_it(right, up):
    panned = pan(START, right, up)
    half_height = math.tan(math.radians(START.fov) / 2)
    np.testing.assert_allclose(screen_position(panned, pivot(START)),
                               (-2 * right * half_height, -2 * up * half_height), atol=TOL)
    np.testing.assert_allclose(eye(panned) - eye(START), pivot(panned) - pivot(START), atol=TOL)


def test_a_zoom_scales_the_distance_along_the_view_and_stops_short_of_the_pivot():
    closer = zoom(START, 0.5)
    np.testing.assert_allclose(eye(closer), (0.0, 1.0, 2.5), atol=TOL)
    assert zoom(START, 1e-12).position == pytest.approx((0.0, 1.0, MIN_DISTANCE), abs=TOL)
    with pytest.raises(ValueError, match="positive"):
        zoom(START, 0.0)


def test_flying_is_independent_of_the_frame_rate():
    velocity = (1.5, -0.25, 3.0)                 # m/s: right, up, forward
    one_frame = fly(START, velocity, 1 / 30)
    two_frames = fly(fly(START, velocity, 1 / 60), velocity, 1 / 60)
    np.testing.assert_allclose(eye(two_frames), eye(one_frame), atol=TOL)
    np.testing.assert_allclose(pivot(two_frames), pivot(one_frame), atol=TOL)
    # forward is -z here, right +x, up +y: the exact displacement of 1/30 s
    np.testing.assert_allclose(eye(one_frame) - eye(START), np.array([1.5, -0.25, -3.0]) / 30,
                               atol=TOL)


def test_a_motion_past_the_scene_formats_range_leaves_the_camera_where_it_was():
    assert fly(START, (0.0, 0.0, 1.0), 2 * MAX_COORDINATE) is START
    assert zoom(START, 1e7) is START


def test_rodrigues_turns_x_into_y_about_z():
    np.testing.assert_allclose(rotate_about(np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), 90),
                               (0, 1, 0), atol=1e-15)
