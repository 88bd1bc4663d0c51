"""Lighting and shading: rendered pixels against the Phong formula worked out in the test.

The scene is the plane z = 0 (outward normal +z) filling the view of a camera at z ~ 5, so every
pixel's hit point, normal and view vector are known in closed form: t = -o_z / d_z,
N = (0, 0, 1), V = -d. epsilon is 1e-7 (a plane is reached geometrically fast), so the marched
point is within ~1e-7 of the analytic one and the rendered linear colour (float32) must match
the hand-computed one within 2e-5. Material and light values are chosen so nothing clips.

Phong (reference_cpu/shading.py)::

    I = ka albedo i_a + radiance (kd max(N.L, 0) albedo + ks max(R.V, 0)^alpha),
    R = reflect(-L, N) = -L + 2 (N.L) N,  radiance = colour intensity / (c + l d + q d^2)

Blinn-Phong uses max(N.H, 0)^alpha with H = normalize(L + V).
"""

import dataclasses
import math

import numpy as np
import pytest

import marchlab
from reference_cpu import shading
from reference_cpu.lights import attenuation, light_at, spot_cone
from scene_model.builder import (Camera, DirectionalLight, Material, PointLight, RenderSettings,
                                 Scene, SolidBackground, SpotLight, plane)

WIDTH, HEIGHT = 9, 7          # odd: pixel (4, 3) looks exactly along the view axis
TOLERANCE = 2e-5

ALBEDO = np.array([0.6, 0.5, 0.4])
KA, KD, KS, SHININESS = 0.3, 0.5, 0.4, 8.0
AMBIENT = np.array([0.2, 0.3, 0.4])
MATERIAL = Material(color=tuple(ALBEDO), ka=KA, kd=KD, ks=KS, shininess=SHININESS)

POINT = PointLight(position=(1.5, 2.0, 3.0), color=(0.9, 0.8, 0.7), intensity=1.5,
                   constant=1.0, linear=0.1, quadratic=0.02)

SCENE = Scene(
    camera=Camera(position=(0.2, -0.3, 5.0), look_at=(0.0, 0.0, 0.0), fov=40.0),
    render=RenderSettings(epsilon=1e-7, max_steps=256, ambient=tuple(AMBIENT),
                          shadows="none", background=SolidBackground((0.0, 0.0, 0.0))),
    materials={"m": MATERIAL},
    lights=(POINT,),
    objects=(plane((0.0, 0.0, 1.0), 0.0, material="m"),),
)
NORMAL = np.array([0.0, 0.0, 1.0])


def with_lights(*lights, **settings):
    return dataclasses.replace(SCENE, lights=lights,
                               render=dataclasses.replace(SCENE.render, **settings))


def plane_hits(scene):
    """Analytic hit point and view vector of every pixel on the plane z = 0."""
    origin, d = marchlab.camera_rays(scene.camera, WIDTH, HEIGHT)
    t = -origin[2] / d[..., 2]
    return origin + t[..., None] * d, -d


def point_light_arriving(light, p):
    """(L, radiance) of a point light, written out from its definition."""
    offset = np.asarray(light.position) - p
    distance = np.linalg.norm(offset, axis=-1, keepdims=True)
    att = 1 / (light.constant + light.linear * distance + light.quadratic * distance ** 2)
    return offset / distance, np.asarray(light.color) * light.intensity * att


def phong(p, v, lights_arriving, model="phong", diffuse_shape=None, specular_shape=None):
    """The lit colour, term by term, for the plane's normal at points p (H, W, 3)."""
    color = KA * ALBEDO * AMBIENT * np.ones_like(p)
    for to_light, radiance in lights_arriving:
        n_dot_l = to_light @ NORMAL
        diffuse = np.maximum(n_dot_l, 0)
        if model == "phong":
            r = -to_light + 2 * n_dot_l[..., None] * NORMAL      # reflect(-L, N)
            lobe = np.sum(r * v, axis=-1)
        else:
            h = to_light + v
            lobe = (h / np.linalg.norm(h, axis=-1, keepdims=True)) @ NORMAL
        specular = np.where(n_dot_l > 0, np.maximum(lobe, 0) ** SHININESS, 0)
        if diffuse_shape is not None:
            diffuse, specular = diffuse_shape(diffuse), specular_shape(specular)
        color = color + radiance * (KD * diffuse[..., None] * ALBEDO + KS * specular[..., None])
    return color


def assert_unclipped(expected):
    """The comparison is only meaningful on colours that the [0, 1] clip leaves alone."""
    assert expected.min() > 0.01 and expected.max() < 0.99


def test_centre_pixel_matches_phong_computed_by_hand():
    """Centre pixel: hit point (0, 0, 0), V = normalize(camera), one point light."""
    frame = marchlab.render(SCENE, WIDTH, HEIGHT)
    p = np.zeros(3)
    v = np.array(SCENE.camera.position) / np.linalg.norm(SCENE.camera.position)
    d = math.dist(POINT.position, p)
    l = np.array(POINT.position) / d
    radiance = np.array(POINT.color) * POINT.intensity / (1 + 0.1 * d + 0.02 * d * d)
    n_dot_l = l[2]
    r = -l + 2 * n_dot_l * NORMAL
    expected = (KA * ALBEDO * AMBIENT
                + radiance * (KD * n_dot_l * ALBEDO + KS * max(r @ v, 0) ** SHININESS))
    assert_unclipped(expected)
    assert frame.hit[3, 4] and frame.depth[3, 4] == pytest.approx(np.linalg.norm(
        SCENE.camera.position), abs=1e-6)
    np.testing.assert_allclose(frame.color[3, 4], expected, rtol=0, atol=TOLERANCE)


def test_every_pixel_matches_phong_with_a_point_light():
    frame = marchlab.render(SCENE, WIDTH, HEIGHT)
    p, v = plane_hits(SCENE)
    expected = phong(p, v, [point_light_arriving(POINT, p)])
    assert_unclipped(expected)
    assert frame.hit.all()
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)


def test_every_pixel_matches_blinn_phong_with_the_half_vector():
    scene = with_lights(POINT, shading="blinn_phong")
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    p, v = plane_hits(scene)
    expected = phong(p, v, [point_light_arriving(POINT, p)], model="blinn_phong")
    assert_unclipped(expected)
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)
    # The two highlights differ here by more than the tolerance, so each test pins its model.
    assert np.abs(expected - phong(p, v, [point_light_arriving(POINT, p)])).max() > 0.01


def test_directional_light_has_constant_direction_and_no_attenuation():
    sun = DirectionalLight(direction=(-0.3, -0.5, -1.0), color=(0.8, 0.7, 0.6), intensity=0.9)
    scene = with_lights(sun)
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    p, v = plane_hits(scene)
    l = -np.array(sun.direction) / np.linalg.norm(sun.direction)
    radiance = np.array(sun.color) * sun.intensity
    expected = phong(p, v, [(np.broadcast_to(l, p.shape), radiance)])
    assert_unclipped(expected)
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)


def test_two_lights_add():
    sun = DirectionalLight(direction=(0.4, -0.2, -1.0), color=(0.3, 0.3, 0.5), intensity=0.5)
    scene = with_lights(POINT, sun)
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    p, v = plane_hits(scene)
    l = -np.array(sun.direction) / np.linalg.norm(sun.direction)
    expected = phong(p, v, [point_light_arriving(POINT, p),
                            (np.broadcast_to(l, p.shape), np.array(sun.color) * sun.intensity)])
    assert_unclipped(expected)
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)


def test_spot_light_pixels_match_phong_times_the_cone_factor():
    """A spot at (0.3, 0.2, 2) aimed down -z: the image spans the full, partial and dark parts
    of the cone (inner 15, outer 25 degrees)."""
    spot = SpotLight(position=(0.3, 0.2, 2.0), direction=(0.0, 0.0, -1.0), color=(1.0, 0.9, 0.8),
                     intensity=1.2, inner_angle=15.0, outer_angle=25.0, constant=1.0,
                     linear=0.05, quadratic=0.0)
    scene = with_lights(spot)
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    p, v = plane_hits(scene)
    to_light, radiance = point_light_arriving(spot, p)
    theta = np.degrees(np.arccos(np.clip(-to_light @ np.array([0.0, 0.0, -1.0]), -1, 1)))
    cos_in, cos_out = math.cos(math.radians(15.0)), math.cos(math.radians(25.0))
    cone = np.clip((np.cos(np.radians(theta)) - cos_out) / (cos_in - cos_out), 0, 1)
    assert (theta < 15).any() and ((theta > 15) & (theta < 25)).any() and (theta > 25).any()
    expected = phong(p, v, [(to_light, radiance * cone[..., None])])
    assert expected.max() < 0.99
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)
    # Outside the outer cone only the ambient term is left.
    np.testing.assert_allclose(frame.color[theta > 25], np.broadcast_to(
        KA * ALBEDO * AMBIENT, frame.color[theta > 25].shape), atol=1e-6)


# --- Lights, at the level of reference_cpu.lights ------------------------------------------

def test_spot_cone_is_one_inside_zero_outside_and_linear_in_cos_between():
    inner, outer = 20.0, 30.0
    cos_in, cos_out = math.cos(math.radians(inner)), math.cos(math.radians(outer))
    inside = np.cos(np.radians([0.0, 5.0, 19.9, 20.0]))
    outside = np.cos(np.radians([30.0, 30.1, 45.0, 90.0, 180.0]))
    np.testing.assert_array_equal(spot_cone(inside, inner, outer), 1.0)
    np.testing.assert_array_equal(spot_cone(outside, inner, outer), 0.0)
    between = np.linspace(cos_out, cos_in, 11)[1:-1]
    np.testing.assert_allclose(spot_cone(between, inner, outer), np.linspace(0, 1, 11)[1:-1],
                               rtol=0, atol=1e-12)
    # Halfway in angle (25 degrees) is not halfway: the blend is linear in cos, not the angle.
    assert spot_cone(np.cos(np.radians([25.0])), inner, outer)[0] == pytest.approx(
        (math.cos(math.radians(25.0)) - cos_out) / (cos_in - cos_out), abs=1e-12)


def test_spot_light_at_combines_cone_attenuation_colour_and_intensity():
    spot = SpotLight(position=(1.0, 4.0, -1.0), direction=(0.2, -1.0, 0.1), color=(0.5, 0.7, 0.9),
                     intensity=2.0, inner_angle=10.0, outer_angle=35.0, constant=0.5,
                     linear=0.2, quadratic=0.05)
    rng = np.random.default_rng(11)
    p = np.column_stack([rng.uniform(-4, 6, 200), np.zeros(200), rng.uniform(-6, 4, 200)])
    to_light, distance, radiance = light_at(spot, p)
    offset = np.array(spot.position) - p
    d = np.linalg.norm(offset, axis=1)
    axis = np.array(spot.direction) / np.linalg.norm(spot.direction)
    cos_theta = (-offset / d[:, None]) @ axis
    cos_in, cos_out = math.cos(math.radians(10.0)), math.cos(math.radians(35.0))
    cone = np.clip((cos_theta - cos_out) / (cos_in - cos_out), 0, 1)
    assert (cone == 1).any() and (cone == 0).any() and ((cone > 0) & (cone < 1)).any()
    expected = (np.array(spot.color) * 2.0 * (cone / (0.5 + 0.2 * d + 0.05 * d * d))[:, None])
    np.testing.assert_allclose(to_light, offset / d[:, None], atol=1e-12)
    np.testing.assert_allclose(distance, d, rtol=1e-12)
    np.testing.assert_allclose(radiance, expected, rtol=0, atol=1e-12)


def test_point_light_radiance_falls_off_as_one_over_c_plus_l_d_plus_q_d_squared():
    light = PointLight(position=(0.0, 3.0, 0.0), color=(1.0, 0.5, 0.25), intensity=3.0,
                       constant=0.7, linear=0.3, quadratic=0.11)
    heights = np.array([0.0, 1.0, 2.0, 2.5, -7.0])           # distances 3, 2, 1, 0.5, 10
    p = np.column_stack([np.zeros(5), heights, np.zeros(5)])
    to_light, distance, radiance = light_at(light, p)
    d = np.array([3.0, 2.0, 1.0, 0.5, 10.0])
    np.testing.assert_allclose(distance, d, rtol=1e-15)
    np.testing.assert_allclose(to_light, np.tile([0.0, 1.0, 0.0], (5, 1)), atol=1e-15)
    expected = 3.0 * np.array([1.0, 0.5, 0.25]) / (0.7 + 0.3 * d + 0.11 * d * d)[:, None]
    np.testing.assert_allclose(radiance, expected, rtol=1e-12)
    np.testing.assert_allclose(attenuation(d, 0.7, 0.3, 0.11), 1 / (0.7 + 0.3 * d + 0.11 * d * d),
                               rtol=1e-12)
    np.testing.assert_allclose(attenuation(d, 0.0, 0.0, 1.0), 1 / d ** 2, rtol=1e-12)


def test_directional_light_at_is_minus_its_unit_direction_at_infinite_distance():
    sun = DirectionalLight(direction=(1.0, -2.0, 2.0), color=(0.2, 0.4, 0.6), intensity=1.5)
    p = np.random.default_rng(12).normal(size=(10, 3)) * 10
    to_light, distance, radiance = light_at(sun, p)
    np.testing.assert_allclose(to_light, np.tile([-1 / 3, 2 / 3, -2 / 3], (10, 1)), atol=1e-15)
    assert np.all(np.isposinf(distance))
    np.testing.assert_allclose(radiance, np.tile([0.3, 0.6, 0.9], (10, 1)), rtol=1e-12)


# --- Specular only in front of the surface -----------------------------------------------------

def test_specular_is_zero_when_the_light_is_behind_the_surface():
    """N.L < 0 yet R.V > 0 (Phong) and N.H > 0 (Blinn): both highlights must still be 0."""
    n = np.array([[0.0, 0.0, 1.0]])
    l = np.array([[0.6, 0.0, -0.8]])                    # below the surface
    v = np.array([[-0.6, 0.0, -0.8]])                   # along R = reflect(-L, N)
    assert (shading.reflect(-l, n) @ v[0])[0] > 0.99    # unguarded, Phong would give ~1
    np.testing.assert_array_equal(shading.specular_phong(n, l, v, 10.0), [0.0])
    v_front = np.array([[0.0, 0.0, 1.0]])
    h = (l + v_front) / np.linalg.norm(l + v_front)
    assert (h @ n[0])[0] > 0.1                          # unguarded, Blinn would give > 0
    np.testing.assert_array_equal(shading.specular_blinn_phong(n, l, v_front, 1.0), [0.0])
    # In front, the same functions do light it: the guard is on N.L, not on everything.
    l_front = np.array([[0.6, 0.0, 0.8]])
    assert shading.specular_phong(n, l_front, np.array([[-0.6, 0.0, 0.8]]), 10.0)[0] == \
        pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("model", ["phong", "blinn_phong"])
def test_light_behind_the_plane_leaves_only_the_ambient_term(model):
    """A light at z = -0.1 is behind the plane for every pixel, while R.V of the unguarded
    formula is well above 0 on part of the image."""
    light = PointLight(position=(5.0, 0.0, -0.1), intensity=1.0)
    scene = with_lights(light, shading=model)
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    p, v = plane_hits(scene)
    to_light, _ = point_light_arriving(light, p)
    r = -to_light + 2 * (to_light @ NORMAL)[..., None] * NORMAL
    assert (np.sum(r * v, axis=-1) > 0.1).any()
    np.testing.assert_allclose(frame.color, np.broadcast_to(KA * ALBEDO * AMBIENT,
                                                            frame.color.shape), atol=1e-6)


# --- Toon shading -----------------------------------------------------------------------------

@pytest.mark.parametrize("bands", [2, 3, 4, 7])
def test_toon_band_gives_the_documented_levels_away_from_band_edges(bands):
    """x in [k/b, (k + 0.9)/b) is level k/(b - 1); x = 1 is the top level 1."""
    for k in range(bands):
        x = (k + np.linspace(0.0, 0.89, 50)) / bands
        np.testing.assert_allclose(shading.toon_band(x, bands), k / (bands - 1), atol=1e-12)
    assert shading.toon_band(np.array([1.0]), bands)[0] == 1.0
    assert shading.toon_band(np.array([0.0]), bands)[0] == 0.0


@pytest.mark.parametrize("bands", [2, 4, 7])
def test_toon_band_is_continuous_across_band_edges(bands):
    """The smoothstep over the last tenth of each band has slope at most 1.5 per tenth of a
    band, i.e. 15 b / (b - 1) per unit x: no jump bigger than that times the grid spacing."""
    x = np.linspace(0.0, 1.0, 200_001)
    y = shading.toon_band(x, bands)
    max_slope = 15 * bands / (bands - 1)
    assert np.abs(np.diff(y)).max() <= max_slope * (x[1] - x[0]) * (1 + 1e-9)
    # At each edge the left and right limits meet.
    for k in range(1, bands):
        edge = k / bands
        left, right = shading.toon_band(np.array([edge - 1e-12, edge + 1e-12]), bands)
        assert left == pytest.approx(right, abs=1e-9)
        assert right == pytest.approx(k / (bands - 1), abs=1e-9)


def test_toon_render_quantises_diffuse_and_specular_into_levels():
    """Where diffuse and specular sit away from the smoothstep at each band's end, the toon
    colour is Phong with x replaced by floor(x b) / (b - 1)."""
    bands = 4
    scene = with_lights(POINT, shading="toon", toon_bands=bands)
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    p, v = plane_hits(scene)
    arriving = [point_light_arriving(POINT, p)]
    level = lambda x: np.minimum(np.floor(x * bands) / (bands - 1), 1)
    expected = phong(p, v, arriving, diffuse_shape=level, specular_shape=level)
    # Pixels whose diffuse or specular value is within the smoothstep region are skipped.
    to_light, _ = arriving[0]
    n_dot_l = to_light @ NORMAL
    r = -to_light + 2 * n_dot_l[..., None] * NORMAL
    spec = np.maximum(np.sum(r * v, axis=-1), 0) ** SHININESS
    frac = lambda x: x * bands - np.floor(x * bands)
    clear = (frac(n_dot_l) < 0.88) & (frac(spec) < 0.88)
    assert clear.sum() > WIDTH * HEIGHT // 2
    assert len(np.unique(np.floor(n_dot_l[clear] * bands))) >= 2   # several diffuse bands seen
    np.testing.assert_allclose(frame.color[clear], expected[clear], rtol=0, atol=TOLERANCE)


# --- Lights with their own ambient, diffuse and specular colours -----------------------------

OWN = dataclasses.replace(POINT, ambient=(0.1, 0.05, 0.0), diffuse=(0.3, 0.6, 0.2),
                          specular=(0.1, 0.2, 0.9))


def test_a_light_with_its_own_colours_matches_the_terms_worked_out_by_hand():
    """ambient x ka albedo x attenuation + diffuse x kd max(N.L, 0) albedo x attenuation
    + specular x ks max(R.V, 0)^alpha x attenuation, each colour times intensity."""
    frame = marchlab.render(with_lights(OWN), WIDTH, HEIGHT)
    p, v = plane_hits(SCENE)
    to_light, white = point_light_arriving(dataclasses.replace(OWN, color=(1.0, 1.0, 1.0)), p)
    falloff = white / OWN.intensity
    lit_diffuse = phong(p, v, [(to_light, falloff * np.multiply(OWN.diffuse, OWN.intensity))],
                        specular_shape=lambda s: 0 * s, diffuse_shape=lambda d: d)
    lit_specular = phong(p, v, [(to_light, falloff * np.multiply(OWN.specular, OWN.intensity))],
                         diffuse_shape=lambda d: 0 * d, specular_shape=lambda s: s)
    base = KA * ALBEDO * AMBIENT
    expected = (lit_diffuse + lit_specular - base
                + KA * ALBEDO * np.multiply(OWN.ambient, OWN.intensity) * falloff)
    assert_unclipped(expected)
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)


def test_a_light_whose_own_colours_are_its_colour_renders_as_the_plain_light():
    same = dataclasses.replace(POINT, diffuse=POINT.color, specular=POINT.color)
    a = marchlab.render(with_lights(POINT), WIDTH, HEIGHT, precision="float64")
    b = marchlab.render(with_lights(same), WIDTH, HEIGHT, precision="float64")
    np.testing.assert_allclose(b.color, a.color, rtol=0, atol=1e-7)     # float32 colours


def test_a_lights_ambient_term_lights_points_in_its_shadow():
    """A ball between the light and the plane: in its shadow the diffuse and specular terms
    vanish, the light's ambient term does not."""
    from scene_model.builder import sphere
    sun = DirectionalLight(direction=(1.0, 0.0, -1.0), color=(0.5, 0.5, 0.5),
                           ambient=(0.2, 0.1, 0.05))
    scene = dataclasses.replace(with_lights(sun, shadows="hard"),
                                objects=SCENE.objects + (sphere(0.4, material="m").at(0, 0, 1.0),))
    frame = marchlab.render(scene, 41, 31, precision="float64")
    shadowed = frame.hit & (frame.object_id == 0) & (frame.color[..., 0] < 0.1)
    assert shadowed.sum() > 20
    expected = KA * ALBEDO * (AMBIENT + np.array(sun.ambient))
    np.testing.assert_allclose(frame.color[shadowed], np.broadcast_to(     # float32 colours
        expected, (shadowed.sum(), 3)), rtol=0, atol=1e-7)


def test_stripes_follow_the_sawtooth_of_the_diffuse_and_specular_terms():
    frame = marchlab.render(with_lights(POINT, shading="stripes", toon_bands=3), WIDTH, HEIGHT)
    p, v = plane_hits(SCENE)
    band = lambda x: shading.stripes_band(np.asarray(x), 3)
    expected = phong(p, v, [point_light_arriving(POINT, p)], diffuse_shape=band,
                     specular_shape=band)
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=TOLERANCE)


def test_stripes_band_is_a_continuous_sawtooth_of_n_teeth():
    x = np.linspace(0, 1, 100_001)
    y = shading.stripes_band(x, 4)
    assert np.abs(np.diff(y)).max() < 1e-3            # no jump anywhere
    teeth = np.sum((y[1:] < 0.05) & (y[:-1] >= 0.05))  # each tooth falls back once
    assert teeth == 4
    np.testing.assert_allclose(y[x < 0.2], 4 * x[x < 0.2], atol=1e-12)   # rises as 4 x
