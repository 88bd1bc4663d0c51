"""The view's mouse and keys move the camera by the documented amounts
(marchlab/camera_control.py)."""

import math

import numpy as np
import pytest

from marchlab import camera_control
from scene_model.scene import Camera

CAMERA = Camera(position=(0.0, 1.0, 5.0), look_at=(0.0, 0.5, 0.0), fov=50.0)


def _azimuth(camera):
    offset = np.subtract(camera.position, camera.look_at)
    return math.degrees(math.atan2(offset[0], offset[2]))


def _elevation(camera):
    offset = np.subtract(camera.position, camera.look_at)
    return math.degrees(math.asin(offset[1] / np.linalg.norm(offset)))


@pytest.mark.parametrize("pixels", [10, 120, 240])
def test_a_sideways_drag_turns_the_eye_by_orbit_degrees_per_view_height(pixels):
    moved = camera_control.drag(CAMERA, "left", pixels, 0, view_height=480)
    # dragging right carries the eye to the left (clockwise seen from above): azimuth falls
    expected = -camera_control.ORBIT_DEGREES * pixels / 480
    assert _azimuth(moved) - _azimuth(CAMERA) == pytest.approx(expected, abs=1e-9)
    assert moved.look_at == CAMERA.look_at


def test_a_downward_drag_raises_the_eye_by_orbit_degrees_per_view_height():
    moved = camera_control.drag(CAMERA, "left", 0, 48, view_height=480)
    assert _elevation(moved) - _elevation(CAMERA) == pytest.approx(18.0, abs=1e-9)
    np.testing.assert_allclose(np.linalg.norm(np.subtract(moved.position, moved.look_at)),
                               np.linalg.norm(np.subtract(CAMERA.position, CAMERA.look_at)))


@pytest.mark.parametrize("button", ["right", "middle"])
def test_a_pan_drag_carries_the_pivot_with_the_cursor(button):
    from scene_model.camera import project
    before = project(CAMERA, [CAMERA.look_at], 640, 480)[0]
    moved = camera_control.drag(CAMERA, button, 64, -32, view_height=480)
    # the old pivot now appears where the cursor moved it: 64 px right and 32 px up
    after = project(moved, [CAMERA.look_at], 640, 480)[0]
    np.testing.assert_allclose(after[:2] - before[:2], [64, -32], atol=1e-9)


def test_each_wheel_click_multiplies_the_distance_by_zoom_per_click():
    distance = np.linalg.norm(np.subtract(CAMERA.position, CAMERA.look_at))
    moved = camera_control.scroll(CAMERA, 3)
    assert np.linalg.norm(np.subtract(moved.position, moved.look_at)) == pytest.approx(
        distance * camera_control.ZOOM_PER_CLICK ** 3)
    back = camera_control.scroll(moved, -3)
    np.testing.assert_allclose(back.position, CAMERA.position, atol=1e-12)


def test_flying_depends_on_seconds_held_not_on_the_frame_rate():
    one = camera_control.fly_keys(CAMERA, {"W", "D"}, 0.5)
    many = CAMERA
    for _ in range(30):
        many = camera_control.fly_keys(many, {"W", "D"}, 0.5 / 30)
    np.testing.assert_allclose(many.position, one.position, atol=1e-12)
    distance = np.linalg.norm(np.subtract(CAMERA.position, CAMERA.look_at))
    travelled = np.linalg.norm(np.subtract(one.position, CAMERA.position))
    assert travelled == pytest.approx(0.5 * camera_control.FLY_SPEED * distance * math.sqrt(2))


def test_shift_flies_fast_times_farther_and_opposite_keys_cancel():
    slow = camera_control.fly_keys(CAMERA, {"W"}, 0.1)
    fast = camera_control.fly_keys(CAMERA, {"W"}, 0.1, fast=True)
    assert np.linalg.norm(np.subtract(fast.position, CAMERA.position)) == pytest.approx(
        camera_control.FAST * np.linalg.norm(np.subtract(slow.position, CAMERA.position)))
    assert camera_control.fly_keys(CAMERA, {"W", "S", "A", "D"}, 1.0) == CAMERA


def test_an_unknown_button_is_refused():
    with pytest.raises(ValueError, match="unknown mouse button"):
        camera_control.drag(CAMERA, "fourth", 1, 1, 100)
