"""`pixel_ray` aims where `camera_rays` does, and `project` is its inverse."""

import numpy as np
import pytest

from scene_model.camera import camera_rays, pixel_ray, project
from scene_model.scene import Camera

CAMERAS = [Camera(), Camera(position=(3.0, 2.0, -4.0), look_at=(0.5, 0.2, 0.1), fov=35.0),
           Camera(position=(0.0, 10.0, 0.1), up=(0.0, 0.0, 1.0), fov=90.0)]


@pytest.mark.parametrize("camera", CAMERAS)
def test_pixel_ray_at_pixel_centres_equals_camera_rays(camera):
    origin, directions = camera_rays(camera, 16, 12)
    for j, i in [(0, 0), (5, 9), (11, 15)]:
        o, d = pixel_ray(camera, i + 0.5, j + 0.5, 16, 12)
        np.testing.assert_allclose(o, origin)
        np.testing.assert_allclose(d, directions[j, i], atol=1e-12)


@pytest.mark.parametrize("camera", CAMERAS)
def test_project_inverts_pixel_ray(camera):
    rng = np.random.default_rng(1)
    xy = rng.uniform(0, [64, 48], size=(20, 2))
    points = []
    for (x, y), t in zip(xy, rng.uniform(0.5, 20, size=20)):
        o, d = pixel_ray(camera, x, y, 64, 48)
        points.append(o + t * d)
    projected = project(camera, points, 64, 48)
    np.testing.assert_allclose(projected[:, :2], xy, atol=1e-9)
    assert (projected[:, 2] > 0).all()


def test_project_a_point_behind_the_camera_is_nan():
    camera = Camera()
    behind = np.asarray(camera.position) * 2 - np.asarray(camera.look_at)
    x, y, depth = project(camera, [behind], 64, 48)[0]
    assert np.isnan(x) and np.isnan(y) and depth < 0
