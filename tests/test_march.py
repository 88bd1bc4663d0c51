"""Sphere tracing (reference_cpu.march.march) against analytic ray intersections.

A sphere and a plane have exact SDFs, so the march can be checked against closed forms:

- it never overshoots: t <= t_exact (the SDF is an exact distance, so each step stays inside an
  empty ball);
- it stops within epsilon of the surface, which along the ray is at most epsilon / |cos theta|
  short of the hit (theta between the ray and the surface normal at the hit). For a plane this
  is exact geometry; for a sphere seen from outside, a point at height s above the surface lies
  u = (r + s) cos phi - r cos theta before the hit, and u cos theta <= s (Cauchy-Schwarz on
  (r + s) cos(theta - phi) <= r + s), so the same bound holds.

The step rules of the module docstring are checked on rays whose SDF along the ray is a
closed-form sequence (head-on plane, oblique plane, ray parallel to a plane, ray leaving a
sphere radially).

The fast `march` and Hart's loop as the textbook writes it (`textbook_march`) must agree bit
for bit, on the primary and shadow rays of every bundled scene, in both precisions.
"""

import math

import numpy as np
import pytest

import marchlab
from reference_cpu.lights import light_at
from reference_cpu.march import march, textbook_march
from reference_cpu.normals import estimate_normal
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import plane, sphere
from scene_model.camera import camera_rays
from scene_model.scene import rendered_scene

EPSILON = 1e-3
CENTRE = np.array([0.3, -0.2, 0.5])
RADIUS = 1.2


def sphere_sdf():
    return build_scene_sdf([sphere(RADIUS).at(*CENTRE)])


def floor_sdf():
    """The solid y <= 0; its surface normal is +y."""
    return build_scene_sdf([plane((0.0, 1.0, 0.0), 0.0)])


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def ray_sphere(origins, directions, centre, radius):
    """Nearest t >= 0 of o + t d on the sphere (the exit point from inside); inf on a miss.

    Also returns the distance from the centre to the ray's line, for choosing clear misses.
    """
    oc = origins - centre
    b = np.einsum("ij,ij->i", oc, directions)
    c = np.einsum("ij,ij->i", oc, oc) - radius ** 2
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0))
    near, far = -b - root, -b + root
    t = np.where(near >= 0, near, far)
    t = np.where((disc >= 0) & (t >= 0), t, np.inf)
    closest = np.sqrt(np.maximum(np.einsum("ij,ij->i", oc, oc) - b * b, 0))
    return t, closest


def rays_toward_sphere(rng, n):
    """Rays from random points 3-6 units from the centre, aimed near it."""
    dirs = unit(rng.normal(size=(n, 3)))
    origins = CENTRE + dirs * rng.uniform(3, 6, size=(n, 1))
    aim = CENTRE + rng.uniform(-1.6, 1.6, size=(n, 3)) * RADIUS
    return origins, unit(aim - origins)


def test_sphere_hits_stop_within_epsilon_and_at_most_epsilon_over_cos_short_of_the_hit():
    rng = np.random.default_rng(1)
    origins, directions = rays_toward_sphere(rng, 2000)
    t_exact, closest = ray_sphere(origins, directions, CENTRE, RADIUS)
    t, steps, hit = march(origins, directions, sphere_sdf(), 512, EPSILON, 100.0)
    clear = np.abs(closest - RADIUS) > 2 * EPSILON          # not grazing the silhouette
    assert clear.sum() > 1800
    np.testing.assert_array_equal(hit[clear], np.isfinite(t_exact[clear]))

    h = hit & clear
    assert h.sum() > 500
    p = origins[h] + t[h, None] * directions[h]
    s = np.linalg.norm(p - CENTRE, axis=1) - RADIUS
    assert np.all(np.abs(s) < EPSILON)
    normal = unit(origins[h] + t_exact[h, None] * directions[h] - CENTRE)
    cos_theta = np.abs(np.einsum("ij,ij->i", normal, directions[h]))
    short = t_exact[h] - t[h]
    assert np.all(short >= -1e-12)                          # never past the surface
    assert np.all(short <= EPSILON / cos_theta + 1e-12)


def test_plane_hits_are_exactly_sdf_over_cos_short_of_the_hit():
    rng = np.random.default_rng(2)
    n = 1000
    origins = np.column_stack([rng.uniform(-5, 5, n), rng.uniform(0.5, 4, n),
                               rng.uniform(-5, 5, n)])
    # Downward rays, from steep to 80 degrees off the normal.
    theta = rng.uniform(0, math.radians(80), n)
    phi = rng.uniform(0, 2 * math.pi, n)
    directions = np.column_stack([np.sin(theta) * np.cos(phi), -np.cos(theta),
                                  np.sin(theta) * np.sin(phi)])
    t, _, hit = march(origins, directions, floor_sdf(), 1000, EPSILON, 1000.0)
    assert hit.all()
    t_exact = origins[:, 1] / np.cos(theta)
    height = origins[:, 1] + t * directions[:, 1]           # the SDF where the ray stopped
    assert np.all((height >= 0) & (height < EPSILON))
    np.testing.assert_allclose(t_exact - t, height / np.cos(theta), rtol=0, atol=1e-9)
    assert np.all(t_exact - t <= EPSILON / np.cos(theta) + 1e-12)


def test_rays_that_miss_get_infinite_t_and_hit_false():
    rng = np.random.default_rng(3)
    origins, directions = rays_toward_sphere(rng, 2000)
    t_exact, closest = ray_sphere(origins, directions, CENTRE, RADIUS)
    misses = np.isinf(t_exact) & (closest > RADIUS + 0.05)
    assert misses.sum() > 200
    t, steps, hit = march(origins[misses], directions[misses], sphere_sdf(), 512, EPSILON,
                          50.0)
    assert not hit.any()
    assert np.all(np.isposinf(t))
    assert np.all((steps >= 1) & (steps < 512))             # they escaped, not ran out


def test_ray_starting_inside_a_sphere_walks_out_to_the_inner_surface():
    """Camera inside an object: stepping by |sdf| reaches the exit at r - |o| (radial ray)."""
    rng = np.random.default_rng(4)
    n = 200
    offsets = unit(rng.normal(size=(n, 3))) * rng.uniform(0, 0.9 * RADIUS, size=(n, 1))
    origins = CENTRE + offsets
    radial = unit(offsets)
    t, _, hit = march(origins, radial, sphere_sdf(), 256, EPSILON, 100.0)
    assert hit.all()
    exit_distance = RADIUS - np.linalg.norm(offsets, axis=1)
    # Radial: the normal is along the ray (cos theta = 1).
    assert np.all((exit_distance - t >= -1e-12) & (exit_distance - t <= EPSILON + 1e-12))

    # Any direction from inside: the exit distance of the ray-sphere equation.
    directions = unit(rng.normal(size=(n, 3)))
    t, _, hit = march(origins, directions, sphere_sdf(), 256, EPSILON, 100.0)
    t_exact, _ = ray_sphere(origins, directions, CENTRE, RADIUS)
    assert hit.all()
    normal = unit(origins + t_exact[:, None] * directions - CENTRE)
    cos_theta = np.abs(np.einsum("ij,ij->i", normal, directions))
    assert np.all(np.abs(t_exact - t) <= EPSILON / cos_theta + 1e-12)


def test_origin_on_the_surface_hits_at_t_zero_after_one_evaluation():
    t, steps, hit = march(np.array([1.0, 0.0, 2.0]), unit([[0.3, -1.0, 0.2]]), floor_sdf(),
                          10, EPSILON, 100.0)
    assert hit[0] and t[0] == 0.0 and steps[0] == 1


def test_head_on_plane_is_hit_after_exactly_two_evaluations():
    """d_1 = h moves the ray exactly onto the plane; d_2 = 0 < epsilon is the hit."""
    calls = []

    def counting_sdf(p):
        calls.append(len(p))
        return floor_sdf()(p)

    t, steps, hit = march(np.array([0.0, 3.0, 0.0]), np.array([[0.0, -1.0, 0.0]]),
                          counting_sdf, 100, EPSILON, 100.0)
    assert hit[0] and t[0] == 3.0
    assert steps[0] == 2 and len(calls) == 2


@pytest.mark.parametrize("degrees, height", [(60.0, 2.0), (75.0, 1.0), (30.0, 5.0)])
def test_steps_on_an_oblique_plane_follow_the_geometric_sequence(degrees, height):
    """At angle theta to the normal each step keeps a fraction q = 1 - cos theta of the
    height: d_i = h q^(i-1), so the hit is at the first i with h q^(i-1) < epsilon, and
    t = h (1 - q^(i-1)) / cos theta. steps counts SDF evaluations (checked with a counter)."""
    theta = math.radians(degrees)
    q = 1 - math.cos(theta)
    expected_steps = math.floor(math.log(EPSILON / height) / math.log(q)) + 2
    assert height * q ** (expected_steps - 1) < EPSILON <= height * q ** (expected_steps - 2)
    calls = []

    def counting_sdf(p):
        calls.append(len(p))
        return floor_sdf()(p)

    direction = np.array([[math.sin(theta), -math.cos(theta), 0.0]])
    t, steps, hit = march(np.array([0.0, height, 0.0]), direction, counting_sdf, 1000,
                          EPSILON, 1000.0)
    assert hit[0]
    assert steps[0] == expected_steps == len(calls)
    assert t[0] == pytest.approx(height * (1 - q ** (expected_steps - 1)) / math.cos(theta),
                                 rel=1e-12)

    # One step fewer than needed: the ray runs out of steps and misses.
    t, steps, hit = march(np.array([0.0, height, 0.0]), direction, floor_sdf(),
                          expected_steps - 1, EPSILON, 1000.0)
    assert not hit[0] and np.isposinf(t[0]) and steps[0] == expected_steps - 1


def test_ray_escaping_past_max_distance_misses_on_the_step_that_crosses_it():
    """Leaving a sphere radially from distance D - r = 1: d_i = 1 + t_(i-1), so t_i = 2^i - 1.
    With max_distance 100 the escape is at step 7 (t = 127); a t equal to max_distance (127)
    is not past it, so the escape waits for step 8."""
    sdf = build_scene_sdf([sphere(1.0)])
    origin, direction = np.array([0.0, 0.0, 2.0]), np.array([[0.0, 0.0, 1.0]])
    t, steps, hit = march(origin, direction, sdf, 100, EPSILON, 100.0)
    assert not hit[0] and np.isposinf(t[0]) and steps[0] == 7
    t, steps, hit = march(origin, direction, sdf, 100, EPSILON, 127.0)
    assert not hit[0] and steps[0] == 8
    t, steps, hit = march(origin, direction, sdf, 100, EPSILON, 126.0)
    assert not hit[0] and steps[0] == 7


def test_exhausting_max_steps_is_a_miss_with_steps_equal_to_max_steps():
    """A ray parallel to the floor at height 1 has d_i = 1 forever: t_i = i never hits."""
    t, steps, hit = march(np.array([0.0, 1.0, 0.0]), np.array([[1.0, 0.0, 0.0]]), floor_sdf(),
                          10, EPSILON, 1000.0)
    assert not hit[0] and np.isposinf(t[0]) and steps[0] == 10


def test_per_ray_max_distance_array_limits_each_ray_separately():
    """Three copies of a head-on ray to a plane 5 away, limits 10, 3 and 5."""
    directions = np.tile([0.0, -1.0, 0.0], (3, 1))
    t, steps, hit = march(np.array([0.0, 5.0, 0.0]), directions, floor_sdf(), 100, EPSILON,
                          np.array([10.0, 3.0, 5.0]))
    np.testing.assert_array_equal(hit, [True, False, True])
    np.testing.assert_array_equal(t, [5.0, np.inf, 5.0])
    np.testing.assert_array_equal(steps, [2, 1, 2])


def test_per_ray_origins_give_the_same_result_as_marching_each_ray_alone():
    rng = np.random.default_rng(5)
    origins, directions = rays_toward_sphere(rng, 50)
    sdf = sphere_sdf()
    t, steps, hit = march(origins, directions, sdf, 256, EPSILON, 100.0)
    for i in range(len(origins)):
        ti, si, hi = march(origins[i], directions[i:i + 1], sdf, 256, EPSILON, 100.0)
        assert (ti[0], si[0], hi[0]) == (t[i], steps[i], hit[i])


def test_float32_march_returns_float32_t_within_float32_tolerance_of_float64():
    rng = np.random.default_rng(6)
    origins, directions = rays_toward_sphere(rng, 500)
    t_exact, closest = ray_sphere(origins, directions, CENTRE, RADIUS)
    clear = np.abs(closest - RADIUS) > 0.05
    o32, d32 = origins[clear].astype(np.float32), directions[clear].astype(np.float32)
    t, _, hit = march(o32, d32, build_scene_sdf([sphere(RADIUS).at(*CENTRE)], np.float32),
                      256, EPSILON, 100.0)
    assert t.dtype == np.float32
    np.testing.assert_array_equal(hit, np.isfinite(t_exact[clear]))
    h = hit
    normal = unit(origins[clear][h] + t_exact[clear][h, None] * directions[clear][h] - CENTRE)
    cos_theta = np.abs(np.einsum("ij,ij->i", normal, directions[clear][h]))
    # The float64 bound plus float32 rounding of t ~ 6 (a few ulps of 2^-21).
    assert np.all(np.abs(t_exact[clear][h] - t[h]) <= EPSILON / cos_theta + 1e-5)


def scene_rays(name, dtype, width=40, height=30):
    """A bundled scene's SDF and settings, and its primary and shadow rays, as the renderer
    makes them: the shadow rays start at the primary hits pushed out along the normal and run
    toward every light, each no farther than its light (a per-ray max_distance)."""
    scene = marchlab.load_scene(name)
    r = scene.render
    sdf = build_scene_sdf(rendered_scene(scene).objects, dtype)
    origin, directions = camera_rays(scene.camera, width, height, dtype)
    primary = (origin, directions.reshape(-1, 3), sdf, r.max_steps, r.epsilon, r.max_distance)
    t, _, hit = textbook_march(*primary)
    p = origin + t[hit, None] * primary[1][hit]
    normal = estimate_normal(sdf, p, dtype.type(r.normal_step), r.normal_method)
    start = p + dtype.type(r.surface_offset) * normal
    lights = [light_at(light, start) for light in scene.lights]
    to_light = np.concatenate([to_light for to_light, _, _ in lights])
    limit = np.minimum(np.concatenate([distance for _, distance, _ in lights]),
                       dtype.type(r.max_distance))
    shadow = (np.tile(start, (len(lights), 1)), to_light, sdf, r.max_steps, r.epsilon, limit)
    return primary, shadow


@pytest.mark.parametrize("precision", ["float64", "float32"])
@pytest.mark.parametrize("name", marchlab.bundled_scene_names(meshes=False))
def test_fast_march_is_bit_identical_to_the_textbook_march_on_every_bundled_scene(name,
                                                                                 precision):
    ended = []
    for rays in scene_rays(name, np.dtype(precision)):
        expected = textbook_march(*rays)
        got = march(*rays)
        for output, a, b in zip(("t", "steps", "hit"), got, expected):
            np.testing.assert_array_equal(a, b, err_msg=output, strict=True)   # dtype too
        t, steps, hit = expected
        ended.append(hit)
        assert len(np.unique(steps)) > 5
    # Rays end both ways, so every rule of the loop took part (in a scene seen from above,
    # such as the bowl, every primary ray hits and only shadow rays escape).
    ended = np.concatenate(ended)
    assert ended.any() and not ended.all()
