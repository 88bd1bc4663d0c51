"""Distances of 1e3 to 1e4 in float32: the spacing of the numbers reaches epsilon.

Near 1e4 consecutive float32 numbers are 2^-10 = 9.8e-4 apart: about epsilon = 1e-3. A
march there computes each point p = o + t d rounded to that grid, and its distance from a
rounded point, so the distance it tests against epsilon is off by up to about one spacing u
of the largest coordinate (or of t). The expected behaviour:

- the hit mask is still that of the sphere (grown by epsilon) outside a tangent band of
  2 epsilon + 4 u in clearance;
- the stopping error keeps the contract's form with u added on both sides:
  -2u <= (t* - t) cos(theta) <= epsilon + 2u, so a float32 ray may now stop slightly *past*
  the surface (measured at 1e4: -0.73 epsilon to 1.62 epsilon; in float64 0.01 to 0.99);
- the normal's central differences (h = 1e-3 ~ u) divide rounding errors of up to u by 2h:
  the normal may tilt by about u / h radians (measured: 0.96 degrees at 1e3, 2.9 at 1e4);
- no NaN or inf anywhere.

Three scenes: a sphere of radius D/10 at distance D = 1e3 and 1e4 from a camera at the
origin (large t), and a unit sphere 5 units from a camera at (1e4, 0, 1e4) (large
coordinates, small t). max_steps = 512 leaves no ray short of steps.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from scene_model.builder import Camera, PointLight, RenderSettings, Scene, sphere

from .conftest import dot, pixel_rays, ray_sphere

EPSILON = 1e-3
WIDTH, HEIGHT = 48, 36

# name: (camera position, sphere centre, radius, max_distance)
SCENES = {
    "distance-1e3": ((0.0, 0.0, 0.0), (0.0, 0.0, -1e3), 100.0, 2e3),
    "distance-1e4": ((0.0, 0.0, 0.0), (0.0, 0.0, -1e4), 1000.0, 2e4),
    "coordinates-1e4": ((1e4, 0.0, 1e4), (1e4, 0.0, 1e4 - 5.0), 1.0, 100.0),
}


def far_scene(name, mode):
    position, centre, radius, max_distance = SCENES[name]
    distance = math.dist(position, centre)
    fov = 2.2 * math.degrees(math.asin(radius / distance))        # the sphere and a rim
    return Scene(camera=Camera(position=position, look_at=centre, fov=fov),
                 render=RenderSettings(relaxation=mode, epsilon=EPSILON, max_steps=512,
                                       max_distance=max_distance),
                 objects=(sphere(radius).at(*centre),),
                 lights=(PointLight(position=(position[0], position[1] + radius,
                                              position[2])),))


@pytest.mark.parametrize("mode", ["none", "auto"])
@pytest.mark.parametrize("name", list(SCENES))
def test_far_sphere_keeps_its_mask_and_stops_within_epsilon_plus_two_spacings(renderer,
                                                                              name, mode):
    position, centre, radius, _ = SCENES[name]
    centre = np.asarray(centre)
    scene = far_scene(name, mode)
    frame = renderer.draw(scene, WIDTH, HEIGHT)
    origin, directions = pixel_rays(scene, WIDTH, HEIGHT)
    directions = directions.reshape(-1, 3)
    t_exact, closest = ray_sphere(np.tile(origin, (len(directions), 1)), directions, centre,
                                  radius)
    hit, depth = frame.hit.ravel(), frame.depth.ravel().astype(np.float64)
    # u: the spacing of the renderer's numbers at the largest coordinate or distance.
    largest = max(np.abs(origin).max() + 1, np.abs(centre).max() + radius,
                  np.linalg.norm(centre - origin) + radius)
    u = float(np.spacing(renderer.dtype.type(largest)))

    outside_band = np.abs(closest - radius) > 2 * EPSILON + 4 * u
    assert np.isfinite(t_exact).sum() >= 500 and outside_band.mean() > 0.95
    np.testing.assert_array_equal(hit[outside_band], (closest < radius)[outside_band])

    enters = hit & np.isfinite(t_exact)
    at_hit = origin + t_exact[enters, None] * directions[enters] - centre
    cos_theta = np.abs(dot(at_hit / radius, directions[enters]))
    excess = (t_exact[enters] - depth[enters]) * cos_theta
    assert np.all((excess >= -2 * u) & (excess <= EPSILON + 2 * u)), (
        f"{renderer}: (t* - t) cos(theta) in [{excess.min():.3g}, {excess.max():.3g}], "
        f"u = {u:.3g}")

    # The normal against the exact gradient at the point where the ray stopped.
    stop = origin + depth[enters, None] * directions[enters] - centre
    exact = stop / np.linalg.norm(stop, axis=1, keepdims=True)
    normal = frame.normal.reshape(-1, 3)[enters].astype(np.float64)
    tilt = np.arccos(np.clip(dot(normal, exact), -1, 1))
    assert tilt.max() <= max(u / 1e-3, 1e-6), f"{renderer}: {np.degrees(tilt.max()):.3g} deg"
