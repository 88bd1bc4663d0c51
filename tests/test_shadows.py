"""Shadows: a sphere of radius 1 at (0, 2, 0) hangs over the floor y = 0, lit from above.

At the level of reference_cpu.shadows, shadow rays start on the floor (pushed up by
surface_offset) and head for the light; whether the segment to the light passes through the
sphere is a closed-form question (the distance from the centre to the segment). At the level of
a rendered pixel, a floor pixel in shadow keeps only its ambient term and a lit one gets the
whole Phong sum, both computed here by hand.

Soft shadows follow Quilez's estimate: visibility = clamp(min over the march of k h / t, 0, 1),
with h the SDF value after travelling t. It is compared with the same minimum taken over a
dense grid of t (the march samples a subset of the ray, so its minimum can only be larger,
and near the closest approach its samples are dense, so only slightly larger).
"""

import dataclasses

import numpy as np
import pytest

import marchlab
from reference_cpu.scene_sdf import build_scene_sdf
from reference_cpu.shadows import hard_shadow, soft_shadow
from scene_model.builder import (Camera, Material, PointLight, RenderSettings, Scene,
                                 SolidBackground, plane, sphere)

CENTRE = np.array([0.0, 2.0, 0.0])
RADIUS = 1.0
LIGHT = np.array([0.0, 6.0, 0.0])
OFFSET = 0.01                    # surface_offset: shadow rays start this far above the floor
MAX_STEPS, EPSILON, MAX_DISTANCE = 256, 1e-3, 100.0
UP = np.array([0.0, 1.0, 0.0])


def scene_sdf():
    return build_scene_sdf([plane(), sphere(RADIUS).at(*CENTRE)])


def rays_to(light, floor_points):
    """Shadow-ray origins (offset along the floor normal), unit directions and distances."""
    origins = np.asarray(floor_points, dtype=np.float64) + OFFSET * UP
    offset = light - origins
    distance = np.linalg.norm(offset, axis=1)
    return origins, offset / distance[:, None], distance


def segment_clearance(origins, ends, centre, radius):
    """Distance from the sphere's surface to each segment origin-end (< 0: it goes through)."""
    d = ends - origins
    s = np.clip(np.einsum("ij,ij->i", centre - origins, d) / np.einsum("ij,ij->i", d, d), 0, 1)
    return np.linalg.norm(origins + s[:, None] * d - centre, axis=1) - radius


def dense_penumbra(sdf, origin, direction, distance, k, samples=200_001):
    """min over t in (0, distance] of k sdf(o + t d) / t, on a dense grid."""
    t = np.linspace(distance / samples, distance, samples)
    return (k * sdf(origin + t[:, None] * direction)[0] / t).min()


# --- hard_shadow ------------------------------------------------------------------------------

def test_floor_point_under_the_sphere_is_dark_and_one_outside_its_shadow_is_lit():
    points = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, -0.3], [5.0, 0.0, 0.0], [-3.0, 0.0, 2.0]])
    origins, to_light, distance = rays_to(LIGHT, points)
    clearance = segment_clearance(origins, np.tile(LIGHT, (4, 1)), CENTRE, RADIUS)
    assert np.all(clearance[:2] < -0.5) and np.all(clearance[2:] > 0.5)
    lit = hard_shadow(scene_sdf(), origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE)
    np.testing.assert_array_equal(lit, [0.0, 0.0, 1.0, 1.0])


def test_hard_shadow_matches_the_segment_test_on_a_grid_of_floor_points():
    x, z = np.meshgrid(np.linspace(-4, 4, 41), np.linspace(-4, 4, 41))
    points = np.column_stack([x.ravel(), np.zeros(x.size), z.ravel()])
    origins, to_light, distance = rays_to(LIGHT, points)
    clearance = segment_clearance(origins, np.tile(LIGHT, (len(points), 1)), CENTRE, RADIUS)
    lit = hard_shadow(scene_sdf(), origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE)
    # A ray clearing the sphere by less than epsilon counts as blocked; 0.01 leaves a margin.
    clear = np.abs(clearance) > 0.01
    assert (clearance[clear] < 0).sum() > 50 and (clearance[clear] > 0).sum() > 500
    np.testing.assert_array_equal(lit[clear], (clearance[clear] > 0).astype(float))


def test_occluder_beyond_the_light_casts_no_shadow():
    """With the light at y = 0.5, between the floor and the sphere (which starts at y = 1),
    the march toward the light stops at the light's distance."""
    origins, to_light, distance = rays_to(np.array([0.0, 0.5, 0.0]), [[0.0, 0.0, 0.0]])
    lit = hard_shadow(scene_sdf(), origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE)
    assert lit[0] == 1.0
    # The same ray with no distance limit (a directional light straight up) is blocked.
    lit = hard_shadow(scene_sdf(), origins, to_light, np.array([np.inf]), MAX_STEPS, EPSILON,
                      MAX_DISTANCE)
    assert lit[0] == 0.0


# --- soft_shadow ------------------------------------------------------------------------------

def test_soft_shadow_is_zero_for_a_ray_through_the_occluders_centre():
    origins, to_light, distance = rays_to(LIGHT, [[0.0, 0.0, 0.0]])
    v = soft_shadow(scene_sdf(), origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE,
                    8.0)
    assert v[0] == 0.0


def test_soft_shadow_is_one_for_a_ray_pointing_away_from_everything():
    """From (5, 0, 0) toward a light up and away from the sphere: h / t stays above
    sin(45 degrees), so k h / t > 1 for k = 8."""
    light = np.array([15.0, 10.0, 0.0])
    origins, to_light, distance = rays_to(light, [[5.0, 0.0, 0.0]])
    sdf = scene_sdf()
    assert dense_penumbra(sdf, origins[0], to_light[0], distance[0], 8.0) > 1.5
    v = soft_shadow(sdf, origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE, 8.0)
    assert v[0] == 1.0


def test_soft_shadow_grows_from_0_to_1_as_the_ray_passes_farther_outside_the_occluder():
    """Vertical rays from (x0, 0, 0) pass the sphere at distance x0 - 1 after t ~ 2, so
    visibility ~ k (x0 - 1) / 2; each value is within 0.01 above the dense minimum."""
    x0 = np.array([1.01, 1.02, 1.05, 1.1, 1.15, 1.2])
    points = np.column_stack([x0, np.zeros(len(x0)), np.zeros(len(x0))])
    origins = points + OFFSET * UP
    to_light = np.tile(UP, (len(x0), 1))
    distance = np.full(len(x0), 10.0)
    sdf = scene_sdf()
    v = soft_shadow(sdf, origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE, 8.0)
    assert np.all((v > 0) & (v < 1))
    assert np.all(np.diff(v) > 0)
    dense = np.array([dense_penumbra(sdf, o, d, 10.0, 8.0) for o, d in zip(origins, to_light)])
    assert np.all(v >= dense - 1e-6)
    assert np.all(v <= dense + 0.01)


def test_smaller_k_gives_a_wider_penumbra_with_visibility_proportional_to_k():
    """The march does not depend on k, so below the clamp visibility scales exactly with k:
    halving k halves it. A smaller k is softer in that the penumbra reaches farther into the
    lit region (rays that are fully lit at k = 8 are partly shadowed at k = 2)."""
    x0 = np.array([1.02, 1.05, 1.1, 1.2, 1.4])
    origins = np.column_stack([x0, np.full(len(x0), OFFSET), np.zeros(len(x0))])
    to_light = np.tile(UP, (len(x0), 1))
    distance = np.full(len(x0), 10.0)
    sdf = scene_sdf()
    args = (sdf, origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE)
    v8, v4, v2 = (soft_shadow(*args, k) for k in (8.0, 4.0, 2.0))
    below = v8 < 1
    np.testing.assert_allclose(v4[below], v8[below] / 2, rtol=1e-12)
    np.testing.assert_allclose(v2, np.minimum(v4 / 2, 1), rtol=1e-12)
    assert v8[-1] == 1.0 and 0 < v2[-1] < 1


def test_soft_shadow_respects_the_light_distance():
    """Light below the sphere: nothing between it and the floor, so fully visible."""
    origins, to_light, distance = rays_to(np.array([0.0, 0.5, 0.0]), [[0.0, 0.0, 0.0]])
    v = soft_shadow(scene_sdf(), origins, to_light, distance, MAX_STEPS, EPSILON, MAX_DISTANCE,
                    8.0)
    assert v[0] == 1.0


# --- Rendered pixels --------------------------------------------------------------------------

FLOOR_ALBEDO = np.array([0.5, 0.6, 0.7])
KA, KD, KS, SHININESS = 0.2, 0.6, 0.3, 10.0
AMBIENT = np.array([0.4, 0.4, 0.5])
LIGHT_COLOR = np.array([1.0, 0.9, 0.8])
WIDTH, HEIGHT = 48, 36

SCENE = Scene(
    camera=Camera(position=(0.0, 3.0, 8.0), look_at=(0.0, 0.0, 0.0), fov=50.0),
    render=RenderSettings(epsilon=1e-6, max_steps=512, max_distance=MAX_DISTANCE,
                          shadows="hard", surface_offset=OFFSET, ambient=tuple(AMBIENT),
                          background=SolidBackground((0.0, 0.0, 0.0))),
    materials={"floor": Material(color=tuple(FLOOR_ALBEDO), ka=KA, kd=KD, ks=KS,
                                 shininess=SHININESS),
               "ball": Material(color=(0.9, 0.1, 0.1))},
    lights=(PointLight(position=tuple(LIGHT), color=tuple(LIGHT_COLOR), intensity=1.0),),
    objects=(plane(material="floor"), sphere(RADIUS, material="ball").at(*CENTRE)),
)


@pytest.fixture(scope="module")
def floor_pixels():
    """For each pixel whose primary ray clearly hits the floor: hit point, view, direct light."""
    origin, d = marchlab.camera_rays(SCENE.camera, WIDTH, HEIGHT)
    d = d.reshape(-1, 3)
    t_floor = np.where(d[:, 1] < 0, -origin[1] / np.minimum(d[:, 1], -1e-300), np.inf)
    oc = origin - CENTRE
    b = d @ oc
    closest = np.sqrt(np.maximum(oc @ oc - b * b, 0))
    disc = b * b - (oc @ oc - RADIUS ** 2)
    t_ball = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    # Far floor (near the horizon) is left out: it lies beyond max_distance or needs more
    # than max_steps at grazing incidence, and a miss is not what these tests are about.
    floor = (t_floor < 30) & (t_floor < t_ball) & (np.abs(closest - RADIUS) > 0.01)
    p = origin + t_floor[floor, None] * d[floor]
    v = -d[floor]
    to_light = LIGHT - p
    dist = np.linalg.norm(to_light, axis=1)
    l = to_light / dist[:, None]
    r = -l + 2 * l[:, 1:2] * UP                                 # reflect(-L, N), N = +y
    direct = LIGHT_COLOR * (KD * l[:, 1:2] * FLOOR_ALBEDO
                            + KS * np.maximum(np.sum(r * v, axis=1), 0)[:, None] ** SHININESS)
    clearance = segment_clearance(p + OFFSET * UP, np.tile(LIGHT, (len(p), 1)), CENTRE, RADIUS)
    return dict(index=np.flatnonzero(floor), p=p, to_light=l, distance=dist, direct=direct,
                ambient=KA * FLOOR_ALBEDO * AMBIENT, clearance=clearance)


def test_shadowed_floor_pixels_have_only_the_ambient_term_and_lit_ones_full_phong(floor_pixels):
    f = floor_pixels
    frame = marchlab.render(SCENE, WIDTH, HEIGHT)
    color = frame.color.reshape(-1, 3)[f["index"]]
    shadowed, lit = f["clearance"] < -0.02, f["clearance"] > 0.02
    assert shadowed.sum() > 10 and lit.sum() > 200
    np.testing.assert_allclose(color[shadowed], np.broadcast_to(f["ambient"],
                                                                color[shadowed].shape), atol=1e-5)
    expected_lit = f["ambient"] + f["direct"][lit]
    assert expected_lit.max() < 0.99
    np.testing.assert_allclose(color[lit], expected_lit, rtol=0, atol=2e-5)
    # Without shadows the same shadowed pixels are lit: the darkness is the shadow's doing.
    no_shadows = dataclasses.replace(SCENE, render=dataclasses.replace(SCENE.render,
                                                                       shadows="none"))
    unshadowed = marchlab.render(no_shadows, WIDTH, HEIGHT).color.reshape(-1, 3)[f["index"]]
    np.testing.assert_allclose(unshadowed[shadowed], f["ambient"] + f["direct"][shadowed],
                               rtol=0, atol=2e-5)


def test_soft_shadow_pixels_scale_the_direct_light_by_the_penumbra_estimate(floor_pixels):
    """colour = ambient + visibility * direct, visibility within 0.02 of the dense minimum of
    k h / t along the pixel's shadow ray (clamped to [0, 1])."""
    f = floor_pixels
    k = 8.0
    scene = dataclasses.replace(SCENE, render=dataclasses.replace(SCENE.render, shadows="soft",
                                                                  penumbra_k=k))
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    color = frame.color.reshape(-1, 3)[f["index"]]
    sdf = scene_sdf()
    origins = f["p"] + OFFSET * UP
    # Dense minimum on a coarser grid for speed: 4001 samples over at most ~10 units.
    dense = np.array([dense_penumbra(sdf, o, l, dist, k, samples=4001)
                      for o, l, dist in zip(origins, f["to_light"], f["distance"])])
    expected_visibility = np.clip(dense, 0, 1)
    strong = f["direct"].max(axis=1) > 0.2
    visibility = ((color - f["ambient"])[:, 0] / f["direct"][:, 0])[strong]
    assert ((expected_visibility[strong] > 0.05) & (expected_visibility[strong] < 0.95)).sum() > 5
    np.testing.assert_allclose(visibility, expected_visibility[strong], rtol=0, atol=0.02)
