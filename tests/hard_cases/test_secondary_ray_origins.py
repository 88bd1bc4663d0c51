"""Shadow-ray and reflection-ray origins: acne, and the offset that cures it.

A primary ray stops at a point p within epsilon of the surface: on the floor y = 0, at a
height p_y in [0, epsilon). Secondary rays start at p + surface_offset N. Their first
evaluation there sees |sdf| = p_y + surface_offset N_y (the floor is the nearest surface),
so with nothing else in the way:

- if p_y + surface_offset N_y < epsilon, the secondary ray "hits" at t = 0, its own
  starting surface: a shadow ray blocks its light (shadow acne), a mirror ray sees the
  mirror itself;
- otherwise the ray leaves the floor, which only grows more distant, and escapes: the
  light is visible and the mirror shows the sky.

So with surface_offset = 0 every floor point is in acne; with surface_offset >= epsilon none
is; between them, exactly the points with p_y < epsilon - surface_offset N_y, which the
tests predict pixel by pixel from the depth and normal each backend returns (pixels within
2e-6 of the threshold, where rounding decides, are excused). Relaxed marches decide the
first point as the plain march does, so they agree. A reflection ray that hits itself stops
at t = 0 at p' = p + surface_offset N and lights that point, whose own shadow ray starts at
height p_y + 2 surface_offset N_y.
"""

from __future__ import annotations

import numpy as np
import pytest

from reference_cpu.march import march
from reference_cpu.normals import estimate_normal
from reference_cpu.scene_sdf import build_scene_sdf
from reference_cpu.shadows import hard_shadow
from scene_model.builder import (Camera, DirectionalLight, Material, RenderSettings, Scene,
                                 SolidBackground, plane)

from .conftest import pixel_rays, unit

EPSILON = 1e-3
OFFSETS = [0.0, 0.25 * EPSILON, 0.5 * EPSILON, EPSILON, 2 * EPSILON, 0.01]
ROUNDING = 2e-6
TO_LIGHT = unit([0.3, 1.0, 0.2])


def floor_hits(dtype, n=4000):
    """Points where oblique rays from above stop on the floor, and their normals."""
    rng = np.random.default_rng(3)
    origins = np.column_stack([rng.uniform(-3, 3, n), rng.uniform(0.5, 3, n),
                               rng.uniform(-3, 3, n)]).astype(dtype)
    directions = unit(np.column_stack([rng.normal(size=n), -rng.uniform(0.2, 1, n),
                                       rng.normal(size=n)])).astype(dtype)
    sdf = build_scene_sdf([plane()], dtype)
    t, _, hit = march(origins, directions, sdf, 1000, EPSILON, 100.0)
    assert hit.all()
    p = origins + t[:, None] * directions
    return sdf, p, estimate_normal(sdf, p, dtype.type(1e-3))


@pytest.mark.parametrize("mode", ["none", "fixed", "auto"])
@pytest.mark.parametrize("offset", OFFSETS)
def test_shadow_ray_blocks_its_light_exactly_where_its_origin_is_within_epsilon(dtype, offset,
                                                                                mode, report):
    sdf, p, normal = floor_hits(dtype)
    origins = p + dtype.type(offset) * normal
    to_light = np.tile(TO_LIGHT, (len(p), 1)).astype(dtype)
    visible = hard_shadow(sdf, origins, to_light, np.full(len(p), np.inf, dtype), 256,
                          EPSILON, 100.0, relaxation=mode, omega=1.9)
    height = p[:, 1].astype(np.float64) + offset * normal[:, 1].astype(np.float64)
    acne = height < EPSILON
    decided = np.abs(height - EPSILON) > ROUNDING
    np.testing.assert_array_equal(visible[decided] == 0, acne[decided])
    if offset == 0:
        assert acne.all()
    if offset >= EPSILON:
        assert not acne.any()
    if mode == "none" and dtype == np.float64:
        report(f"floor points in shadow acne, surface_offset = {offset:g}", float(acne.mean()))


@pytest.mark.parametrize("offset", OFFSETS)
def test_reflection_ray_sees_its_own_mirror_exactly_where_its_origin_is_within_epsilon(
        dtype, offset):
    sdf, p, normal = floor_hits(dtype)
    origins = p + dtype.type(offset) * normal
    rng = np.random.default_rng(4)
    incoming = unit(np.column_stack([rng.normal(size=len(p)), -rng.uniform(0.2, 1, len(p)),
                                     rng.normal(size=len(p))])).astype(dtype)
    mirrored = incoming - 2 * np.sum(incoming * normal, axis=1)[:, None] * normal
    t, steps, hit = march(origins, mirrored, sdf, 256, EPSILON, 100.0)
    height = p[:, 1].astype(np.float64) + offset * normal[:, 1].astype(np.float64)
    decided = np.abs(height - EPSILON) > ROUNDING
    np.testing.assert_array_equal(hit[decided], (height < EPSILON)[decided])
    assert np.all(t[hit] == 0) and np.all(steps[hit] == 1)      # the mirror itself, at once


def mirror_floor_scene(offset, skip_own=False):
    return Scene(camera=Camera(position=(0.0, 1.5, 3.0), look_at=(0.0, 0.0, 0.0), fov=50.0),
                 render=RenderSettings(shadows="hard", reflection_depth=1,
                                       surface_offset=offset, epsilon=EPSILON,
                                       shadow_skip_own=skip_own,
                                       background=SolidBackground(color=(0.3, 0.5, 0.9))),
                 materials={"mirror": Material(color=(0.6, 0.6, 0.6), kr=0.5)},
                 objects=(plane(material="mirror"),),
                 lights=(DirectionalLight(direction=tuple(-TO_LIGHT)),))


@pytest.mark.parametrize("skip_own", [False, True], ids=["floor_kept", "floor_skipped"])
@pytest.mark.parametrize("offset", [0.0, 0.5 * EPSILON, 2 * EPSILON, 0.01])
def test_every_backend_labels_acne_and_self_reflection_exactly_where_predicted(renderer,
                                                                              offset, skip_own):
    """The path label of a floor pixel records, at each bounce, the object hit and whether
    the light's shadow ray was blocked: 64 + blocked for the first bounce, then the sky
    (id -1) or the floor again with its own blocked bit, folded into the first; the pixel's
    label is the sum of the two bounces' (reference_cpu/render.py, Tracer.lit_color).

    With render.shadow_skip_own a shadow ray leaves the floor (convex: a half-space) out of
    its march, so no shadow ray is blocked at any offset, 0 included: no acne. A mirror ray
    keeps its own object, and still sees the mirror where it starts within epsilon."""
    scene = mirror_floor_scene(offset, skip_own)
    frame = renderer.draw(scene, 48, 36)
    origin, directions = pixel_rays(scene, 48, 36)
    hit = frame.hit
    assert hit.sum() >= 800
    p_y = origin[1] + frame.depth[hit].astype(np.float64) * directions[hit][:, 1]
    n_y = frame.normal[hit][:, 1].astype(np.float64)
    first = p_y + offset * n_y                   # origin height of both secondary rays
    second = p_y + 2 * offset * n_y              # shadow ray of the reflected point
    self_hit = first < EPSILON
    acne, acne_again = (first < EPSILON) & (not skip_own), (second < EPSILON) & (not skip_own)
    first_bounce = 64 + acne.astype(np.uint32)
    second_bounce = np.where(self_hit, (first_bounce * 1009 + 1) * 64 + acne_again,
                             first_bounce * 1009 * 64) & 0xFFFFFF
    label = (first_bounce + second_bounce) & 0xFFFFFF
    decided = (np.abs(first - EPSILON) > ROUNDING) & (np.abs(second - EPSILON) > ROUNDING)
    assert decided.mean() > 0.97
    np.testing.assert_array_equal(frame.path[hit][decided], label[decided])
    if skip_own:
        # The labels held no blocked bit; the mirror rays still see the floor below epsilon.
        assert offset >= EPSILON or self_hit.mean() > 0.05
    elif offset == 0:
        assert acne.all()
    elif offset >= EPSILON:
        assert not acne.any()
    else:
        assert 0.05 < acne.mean() < 0.5          # a speckle: measured 0.116 of the pixels
