"""A smooth union with a large blend width k: a bound, not a distance, and never skipped.

Quilez's polynomial smooth minimum, smin(a, b) = mix(b, a, h) - k h (1 - h) with
h = clamp(1/2 + (b - a) / (2k), 0, 1), lies below min(a, b) by up to k/4, so for a large k it
underestimates the distance to its surface by a lot: a bound, not an exact SDF. Sphere
tracing needs no more than a 1-Lipschitz bound, and this one is 1-Lipschitz for every k:
where 0 < h < 1, d smin / dh = (a - b) - k (1 - 2h) = 0 (as a - b = k (1 - 2h) there), so
grad smin = h grad a + (1 - h) grad b, a convex combination of unit vectors, of length <= 1;
where h is clamped it is a or b. (One might expect it not to be 1-Lipschitz; the sampled
difference quotients below stay <= 1 for k up to 16, and are reported at the end of the run.)

So the renderer must not skip the surface: a ray stops at the first root t_root of the
field along it or before it, where the field is below epsilon, at most about
epsilon / |f'(t_root)| short (the field falls with slope f' along the ray near the root; for
an exact SDF |f'| = |cos theta|). Hit iff the ray has a root, outside a tangent band of rays
whose smallest sampled value along the ray is within Delta/2 + 2 epsilon of 0 (Delta, the
sampling step of the reference root finder: a 1-Lipschitz field cannot dip deeper than
Delta/2 between samples). The roots are found in float64 by dense sampling and bisection.

The blob: a sphere of radius 0.5 at x = -0.6 joined to a box of half-size 0.3 at x = 0.6.
Measured: shortfall |f'| / epsilon <= 0.9992 in every mode and precision; no mask difference.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from sdf_reference import first_roots as roots_along_rays

from reference_cpu.march import march
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import Camera, PointLight, RenderSettings, Scene, box, sphere

from .conftest import pixel_rays, unit

EPSILON = 1e-3
REACH = 8.0                 # rays are sampled over t in [0, REACH]
SAMPLES = 2000
DELTA = REACH / SAMPLES


def blob(k):
    return sphere(0.5).at(-0.6, 0.0, 0.0).smooth_union(box(0.3).at(0.6, 0.0, 0.0), k=k)


@pytest.mark.parametrize("k", [0.25, 1.0, 4.0, 16.0])
def test_smooth_union_difference_quotients_are_at_most_1_for_any_k(k, report):
    """|f(p) - f(q)| <= |p - q| (1 + 1e-9) on 250 000 pairs: random pairs at distances 1e-6
    to 1, and consecutive points of walks through the blend."""
    f = build_scene_sdf([blob(k)])
    rng = np.random.default_rng(11)
    p = rng.uniform(-3, 3, (150_000, 3))
    q = p + unit(rng.normal(size=p.shape)) * 10 ** rng.uniform(-6, 0, (len(p), 1))
    # Walks between the two shapes, through the middle of the blend.
    ends = rng.uniform(-1.5, 1.5, (100, 2, 3))
    s = np.linspace(0, 1, 1001)[:, None, None]
    walk = (ends[:, 0] + s * (ends[:, 1] - ends[:, 0])).reshape(-1, 100, 3)
    p = np.concatenate([p, walk[:-1].reshape(-1, 3)])
    q = np.concatenate([q, walk[1:].reshape(-1, 3)])
    quotient = np.abs(f(p)[0] - f(q)[0]) / np.linalg.norm(p - q, axis=1)
    report(f"max sampled difference quotient, k = {k}", float(quotient.max()))
    assert quotient.max() <= 1 + 1e-9
    assert quotient.max() > 0.99            # the sampling reaches the steepest directions
    # The bound is k/4 below the union at most, and reaches it: the surface does grow.
    union = build_scene_sdf([sphere(0.5).at(-0.6, 0.0, 0.0) | box(0.3).at(0.6, 0.0, 0.0)])
    gap = union(p)[0] - f(p)[0]
    assert gap.min() >= -1e-12 and gap.max() <= k / 4 + 1e-12


@functools.cache
def first_roots(k, origins_key, directions_key):
    """The first root of the blob's field along each ray (inf if none) and the smallest
    sampled value, in float64 (see the module docstring)."""
    origins = np.frombuffer(origins_key).reshape(-1, 3)
    directions = np.frombuffer(directions_key).reshape(-1, 3)
    f = build_scene_sdf([blob(k)])
    root, lowest = roots_along_rays(f, origins, directions, REACH, SAMPLES)
    # |f'| at the root, by a central difference along the ray.
    r = np.where(np.isfinite(root), root, 0.0)[:, None]
    slope = np.abs(f(origins + (r + 1e-7) * directions)[0]
                   - f(origins + (r - 1e-7) * directions)[0]) / 2e-7
    return root, lowest, slope


def check_against_roots(k, origins, directions, t, hit, slack):
    """Hit iff a root (outside the tangent band), never past it, short by <= eps / |f'|."""
    origins = np.ascontiguousarray(np.broadcast_to(origins, directions.shape), np.float64)
    directions = np.ascontiguousarray(directions, np.float64)
    root, lowest, slope = first_roots(k, origins.tobytes(), directions.tobytes())
    band = np.abs(lowest) < DELTA / 2 + 2 * EPSILON
    has_root = np.isfinite(root)
    assert has_root.sum() >= 150 and (~has_root).sum() >= 150 and band.sum() <= 20
    wrong = (hit != has_root) & ~band
    assert not wrong.any(), f"{wrong.sum()} rays: smallest sampled values {lowest[wrong][:5]}"
    both = hit & has_root
    short = root[both] - t[both]
    assert np.all(short >= -slack), "a ray stopped past the first root: it skipped the surface"
    assert np.all(short * slope[both] <= EPSILON * 1.01 + slack)
    # Where it stopped, the field is below epsilon.
    f = build_scene_sdf([blob(k)])
    stopped = f(origins[hit] + t[hit, None] * directions[hit])[0]
    assert np.all(np.abs(stopped) < EPSILON + slack)


@pytest.mark.parametrize("mode, omega", [("none", 1.0), ("fixed", 1.9), ("auto", 1.0)])
@pytest.mark.parametrize("k", [0.5, 2.0, 4.0])
def test_march_stops_at_or_before_the_first_root_of_a_large_k_smooth_union(dtype, k, mode,
                                                                          omega):
    rng = np.random.default_rng(12)
    origins = unit(rng.normal(size=(600, 3))) * 5
    # Aim around the blob, whose solid reaches k/4 beyond the two shapes: about half hit.
    aim = rng.uniform(-1, 1, (600, 3)) * (np.array([1.2, 0.6, 0.6]) + k / 4) * 1.4
    directions = unit(aim - origins)
    sdf = build_scene_sdf([blob(k)], dtype)
    t, _, hit = march(origins.astype(dtype), directions.astype(dtype), sdf, 2000, EPSILON,
                      20.0, relaxation=mode, omega=omega)
    check_against_roots(k, origins, directions, t, hit, 1e-9 if dtype == np.float64 else 4e-6)


def blob_scene(k, mode):
    return Scene(camera=Camera(position=(0.5, 1.2, 3.5), look_at=(0.0, 0.0, 0.0), fov=50.0),
                 render=RenderSettings(relaxation=mode, epsilon=EPSILON, max_steps=512),
                 objects=(blob(k),), lights=(PointLight(position=(2.0, 4.0, 3.0)),))


@pytest.mark.parametrize("mode", ["none", "auto"])
def test_every_backend_draws_the_large_k_blend_without_skipping_it(renderer, mode):
    k = 2.0
    scene = blob_scene(k, mode)
    frame = renderer.draw(scene, 48, 36)
    origin, directions = pixel_rays(scene, 48, 36)
    check_against_roots(k, origin, directions.reshape(-1, 3), frame.depth.ravel(),
                        frame.hit.ravel(), 1e-9 if renderer.precision == "float64" else 4e-6)
