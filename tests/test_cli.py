"""The ``marchlab`` command: render, scenes, show, and how it reports a user's mistakes.

Most checks call `marchlab.cli.main(argv)` in-process (fast); a few run the real command in a
subprocess to prove end to end that a user error exits with code 2 and one stderr line, no
traceback. Images are tiny (32x24) so the whole file runs in seconds.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from cli_helpers import assert_one_line_error, leftovers, run_cli, run_marchlab

from marchlab import Frame, load_scene
import marchlab
from scene_model.files import write_atomically
from scene_model.scenefile import scene_path

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


# --- render --------------------------------------------------------------------------------------

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


# --- scenes and show -----------------------------------------------------------------------------

def test_scenes_lists_every_bundled_scene_with_its_description(capsys):
    code, out, _ = run_cli(capsys, "scenes")
    assert code == 0
    lines = out.splitlines()
    names = marchlab.bundled_scene_names()
    assert len(lines) == len(names)
    for line, name in zip(lines, names):
        listed_name, _, description = line.partition(" ")
        assert listed_name == name
        assert description.strip() == load_scene(name).description.strip()


@pytest.mark.parametrize("name", marchlab.bundled_scene_names())
def test_bundled_scene_has_a_one_line_description(name):
    description = load_scene(name).description
    assert description.strip()
    assert "\n" not in description


@pytest.mark.parametrize("name", marchlab.bundled_scene_names())
def test_show_prints_toml_that_loads_back_equal_to_the_scene(name, tmp_path, capsys):
    code, out, _ = run_cli(capsys, "show", name)
    assert code == 0
    path = tmp_path / "shown.toml"
    path.write_text(out, encoding="utf-8")
    assert load_scene(path) == load_scene(name)


def test_show_applies_set_overrides(tmp_path, capsys):
    code, out, _ = run_cli(capsys, "show", "classroom", "--set", "render.max_steps=64")
    assert code == 0
    path = tmp_path / "shown.toml"
    path.write_text(out, encoding="utf-8")
    assert load_scene(path).render.max_steps == 64 != load_scene("classroom").render.max_steps


# --- User errors: exit code 2, one line naming file, field and problem ---------------------------

TWO_OBJECTS = '[[objects]]\ntype = "plane"\n\n[[objects]]\ntype = "sphere"\n\n'
UNION = '[[objects]]\ntype = "plane"\n\n[[objects]]\ntype = "union"\n[[objects.children]]\n'

# (id, file text, field path the message names, fragment of the problem)
BAD_FILES = [
    ("negative_radius", TWO_OBJECTS + '[[objects]]\ntype = "sphere"\nradius = -1.0\n',
     "objects[2].radius", "must be positive"),
    ("nan_radius", TWO_OBJECTS + '[[objects]]\ntype = "sphere"\nradius = nan\n',
     "objects[2].radius", "finite"),
    ("inf_radius", TWO_OBJECTS + '[[objects]]\ntype = "sphere"\nradius = inf\n',
     "objects[2].radius", "finite"),
    ("inf_fov", '[camera]\nfov = -inf\n', "camera.fov", "finite"),
    ("unknown_primitive_type", TWO_OBJECTS + '[[objects]]\ntype = "sphear"\n',
     "objects[2].type", "did you mean 'sphere'?"),
    ("unknown_key", TWO_OBJECTS + '[[objects]]\ntype = "sphere"\nmaterail = "default"\n',
     "objects[2].materail", "did you mean 'material'?"),
    ("string_for_number", TWO_OBJECTS + '[[objects]]\ntype = "sphere"\nradius = "one"\n',
     "objects[2].radius", "must be a number"),
    ("float_for_integer", '[render]\nmax_steps = 64.0\n', "render.max_steps",
     "must be an integer"),
    ("two_component_vector", '[camera]\nposition = [0.0, 1.0]\n', "camera.position",
     "3 components"),
    ("unknown_material", TWO_OBJECTS + '[[objects]]\ntype = "sphere"\nmaterial = "gold"\n',
     "objects[2].material", "unknown material 'gold'"),
    ("colour_out_of_range", '[materials.default]\ncolor = [0.5, 1.2, 0.5]\n',
     "materials.default.color", "between 0 and 1"),
    ("spot_inner_not_below_outer",
     '[[lights]]\ntype = "spot"\ninner_angle = 45.0\nouter_angle = 30.0\n',
     "lights[0].inner_angle", "less than outer_angle"),
    ("camera_up_parallel_to_view",
     '[camera]\nposition = [0.0, 5.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n',
     "camera.up", "parallel"),
    ("nested_negative_radius", UNION + 'type = "sphere"\nradius = -0.5\n',
     "objects[1].children[0].radius", "must be positive"),
    ("nested_unknown_type", UNION + 'type = "sphere"\n[[objects.children]]\ntype = "tourus"\n',
     "objects[1].children[1].type", "did you mean 'torus'?"),
    ("shorthand_negative_scale", '[[objects]]\ntype = "box"\nscale = -2.0\n',
     "objects[0].scale", "must be positive"),
    ("nested_shorthand_short_position", UNION + 'type = "box"\nposition = [1.0, 2.0]\n',
     "objects[1].children[0].position", "3 components"),
]


@pytest.mark.parametrize("text, field, problem", [case[1:] for case in BAD_FILES],
                         ids=[case[0] for case in BAD_FILES])
def test_bad_scene_file_exits_2_with_one_line_naming_file_field_and_problem(
        text, field, problem, tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out.png"
    code, stdout, err = run_cli(capsys, "render", scene, "-o", out, "--size", "4x3")
    assert_one_line_error(code, err)
    assert err.startswith(f"marchlab: error: {scene}: {field}: "), err
    assert problem in err
    assert stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_missing_scene_file_exits_2_naming_it(tmp_path, capsys):
    missing = tmp_path / "missing.toml"
    code, _, err = run_cli(capsys, "render", missing, "-o", tmp_path / "out.png")
    assert_one_line_error(code, err)
    assert err.startswith(f"marchlab: error: {missing}: ")
    assert "no such file" in err


def test_toml_syntax_error_exits_2_naming_file_and_line(tmp_path, capsys):
    scene = tmp_path / "syntax.toml"
    scene.write_text('[camera]\nfov = 50.0\nposition == [0.0, 1.0, 5.0]\n')
    code, _, err = run_cli(capsys, "render", scene, "-o", tmp_path / "out.png")
    assert_one_line_error(code, err)
    assert err.startswith(f"marchlab: error: {scene}: TOML syntax error")
    assert "line 3" in err


@pytest.mark.parametrize("size_args", [["--size", "640by480"], ["--size", "0x10"],
                                       ["--size=-5x5"], ["--size", "10x0"], ["--size", "3x4x5"],
                                       ["--size", "100000x10"]],
                         ids=["word_separator", "zero_width", "negative_width", "zero_height",
                              "three_numbers", "beyond_16384"])
def test_bad_size_exits_2_with_one_line_quoting_it(size_args, tmp_path, capsys):
    out = tmp_path / "out.png"
    code, _, err = run_cli(capsys, "render", "classroom", "-o", out, *size_args)
    assert_one_line_error(code, err)
    assert "--size" in err and "WIDTHxHEIGHT" in err
    assert repr(size_args[-1].removeprefix("--size=")) in err
    assert not out.exists()


def test_negative_size_as_a_separate_argument_is_reported_as_a_bad_size(tmp_path, capsys):
    code, _, err = run_cli(capsys, "render", "classroom", "-o", tmp_path / "out.png",
                           "--size", "-5x5")
    assert_one_line_error(code, err)
    assert "'-5x5'" in err and "WIDTHxHEIGHT" in err


@pytest.mark.parametrize("assignment, field, problem", [
    ("render.max_stepz=64", "render.max_stepz", "did you mean 'max_steps'?"),
    ("objects[99].radius=1", "objects[99]", "no such entry"),
    ("objects[1].radius=-1", "objects[1].radius", "must be positive"),
], ids=["unknown_field", "index_out_of_range", "bad_value"])
def test_bad_set_exits_2_naming_scene_field_and_problem(assignment, field, problem, tmp_path,
                                                        capsys):
    out = tmp_path / "out.png"
    code, _, err = run_cli(capsys, "render", "classroom", "-o", out, "--size", "4x3",
                           "--set", assignment)
    assert_one_line_error(code, err)
    source, _, rest = err.removeprefix("marchlab: error: ").partition(": ")
    assert source in ("classroom", str(scene_path("classroom")))
    assert rest.startswith(f"{field}: ") and problem in rest
    assert not out.exists()


@pytest.mark.parametrize("assignment", ["render.max_steps", "objects[1]radius=1", "=64"],
                         ids=["no_equals_sign", "missing_dot", "no_field"])
def test_malformed_set_exits_2_quoting_the_assignment(assignment, tmp_path, capsys):
    code, _, err = run_cli(capsys, "render", "classroom", "-o", tmp_path / "out.png",
                           "--size", "4x3", "--set", assignment)
    assert_one_line_error(code, err)
    assert "classroom" in err
    assert f"--set {assignment!r}" in err


def test_unsupported_output_suffix_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out.jpg"
    code, _, err = run_cli(capsys, "render", "classroom", "-o", out, "--size", "4x3")
    assert_one_line_error(code, err)
    assert str(out) in err and "'.jpg'" in err
    assert list(tmp_path.iterdir()) == []


# A few end to end: the real command, its exit code and its whole stderr.
SUBPROCESS_ERRORS = {
    "missing_file": (["render", "missing.toml"], "missing.toml"),
    "nan_in_file": (["render", "nan.toml"], "nan.toml: objects[0].radius"),
    "bad_size": (["render", "classroom", "--size", "640by480"], "'640by480'"),
    "set_index_out_of_range": (["render", "classroom", "--set", "objects[99].radius=1"],
                               "objects[99]"),
    "unsupported_suffix": (["render", "classroom", "-o", "out.jpg"], "out.jpg"),
    "show_missing_file": (["show", "missing.toml"], "missing.toml"),
}


@pytest.mark.parametrize("argv, named", SUBPROCESS_ERRORS.values(), ids=SUBPROCESS_ERRORS.keys())
def test_user_error_in_the_real_command_exits_2_with_one_stderr_line_and_no_traceback(
        argv, named, tmp_path):
    (tmp_path / "nan.toml").write_text('[[objects]]\ntype = "sphere"\nradius = nan\n')
    result = run_marchlab(*argv, cwd=tmp_path)
    assert_one_line_error(result.returncode, result.stderr)
    assert result.stderr.startswith("marchlab")
    assert named in result.stderr
    assert result.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nan.toml"]


# --- Writing never leaves a half-written file ----------------------------------------------------

def test_failed_render_leaves_the_existing_output_untouched_and_no_temp_file(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text('[[objects]]\ntype = "sphere"\nradius = -1.0\n')
    out = tmp_path / "out.png"
    out.write_bytes(b"the previous picture")
    code, _, _ = run_cli(capsys, "render", scene, "-o", out, "--size", "4x3")
    assert code == 2
    assert out.read_bytes() == b"the previous picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "out.png"]


def test_png_encoding_failure_keeps_the_old_file_and_leaves_no_temp_file(tmp_path, capsys,
                                                                         monkeypatch):
    def broken_save(self, fp, format=None, **params):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(Image.Image, "save", broken_save)
    out = tmp_path / "out.png"
    out.write_bytes(b"the previous picture")
    code, _, err = run_cli(capsys, "render", "classroom", "-o", out, "--size", "4x3")
    assert_one_line_error(code, err)
    assert str(out) in err
    assert out.read_bytes() == b"the previous picture"
    assert leftovers(tmp_path) == []


class FailingFile:
    """A file object whose write fails half way, like a full disk."""

    def __init__(self, real):
        self.real = real

    def write(self, payload):
        self.real.write(payload[:len(payload) // 2])
        raise OSError(28, "No space left on device")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.real.close()


def test_write_atomically_removes_its_temp_file_when_the_payload_write_fails(tmp_path,
                                                                             monkeypatch):
    target = tmp_path / "image.png"
    target.write_bytes(b"old")
    real_fdopen = os.fdopen
    monkeypatch.setattr("scene_model.files.os.fdopen",
                        lambda fd, *args, **kw: FailingFile(real_fdopen(fd, *args, **kw)))
    with pytest.raises(OSError):
        write_atomically(target, b"new contents" * 100)
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["image.png"]


def test_write_atomically_renames_a_complete_temp_file_over_the_target(tmp_path, monkeypatch):
    target = tmp_path / "image.png"
    target.write_bytes(b"old")
    payload = b"new contents" * 100
    seen = {}
    real_replace = os.replace

    def spying_replace(src, dst):
        # At the moment of the rename the target is still whole and old, the temp file whole
        # and new, and both are in the same folder (so the rename is atomic).
        seen.update(src=Path(src), dst=Path(dst), target_then=target.read_bytes(),
                    temp_then=Path(src).read_bytes())
        real_replace(src, dst)

    monkeypatch.setattr("scene_model.files.os.replace", spying_replace)
    write_atomically(target, payload)
    assert seen["dst"] == target and seen["src"].parent == tmp_path
    assert seen["src"].name.startswith(".image.png.") and seen["src"].name.endswith(".tmp")
    assert seen["target_then"] == b"old" and seen["temp_then"] == payload
    assert target.read_bytes() == payload
    assert sorted(p.name for p in tmp_path.iterdir()) == ["image.png"]


def test_written_files_get_ordinary_permissions_or_keep_the_old_ones(tmp_path):
    """A new file gets 0666 less the umask like open(); a replaced file keeps its mode."""
    umask = os.umask(0o022)
    try:
        fresh = tmp_path / "fresh.png"
        write_atomically(fresh, b"new")
        assert fresh.stat().st_mode & 0o777 == 0o644
        kept = tmp_path / "kept.png"
        kept.write_bytes(b"old")
        kept.chmod(0o640)
        write_atomically(kept, b"new")
        assert kept.stat().st_mode & 0o777 == 0o640 and kept.read_bytes() == b"new"
    finally:
        os.umask(umask)


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
