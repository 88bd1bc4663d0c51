"""``marchlab render``: the PNG and NPZ it writes equal what the Python API renders.

Most checks call `marchlab.cli.main(argv)` in-process (fast); one runs the real command in a
subprocess. Each output is compared with `marchlab.render` of the same scene, with --set
overrides applied to the scene first. Images are tiny (32x24) so the whole file runs in seconds.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from PIL import Image
from cli_helpers import run_cli, run_marchlab

from marchlab import Frame, load_scene
import marchlab


WIDTH, HEIGHT = 32, 24
SIZE = f"{WIDTH}x{HEIGHT}"
BUFFERS = ("hit", "depth", "normal", "steps", "object_id", "color")


def png_pixels(path) -> np.ndarray:
    with Image.open(path) as image:
        assert image.mode == "RGB"
        return np.asarray(image)


@pytest.fixture(scope="module")
def classroom_frame() -> Frame:
    """classroom at 32x24 through the Python API, with the CLI's default settings."""
    return marchlab.render(load_scene("classroom"), WIDTH, HEIGHT)


def test_render_command_writes_a_32x24_rgb_png_and_reports_it_on_one_line(tmp_path,
                                                                        classroom_frame):
    result = run_marchlab("render", "classroom", "-o", "tmp/x.png", "--size", SIZE, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("\n") == 1 and "tmp/x.png" in result.stdout
    pixels = png_pixels(tmp_path / "tmp" / "x.png")
    assert pixels.shape == (HEIGHT, WIDTH, 3)
    np.testing.assert_array_equal(pixels, classroom_frame.image("color"))


@pytest.mark.parametrize("aov", ["color", "depth", "normal", "steps"])
def test_png_of_an_aov_equals_frame_image_of_that_aov(aov, tmp_path, capsys, classroom_frame):
    out = tmp_path / f"{aov}.png"
    code, stdout, _ = run_cli(capsys, "render", "classroom", "-o", out, "--size", SIZE,
                              "--aov", aov)
    assert code == 0
    assert str(out) in stdout
    np.testing.assert_array_equal(png_pixels(out), classroom_frame.image(aov))


def test_aov_pngs_differ_from_each_other(classroom_frame):
    # Guards the test above: if every AOV drew the same picture, it could not tell them apart.
    images = [classroom_frame.image(aov).tobytes() for aov in ("color", "depth", "normal", "steps")]
    assert len(set(images)) == 4


def test_npz_output_holds_every_buffer_of_the_api_frame(tmp_path, capsys, classroom_frame):
    out = tmp_path / "x.npz"
    code, _, _ = run_cli(capsys, "render", "classroom", "-o", out, "--size", SIZE)
    assert code == 0
    with np.load(out) as data:
        assert set(BUFFERS) <= set(data.files)
    frame = Frame.load(out)
    for name in BUFFERS:
        np.testing.assert_array_equal(getattr(frame, name), getattr(classroom_frame, name),
                                      err_msg=name)
    assert frame.depth.dtype == np.float64
    assert (frame.gamma, frame.max_steps) == (classroom_frame.gamma, classroom_frame.max_steps)


def test_precision_float32_writes_float32_depth_to_the_npz(tmp_path, capsys):
    out = tmp_path / "x.npz"
    code, _, _ = run_cli(capsys, "render", "classroom", "-o", out, "--size", SIZE,
                         "--precision", "float32")
    assert code == 0
    frame = Frame.load(out)
    assert frame.depth.dtype == np.float32
    assert frame.precision == "float32"
    reference = marchlab.render(load_scene("classroom"), WIDTH, HEIGHT, precision="float32")
    np.testing.assert_array_equal(frame.depth, reference.depth)


def test_set_render_shading_normals_renders_the_modified_scene(tmp_path, capsys,
                                                              classroom_frame):
    out = tmp_path / "normals.png"
    code, _, _ = run_cli(capsys, "render", "classroom", "-o", out, "--size", SIZE,
                         "--set", "render.shading=normals")
    assert code == 0
    scene = load_scene("classroom")
    modified = dataclasses.replace(scene, render=dataclasses.replace(scene.render,
                                                                     shading="normals"))
    expected = marchlab.render(modified, WIDTH, HEIGHT).image("color")
    assert not np.array_equal(expected, classroom_frame.image("color"))
    np.testing.assert_array_equal(png_pixels(out), expected)


def test_set_object_radius_renders_the_modified_scene(tmp_path, capsys, classroom_frame):
    out = tmp_path / "radius.npz"
    code, _, _ = run_cli(capsys, "render", "classroom", "-o", out, "--size", SIZE,
                         "--set", "objects[1].radius=0.5")
    assert code == 0
    scene = load_scene("classroom")
    moved = scene.objects[1]                       # the file's position shorthand: Translate
    smaller = dataclasses.replace(moved, child=dataclasses.replace(moved.child, radius=0.5))
    modified = dataclasses.replace(scene, objects=(scene.objects[0], smaller,
                                                   *scene.objects[2:]))
    expected = marchlab.render(modified, WIDTH, HEIGHT)
    frame = Frame.load(out)
    assert not np.array_equal(expected.object_id, classroom_frame.object_id)
    np.testing.assert_array_equal(frame.object_id, expected.object_id)
    np.testing.assert_array_equal(frame.depth, expected.depth)
    np.testing.assert_array_equal(frame.color, expected.color)


def test_several_assignments_may_follow_one_set_or_each_its_own(tmp_path, capsys):
    one = tmp_path / "one.npz"
    two = tmp_path / "two.npz"
    assert run_cli(capsys, "render", "classroom", "-o", one, "--size", "8x6", "--set",
                   "render.shading=normals", "camera.fov=30")[0] == 0
    assert run_cli(capsys, "render", "classroom", "-o", two, "--size", "8x6",
                   "--set", "render.shading=normals", "--set", "camera.fov=30")[0] == 0
    expected = marchlab.render(load_scene("classroom", ["render.shading=normals", "camera.fov=30"]),
                               8, 6)
    for path in (one, two):
        np.testing.assert_array_equal(Frame.load(path).color, expected.color)
