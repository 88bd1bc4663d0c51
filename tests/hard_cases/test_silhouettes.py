"""Sphere silhouettes: which near-tangent rays hit, and do the backends agree?

A ray whose line passes at distance c from the centre of a sphere of radius R has clearance
c - R (negative: it enters the sphere). Sphere tracing stops where |sdf| < epsilon, so a ray
that passes within epsilon of the surface hits too, even if it never touches the sphere:
the silhouette every backend draws is that of the sphere grown by epsilon. Near the tangent
point the march takes steps about as long as the clearance and samples the distance
c - R + x^2 / (2R) at some x no farther than half a step from the closest point, so the
smallest distance it sees exceeds c - R by at most (c - R)^2 / (8R), 1.3e-7 for R = 1: a
ray hits if and only if its clearance is below epsilon, except in a tangent band
|c - R - epsilon| < 2e-3 epsilon that also covers float32 rounding of the ray (directions to
about 6e-8, so c to about 2.4e-7 = 2.4e-4 epsilon at 4 units). Every backend and every
relaxation mode must agree with that classification outside the band.

Two cameras: one at an ordinary distance (the whole sphere in view), one with a 0.004 degree
field of view aimed at the silhouette, so that its pixels sweep clearances from 0.82 to 1.18
epsilon in steps of 0.008 epsilon: the band rule is tested on both sides of the threshold.
Measured: on both, every backend and mode gives the same hit mask; the largest clearance
that hits is 0.9963 epsilon, the smallest that misses 1.0038 epsilon.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from scene_model.builder import Camera, RenderSettings, Scene, SolidBackground, sphere

from .conftest import pixel_rays, ray_sphere

EPSILON = 1e-3
RADIUS = 1.0
DISTANCE = 4.0
WIDTH, HEIGHT = 48, 36
BAND = 2e-3 * EPSILON


def grazing_camera() -> Camera:
    """Looks along the ray from (0, 0, 4) whose clearance is exactly epsilon."""
    beta = math.asin((RADIUS + EPSILON) / DISTANCE)
    return Camera(position=(0.0, 0.0, DISTANCE),
                  look_at=(math.sin(beta), 0.0, DISTANCE - math.cos(beta)), fov=0.004)


CAMERAS = {
    "whole-sphere": Camera(position=(0.4, 0.3, DISTANCE), look_at=(0.0, 0.0, 0.0), fov=40.0),
    "at-the-silhouette": grazing_camera(),
}


def silhouette_scene(camera, mode):
    return Scene(camera=camera,
                 render=RenderSettings(shading="normals", max_steps=512, relaxation=mode,
                                       omega=1.9, epsilon=EPSILON,
                                       background=SolidBackground(color=(0.1, 0.1, 0.1))),
                 objects=(sphere(RADIUS),), lights=())


@pytest.mark.parametrize("mode", ["none", "fixed", "auto"])
@pytest.mark.parametrize("view", list(CAMERAS))
def test_a_pixel_hits_exactly_where_its_ray_passes_within_epsilon_of_the_sphere(renderer,
                                                                                view, mode):
    scene = silhouette_scene(CAMERAS[view], mode)
    frame = renderer.draw(scene, WIDTH, HEIGHT)
    origin, directions = pixel_rays(scene, WIDTH, HEIGHT)
    t_exact, closest = ray_sphere(np.broadcast_to(origin, directions.shape).reshape(-1, 3),
                                  directions.reshape(-1, 3), np.zeros(3), RADIUS)
    clearance = closest.reshape(HEIGHT, WIDTH) - RADIUS
    band = np.abs(clearance - EPSILON) < BAND
    outside_band = ~band
    expected = clearance < EPSILON
    assert expected[outside_band].sum() >= 300 and (~expected[outside_band]).sum() >= 300
    assert band.sum() <= 12
    wrong = (frame.hit != expected) & outside_band
    assert not wrong.any(), (f"{renderer} {mode}: {wrong.sum()} pixels, clearances / epsilon "
                             f"{clearance[wrong][:5] / EPSILON}")

    # Every hit stops within epsilon of the surface (float32: plus rounding of t ~ 4).
    p = origin + frame.depth[frame.hit, None] * directions[frame.hit]
    off_surface = np.abs(np.linalg.norm(p, axis=1) - RADIUS)
    assert np.all(off_surface < EPSILON + 2e-6)
    # Where the ray truly enters the sphere, it stops at most epsilon / cos(theta) short.
    enters = frame.hit & (clearance < 0)
    t_exact = t_exact.reshape(HEIGHT, WIDTH)[enters]
    normal = origin + t_exact[:, None] * directions[enters]
    cos_theta = np.abs(np.einsum("ij,ij->i", normal, directions[enters]))
    short = t_exact - frame.depth[enters]
    assert np.all((short > -2e-6) & (short < EPSILON / cos_theta + 2e-6))
