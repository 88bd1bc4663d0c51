"""A camera inside an object: every ray walks out to the inside of the surface.

The contract steps by |sdf|, so a ray that starts inside a solid moves forward by its
distance to the surface and stops, like any other ray, where |sdf| < epsilon: just inside
the surface it leaves through. For a sphere of radius R with centre c, the exit is at
t* = -b + sqrt(b^2 - |o - c|^2 + R^2) (b = (o - c).d), and the contract's bound on the
shortfall changes because the surface is seen from its concave side: a point at depth s
inside, u before the exit, satisfies (R - s)^2 = R^2 - 2 u R cos(theta) + u^2 (theta between
the ray and the normal at the exit), so

    u <= u_max = R cos(theta) - sqrt(R^2 cos^2(theta) - 2 R epsilon + epsilon^2),

slightly more than epsilon / cos(theta) (measured: up to 1.0011 epsilon / cos(theta) from a
camera at 0.9 R off-centre). The normal there is the SDF's gradient, which points out of the
solid: along the ray (N.d > 0), so the surface is shaded from its back, and no colour may
become NaN.

Relaxed marches must do the same. They do from an off-centre camera; from the exact centre
every ray is radial and "fixed" relaxation loses most of them (see
`test_fixed_relaxation_from_the_centre_of_a_sphere_still_hits_every_ray`).
"""

from __future__ import annotations

import numpy as np
import pytest

from reference_cpu.march import march
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import Camera, PointLight, RenderSettings, Scene, sphere

from .conftest import dot, pixel_rays, ray_sphere, unit

EPSILON = 1e-3
CENTRE = np.array([0.3, -0.2, 0.5])
RADIUS = 1.2
MODES = [("none", 1.0), ("fixed", 1.2), ("fixed", 1.9), ("auto", 1.0)]
# float32: t ~ 1-2 is rounded to about 1e-7 per step; 2e-6 covers the accumulation.
SLACK = {np.dtype("float64"): 1e-12, np.dtype("float32"): 2e-6}


def concave_shortfall_bound(cos_theta, radius=RADIUS, epsilon=EPSILON):
    """u_max: how far before the exit a ray may stop at depth < epsilon (module docstring)."""
    return radius * cos_theta - np.sqrt((radius * cos_theta) ** 2 - 2 * radius * epsilon
                                        + epsilon ** 2)


def check_exit(origins, directions, t, hit, centre, radius, slack):
    """Every ray hit, at most u_max before its exit and never past it."""
    assert hit.all(), f"{(~hit).sum()} of {hit.size} rays from inside missed"
    t_exit, _ = ray_sphere(origins, directions, centre, radius)
    normal = (origins + t_exit[:, None] * directions - centre) / radius
    cos_theta = dot(normal, directions)
    assert np.all(cos_theta > 0.4)                      # the bound is finite for all of them
    short = t_exit - t
    bound = concave_shortfall_bound(cos_theta, radius)
    assert np.all((short > -slack) & (short <= bound + slack))
    return short * cos_theta / EPSILON


# Camera offsets from the centre (in radii).
CASES = [(mode, omega, offset) for mode, omega in MODES for offset in (0.0, 0.3, 0.9)]


@pytest.mark.parametrize("mode, omega, offset", CASES,
                         ids=[f"{m}-{o}-offset{f}" for m, o, f in CASES])
def test_rays_from_inside_a_sphere_stop_at_most_u_max_before_the_exit(dtype, mode, omega,
                                                                      offset):
    rng = np.random.default_rng(7)
    directions = unit(rng.normal(size=(3000, 3)))
    origin = CENTRE + offset * RADIUS * np.array([1.0, 0.0, 0.0])
    sdf = build_scene_sdf([sphere(RADIUS).at(*CENTRE)], dtype)
    t, _, hit = march(origin.astype(dtype), directions.astype(dtype), sdf, 256, EPSILON,
                      100.0, relaxation=mode, omega=omega)
    check_exit(np.tile(origin, (len(directions), 1)), directions, t, hit, CENTRE, RADIUS,
               SLACK[dtype])


@pytest.mark.parametrize("omega", [1.2, 1.9])
def test_fixed_relaxation_from_the_centre_of_a_sphere_still_hits_every_ray(dtype, omega):
    """A radial ray from the centre reaches the surface at t = R after one plain step; the
    contract promises relaxation changes only how long steps are, never where rays stop."""
    rng = np.random.default_rng(7)
    directions = unit(rng.normal(size=(3000, 3)))
    sdf = build_scene_sdf([sphere(RADIUS).at(*CENTRE)], dtype)
    t, _, hit = march(CENTRE.astype(dtype), directions.astype(dtype), sdf, 256, EPSILON,
                      100.0, relaxation="fixed", omega=omega)
    check_exit(np.tile(CENTRE, (len(directions), 1)), directions, t, hit, CENTRE, RADIUS,
               SLACK[dtype])


def inside_scene(position, mode="none", omega=1.2):
    """A camera inside a sphere of radius 2 at the origin, lit from outside."""
    return Scene(camera=Camera(position=position, look_at=(0.2, -0.1, -1.0), fov=60.0),
                 render=RenderSettings(relaxation=mode, omega=omega, epsilon=EPSILON),
                 objects=(sphere(2.0),), lights=(PointLight(position=(0.0, 5.0, 5.0)),))


@pytest.mark.parametrize("mode", ["none", "fixed", "auto"])
def test_every_backend_draws_the_inside_of_the_sphere_around_an_off_centre_camera(renderer,
                                                                                   mode):
    scene = inside_scene((0.3, 0.2, 0.5), mode)
    frame = renderer.draw(scene, 48, 36)
    origin, directions = pixel_rays(scene, 48, 36)
    directions = directions.reshape(-1, 3)
    slack = 1e-12 if renderer.precision == "float64" else 2e-6
    check_exit(np.tile(origin, (len(directions), 1)), directions, frame.depth.ravel(),
               frame.hit.ravel(), np.zeros(3), 2.0, slack)
    # The normal is the outward gradient: it points along the ray, away from the eye.
    normal = frame.normal.reshape(-1, 3).astype(np.float64)
    assert np.all(dot(normal, directions) > 0.9)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, atol=1e-5)


def test_every_backend_draws_the_inside_of_the_sphere_around_a_centred_camera_with_fixed_omega(
        renderer):
    scene = inside_scene((0.0, 0.0, 0.0), "fixed", 1.2)
    frame = renderer.draw(scene, 48, 36)
    assert frame.hit.all(), f"{renderer}: {(~frame.hit).sum()} of {frame.hit.size} missed"
