"""Anti-aliasing by supersampling (`scene_model.sampling`, ``render.samples``): where the
samples go, what a pixel's colour and other buffers become, and that the cone pre-pass still
starts every sample ray before the first surface. Every backend against the reference is in
tests/equivalence (the ``aa_`` cases); here each property is checked against an analytic
answer."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run_cli
from gpu_shader.generate import generate
from marchlab import load_scene
from marchlab.render import render as render_with
from reference_cpu import cone_prepass
from reference_cpu.render import Tracer, render
from required_backends import need_backend
from scene_model.builder import (Camera, Material, RenderSettings, Scene, SolidBackground, box,
                                 sphere)
from scene_model.camera import camera_rays, pixel_ray
from scene_model.sampling import (centre_sample, pixel_max_steps, ray_offsets, rays_per_pixel,
                                  sample_offsets)


def with_render(scene: Scene, **changes) -> Scene:
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **changes))


# --- Where the samples go ----------------------------------------------------------------------

@pytest.mark.parametrize("n", range(1, 9))
def test_rotated_grid_puts_each_sample_in_its_own_column_and_row_of_the_pixel(n):
    # The n-rooks property of RGSS: the n^2 x (and y) positions are exactly the centres of
    # n^2 equal strips of the pixel, (m + 1/2) / n^2 - 1/2, so all differ, all lie inside
    # the pixel and their mean is 0 (to float64 rounding of k / n^2: 1e-15).
    offsets = sample_offsets(n, "rotated")
    strips = (np.arange(n * n) + 0.5) / n**2 - 0.5
    for axis in (0, 1):
        np.testing.assert_allclose(np.sort(offsets[:, axis]), strips, rtol=0, atol=1e-15)
    assert (np.abs(offsets) < 0.5).all()
    np.testing.assert_allclose(offsets.mean(axis=0), 0, atol=1e-15)


@pytest.mark.parametrize("n", range(1, 9))
def test_rotated_grid_is_the_regular_grid_turned_by_atan_1_over_n_and_stretched(n):
    # The closed form (n u - v, u + n v) / n^2 against the construction it stands for:
    # rotate the regular grid by theta = atan(1/n), then scale by 1 / cos(theta).
    theta = math.atan2(1, n)
    turn = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    expected = sample_offsets(n, "regular") @ turn.T / math.cos(theta)
    np.testing.assert_allclose(sample_offsets(n, "rotated"), expected, rtol=0, atol=1e-15)


def test_two_by_two_rotated_grid_is_direct3ds_standard_four_sample_pattern():
    # D3D11_STANDARD_MULTISAMPLE_PATTERN, 4 samples, in 1/16 pixel, y down (Microsoft,
    # "D3D11_STANDARD_MULTISAMPLE_QUALITY_LEVELS enumeration").
    direct3d = np.array([(-2, -6), (6, -2), (-6, 2), (2, 6)]) / 16
    np.testing.assert_array_equal(sample_offsets(2, "rotated"), direct3d)


@pytest.mark.parametrize("n", range(1, 9))
def test_regular_grid_is_the_centres_of_n_by_n_cells_with_mean_zero(n):
    offsets = sample_offsets(n, "regular")
    cells = (np.arange(n) + 0.5) / n - 0.5
    np.testing.assert_allclose(np.unique(offsets[:, 0]), cells, atol=1e-15)
    np.testing.assert_allclose(np.unique(offsets[:, 1]), cells, atol=1e-15)
    np.testing.assert_allclose(offsets.mean(axis=0), 0, atol=1e-15)


@pytest.mark.parametrize("n", range(1, 9))
@pytest.mark.parametrize("pattern", ["regular", "rotated"])
def test_the_centre_ray_is_a_sample_for_odd_n_and_one_more_ray_for_even_n(n, pattern):
    rays = ray_offsets(n, pattern)
    assert len(rays) == rays_per_pixel(n) == n * n + (n % 2 == 0)
    np.testing.assert_array_equal(rays[centre_sample(n)], (0.0, 0.0))
    np.testing.assert_array_equal(rays[:n * n], sample_offsets(n, pattern))


# --- One sample is today's frame ------------------------------------------------------------

@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_one_sample_renders_the_one_ray_pipeline_to_the_bit(precision):
    # render() with samples = 1 against Tracer.trace on the rays through the pixel centres.
    scene = load_scene("classroom")
    width, height = 40, 30
    dtype = np.dtype(precision)
    frame = render(scene, width, height, precision, path_labels=True)
    origin, directions = camera_rays(scene.camera, width, height, dtype)
    ray = Tracer(scene, dtype, path_labels=True).trace(origin, directions.reshape(-1, 3),
                                                        np.zeros(width * height, dtype))
    for name, values in ray.items():
        expected = values.astype(getattr(frame, name).dtype)
        np.testing.assert_array_equal(getattr(frame, name).reshape(expected.shape), expected,
                                      err_msg=name)
    assert frame.max_steps == scene.render.max_steps


@pytest.mark.parametrize("dialect", ["glsl", "opencl", "opencl-packets"])
def test_a_program_with_one_sample_holds_no_sampling_code(dialect):
    # The generator emits the sample loop only for samples > 1; with one sample the pattern
    # changes nothing, so the program text is the same for both.
    scene = load_scene("classroom")
    regular = generate(scene, 64, 48, dialect, path_labels=True)
    rotated = generate(with_render(scene, sample_pattern="rotated"), 64, 48, dialect,
                       path_labels=True)
    assert regular.source == rotated.source
    assert "supersample" not in regular.source and "ray_offset" not in regular.source
    two = generate(with_render(scene, samples=2), 64, 48, dialect, path_labels=True)
    assert "supersample(" in two.source


# --- A pixel's colour is the share of its samples on each side of an edge -------------------

EDGE_SIZE = (32, 96)       # tall: the edge's crossing moves 1/96 of a pixel from row to row
EDGE_MARGIN = 0.02         # pixels: samples nearer the edge than this are not judged


def edge_scene(samples: int, pattern: str) -> Scene:
    """A large thin box face-on to the camera, black behind it, shaded by its normal (0, 0, 1):
    blue where a sample hits, black where it misses. Its right edge, turned by phi =
    atan(1 / H) about the view axis, crosses the image centre and moves one pixel over the
    image's height."""
    width, height = EDGE_SIZE
    phi = math.degrees(math.atan2(1, height))
    slab = box(10.0, 10.0, 0.01).rotate(0, 0, phi).at(-10.0 / math.cos(math.radians(phi)), 0, 0)
    return Scene(camera=Camera(position=(0, 0, 5), look_at=(0, 0, 0), fov=40.0),
                 objects=(slab,), lights=(),
                 render=RenderSettings(shading="normals", epsilon=1e-5, normal_step=1e-5,
                                       background=SolidBackground(color=(0, 0, 0)),
                                       samples=samples, sample_pattern=pattern))


def edge_side(x, y):
    """Signed distance in pixels of the image point (x, y) from the edge's image, negative on
    the box's side. The box's face is parallel to the image plane, so the edge's image is
    the line cos(phi) (x - W/2) - sin(phi) (y - H/2) = 0 (the camera formula with sx, sy
    proportional to 2x - W and H - 2y)."""
    width, height = EDGE_SIZE
    phi = math.atan2(1, height)
    return math.cos(phi) * (x - width / 2) - math.sin(phi) * (y - height / 2)


def expected_coverage(n: int, pattern: str):
    """(H, W) share of each pixel's samples on the box's side, and the mask of pixels whose
    samples all lie at least EDGE_MARGIN from the edge."""
    width, height = EDGE_SIZE
    offsets = sample_offsets(n, pattern)
    x = np.arange(width)[None, :, None] + 0.5 + offsets[:, 0]
    y = np.arange(height)[:, None, None] + 0.5 + offsets[:, 1]
    side = edge_side(x, y)
    return (side < 0).mean(axis=-1), (np.abs(side) >= EDGE_MARGIN).all(axis=-1)


@pytest.mark.parametrize("n", [2, 3, 4])
@pytest.mark.parametrize("pattern", ["regular", "rotated"])
def test_a_pixels_colour_is_the_share_of_its_samples_inside_the_edge_to_1e_6(n, pattern):
    # k of the n^2 samples see (0, 0, 1), the others black: the mean is k / n^2 exactly up
    # to the float32 buffer (6e-8). Judged on every pixel whose samples are all 0.02 px or
    # more from the edge (the march and the normal resolve 1e-5 m, 0.0001 px there).
    width, height = EDGE_SIZE
    frame = render(edge_scene(n, pattern), width, height)
    share, judged = expected_coverage(n, pattern)
    assert judged.mean() > 0.95
    assert ((share > 0) & (share < 1) & judged).sum() >= height // 4   # edge pixels judged
    np.testing.assert_allclose(frame.color[..., 2][judged], share[judged], rtol=0, atol=1e-6)
    np.testing.assert_allclose(frame.color[..., :2], 0, atol=1e-6)


@pytest.mark.parametrize("n", [2, 3])
def test_a_nearly_vertical_edge_gets_n_squared_plus_1_shades_rotated_and_n_plus_1_regular(n):
    # The point of the rotated grid: its n^2 samples have n^2 different x, so as the edge
    # slides across a pixel each sample flips on its own. The regular grid's samples share
    # n columns and flip n at a time.
    width, height = EDGE_SIZE
    shades = {}
    for pattern in ("regular", "rotated"):
        frame = render(edge_scene(n, pattern), width, height)
        _, judged = expected_coverage(n, pattern)
        shades[pattern] = np.unique(np.round(frame.color[..., 2][judged] * n * n))
    np.testing.assert_array_equal(shades["rotated"], np.arange(n * n + 1))
    np.testing.assert_array_equal(shades["regular"], np.arange(n + 1) * n)


# --- The other buffers -------------------------------------------------------------------------

AOV_BACKENDS = [("numpy", "float64"), ("numpy", "float32"), ("opencl", "float32"),
                ("gpu", "float32")]


def render_on(scene, width, height, backend, precision, path_labels=False):
    if backend != "numpy":
        need_backend(backend)
    return render_with(scene, width, height, backend=backend, precision=precision,
                       path_labels=path_labels)


@pytest.mark.parametrize("backend, precision", AOV_BACKENDS)
@pytest.mark.parametrize("n, pattern", [(2, "regular"), (3, "rotated")])
def test_depth_normal_object_and_hit_are_the_centre_rays_to_the_bit(backend, precision, n,
                                                                   pattern):
    # The centre's ray is sample (n^2 - 1) / 2 for odd n and one more ray for even n: either
    # way the same computation as the one-ray frame's, in every backend.
    scene = load_scene("classroom")
    one = render_on(scene, 48, 36, backend, precision)
    many = render_on(with_render(scene, samples=n, sample_pattern=pattern), 48, 36, backend,
                     precision)
    for name in ("depth", "normal", "object_id", "hit"):
        np.testing.assert_array_equal(getattr(many, name), getattr(one, name), err_msg=name)
    assert not np.array_equal(many.color, one.color)


@pytest.mark.parametrize("n", [2, 3])
def test_the_steps_buffer_counts_every_ray_of_the_pixel(n):
    # The sum over the pixel's rays (its samples, and the centre for even n) of each ray's
    # own evaluations, as Tracer.trace counts them; the steps scale grows to match.
    scene = with_render(load_scene("classroom"), samples=n, sample_pattern="rotated")
    width, height = 40, 30
    frame = render(scene, width, height)
    tracer = Tracer(scene, np.dtype(np.float64))
    expected = np.zeros(width * height, np.int64)
    for offset in ray_offsets(n, "rotated"):
        origin, directions = camera_rays(scene.camera, width, height, np.float64, offset)
        expected += tracer.trace(origin, directions.reshape(-1, 3),
                                 np.zeros(width * height))["steps"]
    np.testing.assert_array_equal(frame.steps.reshape(-1), expected)
    assert frame.max_steps == pixel_max_steps(scene.render.max_steps, n) \
        == rays_per_pixel(n) * scene.render.max_steps


# --- The cone pre-pass starts every sample ray before the first surface ---------------------

@pytest.mark.parametrize("pattern", ["regular", "rotated"])
@pytest.mark.parametrize("width, height, tile, fov", [(64, 48, 8, 50.0), (33, 17, 16, 120.0)])
def test_each_tiles_cone_holds_every_sample_ray_of_its_pixels(pattern, width, height, tile, fov):
    # The cone holds the rays through the tile's corners, so (a cone being convex) every ray
    # through the tile: 8 x 8 samples reach within 1/16 px of a pixel's edge.
    camera = Camera(position=(0.3, 1.0, 4.0), look_at=(0.0, 0.2, 0.0), fov=fov)
    axes, tan_half = cone_prepass.tile_cones(camera, width, height, tile)
    rows, cols = np.arange(height) // tile, np.arange(width) // tile
    axis = axes[rows][:, cols]
    cos_half = 1 / np.sqrt(1 + tan_half[rows][:, cols] ** 2)
    for offset in sample_offsets(8, pattern):
        _, directions = camera_rays(camera, width, height, np.float64, offset)
        assert (np.sum(directions * axis, axis=-1) >= cos_half - 1e-12).all()


GRAIN_SIZE = 24            # six 4-pixel tiles a side


def grain_scene(prepass: str) -> Scene:
    """A white sphere 0.05 px in radius, black everywhere else, on the ray of the first of the
    8 x 8 samples of pixel (8, 8), the top-left pixel of 4-pixel tile (2, 2): the image
    point (8.0625, 8.0625), 2.74 px from the tile's centre (10, 10). The tile's cone holds
    the rays through its corners, 2.83 px out; one through its pixel centres alone would
    reach 2.12 px, and stop (`cone_prepass.MIN_PROGRESS`) only within about 2.37. No other
    sample ray and no pixel centre comes within 0.07 px of the grain. Lit by the ambient
    term alone (ka = 1, no lights), a sample sees exactly 1 or 0."""
    camera = Camera(position=(0, 0, 5), look_at=(0, 0, 0), fov=40.0)
    origin, direction = pixel_ray(camera, 8.0625, 8.0625, GRAIN_SIZE, GRAIN_SIZE)
    pixel_size = 5 * 2 * math.tan(math.radians(20)) / GRAIN_SIZE     # metres at 5 m
    grain = sphere(0.05 * pixel_size, material="white").at(*(origin + 5 * direction))
    return Scene(camera=camera, objects=(grain,), lights=(),
                 materials={"white": Material(color=(1, 1, 1), ka=1.0, kd=0.0, ks=0.0)},
                 render=RenderSettings(background=SolidBackground(color=(0, 0, 0)),
                                       samples=8, prepass=prepass, prepass_tile=4))


def assert_one_sample_sees_the_grain(frame):
    expected = np.zeros((GRAIN_SIZE, GRAIN_SIZE, 3), np.float32)
    expected[8, 8] = 1 / 64
    np.testing.assert_array_equal(frame.color, expected)


@pytest.mark.parametrize("backend, precision", AOV_BACKENDS)
@pytest.mark.parametrize("prepass", ["none", "cone"])
def test_a_sample_ray_at_a_tiles_corner_sees_a_grain_smaller_than_a_pixel(backend, precision,
                                                                          prepass):
    frame = render_on(grain_scene(prepass), GRAIN_SIZE, GRAIN_SIZE, backend, precision)
    assert_one_sample_sees_the_grain(frame)
    assert not frame.hit.any()                 # the pixel centres all miss it


def test_the_grain_check_fails_for_a_cone_that_holds_only_the_pixel_centres(monkeypatch):
    # The check above can fail: narrow every cone to the pixel centres of its tile (tan
    # theta times (T - 1) / T) and the grain's sample starts past it, seeing black.
    widest = cone_prepass.tile_cones

    def centres_only(camera, width, height, tile, dtype=np.float64):
        axes, tan_half = widest(camera, width, height, tile, dtype)
        return axes, tan_half * dtype.type((tile - 1) / tile)

    monkeypatch.setattr(cone_prepass, "tile_cones", centres_only)
    frame = render(grain_scene("cone"), GRAIN_SIZE, GRAIN_SIZE)
    with pytest.raises(AssertionError):
        assert_one_sample_sees_the_grain(frame)


# --- Bad settings -------------------------------------------------------------------------

@pytest.mark.parametrize("setting, problem", [
    ("render.samples=0", "render.samples: must be >= 1 (got 0)"),
    ("render.samples=9", "render.samples: must be <= 8 (got 9)"),
    ("render.samples=2.5", "render.samples: must be an integer (got 2.5)"),
    ("render.sample_pattern=jitter",
     "render.sample_pattern: must be one of 'regular', 'rotated' (got 'jitter')")])
def test_a_bad_sample_setting_is_one_line_naming_the_field(capsys, tmp_path, setting, problem):
    code, _, err = run_cli(capsys, "render", "classroom", "-o", tmp_path / "out.png",
                           "--size", "4x3", "--set", setting)
    assert_one_line_error(code, err)
    assert err.strip() == f"marchlab: error: classroom: {problem}"
    assert not (tmp_path / "out.png").exists()
