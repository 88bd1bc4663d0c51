"""The iteration cap: rays that cannot finish in max_steps evaluations.

The contract: after ``max_steps`` evaluations without a hit a ray misses, with steps =
max_steps and depth inf. Two kinds of ray never finish in time:

- a ray that passes a sphere of radius R at a clearance c just above epsilon: near the
  tangent point the distance is about c + x^2 / (2 R) at x along the ray, so the steps there
  number about the integral of dx / (c + x^2 / 2R), pi sqrt(2 R / c): 134 for R = 1 and
  c = 1.1e-3, however far the ray then has to go;
- rays next to the horizon of a floor seen from height h. Below it, the plain count is
  n(q) = floor(ln(epsilon/h) / ln q) + 2 with q = 1 - sin(alpha) (test_grazing_floor.py).
  Above it, at elevation s = d_y > 0, the distance to the floor grows: d_i = h + s t_(i-1),
  so t_n = h ((1 + s)^n - 1) / s and the ray escapes at the first n with t_n > max_distance.
  Both counts pass any cap as alpha -> 0.

Every backend must classify such a ray the same way: a pixel runs out (miss, steps =
max_steps) exactly where its count exceeds max_steps. For the plain march the counts are
the closed forms above; in float32, pixels whose last test lies within 1e-3 (relative) of
its threshold may move by one step and are excused (8% of this image). Relaxed marches
have no closed form: the reference is the NumPy float64 march with an unlimited cap, and
pixels whose count lies within 1 ("fixed") or 8 ("auto") of max_steps are excused: the
auto slope average turns rounding differences into counts up to 7 apart between float32
and float64 (measured here; 6% of the image is excused).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from reference_cpu.march import march
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import plane, sphere

from .conftest import pixel_rays
from .test_grazing_floor import HEIGHT, HEIGHT_PX, MAX_STEPS, WIDTH, horizon_scene, plane_step_count

MAX_DISTANCE = 1000.0       # that of horizon_scene


def escape_step_count(s, height=HEIGHT, limit=MAX_DISTANCE):
    """First n with h ((1 + s)^n - 1) / s > limit, for rays rising at d_y = s > 0, and the
    relative margin of the last two tests (as `plane_step_count`)."""
    n = np.floor(np.log1p(limit * s / height) / np.log1p(s)) + 1
    t = lambda k: height * np.expm1(k * np.log1p(s)) / s
    margin = np.minimum(np.abs(t(n) / limit - 1), np.abs(t(n - 1) / limit - 1))
    return n, margin


@pytest.mark.parametrize("mode, omega", [("none", 1.0), ("fixed", 1.9), ("auto", 1.0)])
def test_ray_grazing_a_sphere_runs_out_of_steps_and_misses(dtype, mode, omega):
    """Clearance 1.1e-3 past a unit sphere: about pi sqrt(2 R / c) = 134 steps near the
    tangent point (measured 137 plain, 138 fixed, 76 auto to escape). With a cap of 64 the
    ray misses with steps = 64 in every mode and precision."""
    clearance = 1.1e-3
    sdf = build_scene_sdf([sphere(1.0)], dtype)
    origin = np.array([-5.0, 1.0 + clearance, 0.0], dtype)
    direction = np.array([[1.0, 0.0, 0.0]], dtype)
    t, steps, hit = march(origin, direction, sdf, 100_000, 1e-3, 20.0, relaxation=mode,
                          omega=omega)
    assert not hit[0] and steps[0] < 100_000                    # it escapes in the end
    if mode == "none":
        assert steps[0] >= math.pi * math.sqrt(2 / clearance)
    t, steps, hit = march(origin, direction, sdf, 64, 1e-3, 20.0, relaxation=mode,
                          omega=omega)
    assert not hit[0] and np.isposinf(t[0]) and steps[0] == 64


def test_plain_horizon_counts_exceed_the_cap_on_both_sides_of_the_horizon():
    """The closed forms agree with the float64 march with an unlimited cap, and the pixels
    next to the horizon need more than MAX_STEPS on both sides of it."""
    scene = horizon_scene("none")
    origin, directions = pixel_rays(scene, WIDTH, HEIGHT_PX)
    _, needed, _ = march(origin, directions.reshape(-1, 3), build_scene_sdf([plane()]),
                         100_000, 1e-3, MAX_DISTANCE)
    expected, margin = analytic_counts(directions)
    sure = margin > 1e-9
    assert sure.sum() >= 0.99 * sure.size
    np.testing.assert_array_equal(needed.reshape(HEIGHT_PX, WIDTH)[sure], expected[sure])
    rising = directions[..., 1] > 0
    assert (expected[rising] > MAX_STEPS).sum() >= 100
    assert (expected[~rising] > MAX_STEPS).sum() >= 100


def analytic_counts(directions):
    """The plain count of every pixel of the horizon image and its rounding margin."""
    s = directions[..., 1]
    rising = s > 0
    below, below_margin = plane_step_count(np.where(rising, 0.5, 1 + s))
    above, above_margin = escape_step_count(np.where(rising, s, 1.0))
    return (np.where(rising, above, below), np.where(rising, above_margin, below_margin))


@pytest.mark.parametrize("mode", ["none", "fixed", "auto"])
def test_every_backend_runs_out_exactly_where_the_count_exceeds_max_steps(renderer, mode):
    scene = horizon_scene(mode)
    frame = renderer.draw(scene, WIDTH, HEIGHT_PX)
    origin, directions = pixel_rays(scene, WIDTH, HEIGHT_PX)
    if mode == "none":
        needed, margin = analytic_counts(directions)
        excused = margin < (1e-3 if renderer.precision == "float32" else 1e-9)
    else:
        _, needed, _ = march(origin, directions.reshape(-1, 3), build_scene_sdf([plane()]),
                             100_000, 1e-3, MAX_DISTANCE, relaxation=mode, omega=1.5)
        needed = needed.reshape(HEIGHT_PX, WIDTH)
        excused = np.abs(needed - MAX_STEPS) <= (1 if mode == "fixed" else 8)
    ran_out = ~frame.hit & (frame.steps == MAX_STEPS)
    expected = needed > MAX_STEPS
    assert expected.sum() >= 400
    wrong = (ran_out != expected) & ~excused
    assert not wrong.any(), (f"{renderer} {mode}: {wrong.sum()} pixels classified against "
                             f"their count, e.g. counts {needed[wrong][:5]}")
    assert excused.sum() <= 0.1 * excused.size
    assert np.all(np.isposinf(frame.depth[ran_out]))
    # Where the count is within the cap, the ray hits or escapes on that very step.
    on_time = ~expected & ~excused
    if mode == "none":
        np.testing.assert_array_equal(frame.steps[on_time], needed[on_time])
