"""The camera contract (marchlab.camera_rays) against the formula of docs/scene-format.md.

The expected rays are computed here independently, pixel by pixel in plain float64 Python
arithmetic, from the documented formula::

    sx = (2 (x + 0.5) / W - 1) tan(fov / 2) W / H
    sy = (1 - 2 (y + 0.5) / H) tan(fov / 2)
    forward = normalize(look_at - position)
    right   = normalize(forward x up)
    up'     = right x forward
    dir     = normalize(forward + sx right + sy up')

with fov the vertical field of view in degrees.
"""

import math

import numpy as np
import pytest

import marchlab
from marchlab import Camera

# Cameras that exercise every term: axis-aligned, tilted, off-origin, an up vector that is not
# perpendicular to the view direction, narrow and wide fields of view.
CAMERAS = [
    Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov=60.0),
    Camera(position=(0.0, 2.2, 7.0), look_at=(0.0, 0.8, 0.0), up=(0.0, 1.0, 0.0), fov=50.0),
    Camera(position=(3.0, -1.0, 2.0), look_at=(-1.0, 0.5, -4.0), up=(0.3, 1.0, -0.2), fov=35.0),
    Camera(position=(-2.0, 4.0, 1.0), look_at=(1.0, 0.0, 0.5), up=(0.0, 0.0, 1.0), fov=100.0),
]
SIZES = [(7, 5), (16, 9), (1, 1), (4, 11)]


def _normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def documented_ray(camera, width, height, x, y):
    """The documented direction of pixel (x, y), in plain Python floats."""
    half = math.tan(math.radians(camera.fov) / 2)
    sx = (2 * (x + 0.5) / width - 1) * half * width / height
    sy = (1 - 2 * (y + 0.5) / height) * half
    forward = _normalize([a - b for a, b in zip(camera.look_at, camera.position)])
    right = _normalize(_cross(forward, camera.up))
    up = _cross(right, forward)
    return _normalize([f + sx * r + sy * u for f, r, u in zip(forward, right, up)])


def angle_between(a, b):
    """Angle in radians between two unit vectors, accurate for small and large angles."""
    return 2 * math.atan2(np.linalg.norm(np.subtract(a, b)), np.linalg.norm(np.add(a, b)))


@pytest.mark.parametrize("camera", CAMERAS)
@pytest.mark.parametrize("width, height", SIZES)
def test_directions_match_documented_formula_within_1e_12(camera, width, height):
    origin, directions = marchlab.camera_rays(camera, width, height)
    assert directions.shape == (height, width, 3)
    expected = np.array([[documented_ray(camera, width, height, x, y) for x in range(width)]
                         for y in range(height)])
    np.testing.assert_allclose(directions, expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(origin, camera.position)


@pytest.mark.parametrize("camera", CAMERAS)
def test_directions_have_unit_length_within_1e_12(camera):
    _, directions = marchlab.camera_rays(camera, 33, 21)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("camera", CAMERAS)
def test_row_zero_is_the_top_and_column_zero_the_left_of_the_image(camera):
    """Row 0 looks more along up' than the last row; column 0 less along right than the last."""
    width, height = 9, 7
    _, directions = marchlab.camera_rays(camera, width, height)
    forward = _normalize([a - b for a, b in zip(camera.look_at, camera.position)])
    right = _normalize(_cross(forward, camera.up))
    up = _cross(right, forward)
    vertical = directions @ np.array(up)        # (H, W): how far up each ray points
    horizontal = directions @ np.array(right)
    # Every column: strictly decreasing from the top row to the bottom row.
    assert np.all(np.diff(vertical, axis=0) < 0)
    assert np.all(np.diff(horizontal, axis=1) > 0)
    assert np.all(vertical[0] > 0) and np.all(vertical[-1] < 0)


def test_row_zero_points_up_in_world_space_for_an_upright_camera():
    """With up = +y and a level camera, the top row's rays have the larger world y."""
    camera = Camera(position=(0.0, 1.0, 5.0), look_at=(0.0, 1.0, 0.0), fov=60.0)
    _, directions = marchlab.camera_rays(camera, 5, 5)
    assert np.all(directions[0, :, 1] > 0.2)
    assert np.all(directions[-1, :, 1] < -0.2)


@pytest.mark.parametrize("fov", [20.0, 60.0, 120.0])
def test_angle_between_top_and_bottom_centre_rays_approaches_fov(fov):
    """For an odd height H the top- and bottom-centre rays lie in the forward/up' plane at
    2 atan((1 - 1/H) tan(fov/2)) apart. By the mean value theorem on atan (whose slope
    1/(1 + x^2) falls with x) the shortfall fov - angle lies between sin(fov)/H and
    2 tan(fov/2) / (H (1 + ((1 - 1/H) tan(fov/2))^2)), so it vanishes like 1/H."""
    camera = Camera(position=(1.0, 2.0, 3.0), look_at=(0.0, 0.5, -1.0), fov=fov)
    errors = []
    for height in (11, 101, 1001):
        width = 3                                  # odd: column 1 is the centre column
        _, directions = marchlab.camera_rays(camera, width, height)
        angle = angle_between(directions[0, 1], directions[-1, 1])
        half = math.tan(math.radians(fov) / 2)
        assert angle == pytest.approx(2 * math.atan((1 - 1 / height) * half), abs=1e-12)
        error = math.radians(fov) - angle
        lower = math.sin(math.radians(fov)) / height
        upper = 2 * half / (height * (1 + ((1 - 1 / height) * half) ** 2))
        assert lower - 1e-12 <= error <= upper + 1e-12
        errors.append(error)
    assert errors[0] > errors[1] > errors[2]


def test_field_of_view_is_vertical_whatever_the_width():
    """The vertical angle does not depend on W; the horizontal one grows as W / H."""
    camera = Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=40.0)
    height = 101
    vertical = []
    for width in (101, 301):
        _, d = marchlab.camera_rays(camera, width, height)
        c = width // 2
        vertical.append(angle_between(d[0, c], d[-1, c]))
        horizontal = angle_between(d[height // 2, 0], d[height // 2, -1])
        half_width = (1 - 1 / width) * math.tan(math.radians(20.0)) * width / height
        assert horizontal == pytest.approx(2 * math.atan(half_width), abs=1e-12)
    assert vertical[0] == pytest.approx(vertical[1], abs=1e-12)


def test_centre_pixel_of_an_odd_image_looks_at_look_at():
    camera = CAMERAS[2]
    _, directions = marchlab.camera_rays(camera, 7, 5)
    forward = _normalize([a - b for a, b in zip(camera.look_at, camera.position)])
    np.testing.assert_allclose(directions[2, 3], forward, rtol=0, atol=1e-12)


@pytest.mark.parametrize("camera", CAMERAS)
def test_float32_rays_are_float32_and_agree_with_float64_within_1e_6(camera):
    origin32, d32 = marchlab.camera_rays(camera, 33, 21, np.float32)
    _, d64 = marchlab.camera_rays(camera, 33, 21, np.float64)
    assert d32.dtype == np.float32 and origin32.dtype == np.float32
    assert d64.dtype == np.float64
    # A few float32 roundings (2^-24 ~ 6e-8 each) on values of order 1.
    np.testing.assert_allclose(d32, d64, rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(d32.astype(np.float64), axis=-1), 1.0, atol=1e-6)
