"""Grazing rays on a floor near the horizon: how far short they stop, and how many steps.

A ray from height h above the floor y = 0, going down at an elevation angle alpha below the
horizon, meets the floor at t* = h / sin(alpha). The angle theta between the ray and the
floor's normal has |cos theta| = sin(alpha), so grazing rays are those with cos theta -> 0.

Plain sphere tracing (Hart 1996) on a plane is a geometric sequence: every step keeps the
fraction q = 1 - sin(alpha) of the height, d_i = h q^(i-1), so

- the ray stops at the first i with h q^(i-1) < epsilon: after n(q) = floor(ln(epsilon/h) /
  ln q) + 2 evaluations, a count that grows like ln(h/epsilon) / sin(alpha) at the horizon;
- it stops exactly d_n / sin(alpha) short of t*, with 0 <= d_n < epsilon: the error bound
  epsilon / |cos theta| of the contract, reached at the horizon.

Over-relaxation with a fixed omega keeps the fraction q = 1 - omega sin(alpha) instead, as
long as the empty spheres of consecutive points overlap, h + h (1 - omega sin alpha) >=
omega h, i.e. omega (1 + sin alpha) <= 2; then no step is ever taken back and the same
formulas hold with that q. "auto" has no closed form (its omega follows a moving average of
the slope); it must stop within the same bound and never take more steps than plain.

Step counts are exact in float64. In float32 the heights carry rounding errors that grow
with the number of steps (about n ulps), so a ray whose last height lies within 1e-3 of
epsilon (relative) may stop one step earlier or later; such rays are excused from the count.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from reference_cpu.march import march
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import Camera, RenderSettings, Scene, SolidBackground, plane

from .conftest import pixel_rays

EPSILON = 1e-3
HEIGHT = 1.0
# Relative closeness of the last height to epsilon under which float32 may count one step
# more or less (measured: 3.5e-4 at most over these rays). Near the horizon consecutive
# heights differ by only sin(alpha) ~ 3e-3, so this excuses about one ray in ten there.
MARGIN = {np.dtype("float64"): 1e-9, np.dtype("float32"): 1e-3}
# Slack on the stopping height h_n < epsilon (measured: 2.4e-8 in float32).
HEIGHT_SLACK = {np.dtype("float64"): 1e-12, np.dtype("float32"): 1e-7}

MODES = [("none", 1.0), ("fixed", 1.2), ("fixed", 1.5), ("fixed", 1.9)]


def plane_step_count(q, height=HEIGHT, epsilon=EPSILON):
    """n(q): evaluations until h q^(n-1) < epsilon, and how close that last test was.

    Returns the count (as float array) and min |h q^(k-1) / epsilon - 1| over the last two
    tests k = n - 1, n, the relative margin by which rounding could change the count.
    """
    n = np.floor(np.log(epsilon / height) / np.log(q)) + 2
    margin = np.minimum(np.abs(height * q ** (n - 1) / epsilon - 1),
                        np.abs(height * q ** (n - 2) / epsilon - 1))
    return n, margin


def grazing_rays(lowest=0.2, highest=20.0, n=400):
    """Unit directions going down at elevations alpha from ``lowest`` to ``highest`` degrees."""
    alpha = np.radians(np.geomspace(lowest, highest, n))
    return np.column_stack([np.cos(alpha), -np.sin(alpha), np.zeros(n)]), np.sin(alpha)


@pytest.mark.parametrize("mode, omega", MODES, ids=[f"{m}-{o}" for m, o in MODES])
def test_grazing_floor_rays_stop_short_by_less_than_epsilon_over_cos_in_the_geometric_count(
        dtype, mode, omega):
    directions, sin_alpha = grazing_rays()
    directions = directions.astype(dtype)
    sin_alpha = -directions[:, 1].astype(np.float64)        # exact for the marched direction
    sdf = build_scene_sdf([plane()], dtype)
    t, steps, hit = march(np.array([0.0, HEIGHT, 0.0], dtype), directions, sdf, 100_000,
                          EPSILON, 1e4, relaxation=mode, omega=omega)
    assert hit.all()
    # The overlap condition omega (1 + sin alpha) <= 2 holds: no step is taken back.
    overlapping = omega * (1 + sin_alpha) <= 2
    assert overlapping.sum() >= (236 if omega == 1.9 else 397)
    q = 1 - omega * sin_alpha
    n, margin = plane_step_count(q)
    counted = overlapping & (margin > MARGIN[dtype])
    assert counted.sum() >= 0.8 * overlapping.sum()
    np.testing.assert_array_equal(steps[counted], n[counted])
    assert np.all(np.abs(steps[overlapping] - n[overlapping]) <= 1)
    assert n.max() > 1000                                   # the horizon is expensive

    # Error bound: 0 <= (t* - t) sin(alpha) = h_n < epsilon.
    stop_height = (HEIGHT / sin_alpha - t) * sin_alpha
    assert np.all(stop_height >= -HEIGHT_SLACK[dtype])
    assert np.all(stop_height < EPSILON + HEIGHT_SLACK[dtype])
    if dtype == np.float64:   # exactly the last term of the sequence
        np.testing.assert_allclose(stop_height[overlapping],
                                   HEIGHT * q[overlapping] ** (n[overlapping] - 1),
                                   rtol=0, atol=1e-14)


def test_auto_relaxation_on_a_grazing_floor_stops_within_the_bound_in_fewer_steps(dtype):
    directions, _ = grazing_rays()
    directions = directions.astype(dtype)
    sin_alpha = -directions[:, 1].astype(np.float64)
    sdf = build_scene_sdf([plane()], dtype)
    t, steps, hit = march(np.array([0.0, HEIGHT, 0.0], dtype), directions, sdf, 100_000,
                          EPSILON, 1e4, relaxation="auto")
    assert hit.all()
    plain, _ = plane_step_count(1 - sin_alpha)
    # auto ends up near omega = 2 / (1 + sin alpha), which halves the count at the horizon.
    # Measured ratio auto / plain: 0.52-0.60 below 5 degrees, up to 0.74 at 20 degrees
    # (the slope's moving average spends its first steps near omega = 1).
    low = sin_alpha < math.sin(math.radians(5))
    assert np.all(steps[low] <= 0.65 * plain[low])
    assert np.all(steps <= 0.8 * plain)
    stop_height = (HEIGHT / sin_alpha - t) * sin_alpha
    assert np.all((stop_height >= -HEIGHT_SLACK[dtype])
                  & (stop_height < EPSILON + HEIGHT_SLACK[dtype]))


# --- every backend, on an image of the horizon ---------------------------------------------

WIDTH, HEIGHT_PX = 48, 36
MAX_STEPS = 96


def horizon_scene(mode="none", omega=1.5):
    """A camera 1 above an endless floor looking at the horizon, fov 12 degrees: the lower
    half of the image sees the floor at elevations up to 6 degrees; the rows next to the
    horizon need more than MAX_STEPS evaluations and run out (see test_iteration_cap)."""
    return Scene(camera=Camera(position=(0.0, HEIGHT, 0.0), look_at=(0.0, HEIGHT, -10.0),
                               fov=12.0),
                 render=RenderSettings(shading="depth", max_steps=MAX_STEPS,
                                       max_distance=1000.0, relaxation=mode, omega=omega,
                                       background=SolidBackground(color=(0.2, 0.3, 0.5))),
                 objects=(plane(),), lights=())


@pytest.mark.parametrize("mode", ["none", "fixed", "auto"])
def test_every_backend_meets_the_grazing_error_bound_and_step_counts(renderer, mode):
    """Every pixel that hits stops within epsilon / sin(alpha) of the floor; plain and fixed
    (omega = 1.5, which overlaps for sin(alpha) <= 1/3, all of this image) take exactly the
    geometric count except where rounding may move it by one; auto never more than plain."""
    scene = horizon_scene(mode)
    frame = renderer.draw(scene, WIDTH, HEIGHT_PX)
    _, directions = pixel_rays(scene, WIDTH, HEIGHT_PX)
    sin_alpha = -directions[..., 1]
    down = sin_alpha > 0
    omega = {"none": 1.0, "fixed": 1.5, "auto": 1.0}[mode]
    n, margin = plane_step_count(np.where(down, 1 - omega * sin_alpha, 0.5))
    plain, _ = plane_step_count(np.where(down, 1 - sin_alpha, 0.5))

    hit = frame.hit
    assert hit.sum() >= 250 and not hit[~down].any()
    # 1e-6: float32 rounding of the point and of the camera basis (measured 2e-8).
    stop_height = (HEIGHT / sin_alpha[hit] - frame.depth[hit]) * sin_alpha[hit]
    assert np.all((stop_height > -1e-6) & (stop_height < EPSILON + 1e-6)), renderer
    if mode == "auto":
        assert np.all(frame.steps[hit] <= plain[hit])
    else:
        sure = hit & (margin > 1e-3)
        np.testing.assert_array_equal(frame.steps[sure], n[sure])
        assert np.all(np.abs(frame.steps[hit] - n[hit]) <= 1)
