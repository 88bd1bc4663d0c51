"""A single sphere rendered through marchlab.render, checked pixel by pixel against the analytic
ray-sphere intersection; and the Frame it returns (gamma-encoded image, PNG and .npz files).

The expected values use the primary rays of marchlab.camera_rays (whose formula
tests/test_camera.py checks) and the closed-form ray-sphere distance, so every tolerance is
geometric: epsilon / |cos theta| along the ray (see tests/test_march.py for the derivation).
"""

import dataclasses

import numpy as np
import pytest

from marchlab import Frame
import marchlab
from scene_model.builder import Camera, RenderSettings, Scene, SolidBackground, sphere

WIDTH, HEIGHT = 64, 48
CENTRE = np.array([0.2, -0.1, 0.0])
RADIUS = 1.0
EPSILON = 1e-3
# Pixels whose analytic ray passes within this distance of the silhouette are excluded from
# the hit-mask comparison: a ray that clears the sphere by less than epsilon "hits" it, and
# near-grazing rays may stop anywhere in the tangent band. 10 epsilon leaves a margin.
TANGENT_BAND = 10 * EPSILON

SCENE = Scene(
    camera=Camera(position=(0.3, 0.2, 4.0), look_at=(0.0, 0.0, 0.0), fov=40.0),
    render=RenderSettings(epsilon=EPSILON, max_steps=256, max_distance=50.0,
                          background=SolidBackground((0.1, 0.2, 0.3))),
    objects=(sphere(RADIUS).at(*CENTRE),),
)


def ray_sphere(origin, directions, centre, radius):
    """Nearest t > 0 on the sphere (inf on a miss) and the centre's distance to each ray line."""
    oc = origin - centre
    b = directions @ oc
    c = oc @ oc - radius ** 2
    disc = b * b - c
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    closest = np.sqrt(np.maximum(oc @ oc - b * b, 0))
    return t, closest


@pytest.fixture(scope="module")
def frame():
    return marchlab.render(SCENE, WIDTH, HEIGHT)


@pytest.fixture(scope="module")
def analytic():
    origin, directions = marchlab.camera_rays(SCENE.camera, WIDTH, HEIGHT)
    t, closest = ray_sphere(origin, directions, CENTRE, RADIUS)
    hit_point = origin + np.where(np.isfinite(t), t, 0)[..., None] * directions
    normal = (hit_point - CENTRE) / RADIUS
    cos_theta = np.abs(np.einsum("hwi,hwi->hw", normal, directions))
    return dict(origin=origin, directions=directions, t=t, hit=np.isfinite(t),
                closest=closest, normal=normal, cos_theta=cos_theta,
                band=np.abs(closest - RADIUS) < TANGENT_BAND)


def test_hit_mask_matches_analytic_mask_outside_the_tangent_band(frame, analytic):
    outside = ~analytic["band"]
    assert analytic["hit"][outside].sum() > 500 and (~analytic["hit"][outside]).sum() > 500
    np.testing.assert_array_equal(frame.hit[outside], analytic["hit"][outside])
    # Inside the band, a hit must at least be a ray that clears the sphere by < epsilon.
    assert np.all(analytic["closest"][frame.hit] < RADIUS + EPSILON)


def test_depth_is_at_most_epsilon_over_cos_theta_short_of_the_analytic_distance(frame, analytic):
    h = frame.hit & analytic["hit"]
    short = analytic["t"][h] - frame.depth[h]
    assert np.all(short >= -1e-12)                          # sphere tracing never overshoots
    assert np.all(short <= EPSILON / analytic["cos_theta"][h] + 1e-12)


def test_misses_have_infinite_depth_and_zero_normal(frame):
    assert np.all(np.isposinf(frame.depth[~frame.hit]))
    assert np.all(frame.normal[~frame.hit] == 0)
    assert np.all(np.isfinite(frame.depth[frame.hit]))


def test_object_id_is_0_on_hits_and_minus_1_on_misses(frame):
    assert frame.object_id.dtype == np.int32
    np.testing.assert_array_equal(frame.object_id, np.where(frame.hit, 0, -1))


def test_normals_match_analytic_sphere_normals_within_the_stopping_error(frame, analytic):
    """The marched point lies up to delta = epsilon / cos theta along the ray from the exact
    hit; the radial direction there differs from the analytic normal by at most delta / r
    radians. Central differences with h = 1e-3 on a sphere add O(h^2 / r^2) ~ 1e-6."""
    h = frame.hit & analytic["hit"] & ~analytic["band"]
    n = frame.normal[h]
    cos = np.clip(np.einsum("ij,ij->i", n, analytic["normal"][h]), -1, 1)
    angle = np.arccos(cos)
    bound = EPSILON / analytic["cos_theta"][h] / RADIUS + 1e-5
    assert np.all(angle <= bound)
    assert np.degrees(angle.max()) < 1.0                    # outside the band: under 1 degree
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)


def test_object_id_names_the_nearer_of_two_spheres_in_depth_first_order():
    """Spheres 0 (left, far) and 1 (right, near) overlap on screen; each hit pixel's id is the
    analytically nearer sphere's index."""
    centres = [np.array([-0.5, 0.0, -1.0]), np.array([0.6, 0.1, 0.5])]
    radii = [1.0, 0.7]
    scene = dataclasses.replace(SCENE, objects=tuple(sphere(r).at(*c)
                                                     for c, r in zip(centres, radii)))
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    origin, directions = marchlab.camera_rays(scene.camera, WIDTH, HEIGHT)
    ts, bands = [], []
    for c, r in zip(centres, radii):
        t, closest = ray_sphere(origin, directions, c, r)
        ts.append(t)
        bands.append(np.abs(closest - r) < TANGENT_BAND)
    t = np.stack(ts)
    expected = np.where(np.isfinite(t).any(axis=0), np.argmin(t, axis=0), -1)
    # Where the spheres' depths are within 10 epsilon the nearer one is not well defined.
    both = np.isfinite(t).all(axis=0)
    gap = np.subtract(t[0], t[1], out=np.full(both.shape, np.inf), where=both)
    contested = np.abs(gap) < TANGENT_BAND
    clear = ~(bands[0] | bands[1] | contested)
    assert {0, 1, -1} <= set(expected[clear].tolist())
    assert (both & clear).sum() > 50                        # sphere 1 really occludes sphere 0
    np.testing.assert_array_equal(frame.object_id[clear], expected[clear])


# --- Frame: images and files -----------------------------------------------------------------

def small_frame(color, gamma=2.2):
    h, w = color.shape[:2]
    rng = np.random.default_rng(7)
    hit = rng.random((h, w)) < 0.5
    return Frame(color=color.astype(np.float32),
                 depth=np.where(hit, rng.uniform(1, 5, (h, w)), np.inf),
                 normal=np.where(hit[..., None], rng.normal(size=(h, w, 3)), 0.0),
                 steps=rng.integers(1, 256, (h, w)).astype(np.int32),
                 object_id=np.where(hit, 0, -1).astype(np.int32), hit=hit, gamma=gamma,
                 max_steps=256, backend="numpy", precision="float64")


@pytest.mark.parametrize("gamma", [1.0, 2.2, 2.4])
def test_color_image_is_floor_of_255_c_to_the_1_over_gamma_plus_half(gamma):
    rng = np.random.default_rng(8)
    color = rng.random((20, 30, 3)).astype(np.float32)
    color[0, :3] = [[0, 0, 0], [1, 1, 1], [0.5, 0.5, 0.5]]
    image = small_frame(color, gamma).image("color")
    assert image.dtype == np.uint8 and image.shape == (20, 30, 3)
    exact = 255 * color.astype(np.float64) ** (1 / gamma) + 0.5
    expected = np.floor(exact)
    # float32 powers may round differently within 1e-3 of a rounding boundary; elsewhere the
    # 8-bit values must be exact.
    clear = np.abs(exact - np.round(exact)) > 1e-3
    assert clear.mean() > 0.99
    np.testing.assert_array_equal(image[clear], expected[clear])
    assert np.all(np.abs(image.astype(int) - expected) <= 1)
    np.testing.assert_array_equal(image[0, :2], [[0, 0, 0], [255, 255, 255]])


def test_gamma_2_image_inverts_squared_8_bit_levels_exactly():
    levels = np.arange(256, dtype=np.float64)
    color = np.repeat(((levels / 255) ** 2).reshape(16, 16, 1), 3, axis=2)
    image = small_frame(color, gamma=2.0).image("color")
    np.testing.assert_array_equal(image[..., 0], levels.reshape(16, 16))


def test_png_is_an_8_bit_rgb_image_of_the_frame_size_equal_to_image(frame, tmp_path):
    from PIL import Image
    path = tmp_path / "sphere.png"
    frame.save(path)
    with Image.open(path) as png:
        assert png.format == "PNG" and png.mode == "RGB"
        assert png.size == (WIDTH, HEIGHT)
        pixels = np.asarray(png)
    np.testing.assert_array_equal(pixels, frame.image("color"))
    # The image is not blank: the sphere and the background are both in it.
    assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 2


def test_npz_round_trips_every_buffer_exactly(frame, tmp_path):
    path = tmp_path / "sphere.npz"
    frame.save(path)
    loaded = Frame.load(path)
    for name in ("color", "depth", "normal", "steps", "object_id", "hit"):
        original, back = getattr(frame, name), getattr(loaded, name)
        assert back.dtype == original.dtype and back.shape == original.shape, name
        np.testing.assert_array_equal(back, original, err_msg=name)
    assert (loaded.gamma, loaded.max_steps, loaded.backend, loaded.precision) == \
        (frame.gamma, frame.max_steps, frame.backend, frame.precision)
    with np.load(path) as data:
        assert {"color", "depth", "normal", "steps", "object_id", "hit"} <= set(data.files)


def test_rendered_frame_colour_is_float32_in_the_unit_interval(frame):
    assert frame.color.dtype == np.float32 and frame.color.shape == (HEIGHT, WIDTH, 3)
    assert frame.color.min() >= 0 and frame.color.max() <= 1
    np.testing.assert_array_equal(frame.color[~frame.hit],
                                  np.broadcast_to(np.float32([0.1, 0.2, 0.3]),
                                                  frame.color[~frame.hit].shape))


@pytest.mark.parametrize("width, height", [(0, 10), (10, 16385), (2.5, 10), (True, 10)])
def test_render_refuses_sizes_outside_1_to_16384_in_one_line(width, height):
    with pytest.raises(marchlab.MarchlabError, match="must be an integer from 1 to 16384"):
        marchlab.render(SCENE, width, height)
