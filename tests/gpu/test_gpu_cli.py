"""``marchlab shader``, ``marchlab compare`` and ``marchlab render --backend gpu``, and the gates
of `marchlab.compare` that ``compare`` applies.

Commands run in-process through `marchlab.cli.main`. ``shader`` and the usage errors need no
OpenGL; the commands that draw take the ``gpu`` fixture (tests/gpu/conftest.py).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from PIL import Image
from cli_helpers import assert_one_line_error, run_cli

import marchlab
from marchlab.compare import Gates, compare_frames, failures, gates_against
from scene_model.builder import Camera, Scene, sphere

SIZE = "48x36"


# --- marchlab shader ---------------------------------------------------------------------

def test_shader_prints_a_whole_program(capsys):
    code, out, err = run_cli(capsys, "shader", "classroom")
    assert code == 0 and err == ""
    assert out.startswith("#version 330")
    assert "void main()" in out and re.search(r"^real scene_sdf\(vec3 p\)", out, re.M)
    assert "hard_shadow_pair(" in out and "apply_fog(" in out   # classroom's hard shadows, fog


def test_shader_set_changes_the_program_as_the_scene_file_would(capsys):
    _, plain, _ = run_cli(capsys, "shader", "classroom")
    _, soft, _ = run_cli(capsys, "shader", "classroom", "--set", "render.shadows=soft")
    assert "soft_shadow(" in soft and "soft_shadow(" not in plain
    assert "hard_shadow(" not in soft


def test_shader_has_path_labels_only_with_the_flag(capsys):
    """A student's shader has no path-label code; --path-labels prints what the equivalence
    suite compiles."""
    _, plain, _ = run_cli(capsys, "shader", "classroom")
    code, labelled, _ = run_cli(capsys, "shader", "classroom", "--path-labels")
    assert code == 0
    assert "path_step(" not in plain and "path_step(" in labelled
    assert "int(px.path)" in labelled


def test_numbered_shader_prefixes_consecutive_line_numbers(capsys):
    _, plain, _ = run_cli(capsys, "shader", "classroom")
    code, numbered, _ = run_cli(capsys, "shader", "classroom", "--numbered")
    assert code == 0
    lines = numbered.splitlines()
    width = len(str(len(lines)))
    parsed = [re.fullmatch(r"\s*(\d+)  (.*)", line) for line in lines]
    assert all(parsed)
    assert [int(m.group(1)) for m in parsed] == list(range(1, len(lines) + 1))
    assert all(len(line) >= width + 2 for line in lines)
    assert [m.group(2) for m in parsed] == plain.splitlines()


@pytest.mark.parametrize("argv", [["shader", "nosuchscene"],
                                  ["shader", "classroom", "--dialect", "hlsl"]],
                         ids=["unknown-scene", "unknown-dialect"])
def test_shader_user_errors_are_one_line_exit_2(capsys, argv):
    code, out, err = run_cli(capsys, *argv)
    assert_one_line_error(code, err)
    assert out == ""


@pytest.mark.parametrize("size", ["0x5", "48x0", "-5x5", "48"])
def test_compare_rejects_a_bad_size_with_exit_2(capsys, size):
    code, _, err = run_cli(capsys, "compare", "classroom", "--size", size)
    assert_one_line_error(code, err)
    assert "WIDTHxHEIGHT" in err


# --- marchlab render --backend gpu --------------------------------------------------------

def test_render_with_gpu_writes_the_png_of_the_frame(gpu, capsys, tmp_path):
    output = tmp_path / "x.png"
    code, out, _ = run_cli(capsys, "render", "classroom", "--backend", "gpu", "--size", "32x24",
                           "-o", output)
    assert code == 0 and "gpu float32" in out
    with Image.open(output) as image:
        pixels = np.asarray(image.convert("RGB"))
    expected = marchlab.render(marchlab.load_scene("classroom"), 32, 24, backend="gpu").image()
    assert pixels.shape == (24, 32, 3)
    assert np.array_equal(pixels, expected)         # PNG is lossless: the same 8-bit frame


# --- marchlab compare --------------------------------------------------------------------

@pytest.mark.parametrize("precision", [[], ["--a-precision", "float64"]],
                         ids=["against-float32", "against-float64"])
def test_compare_gpu_with_numpy_passes_on_classroom(gpu, capsys, precision):
    code, out, _ = run_cli(capsys, "compare", "classroom", "--size", SIZE, *precision)
    reference = "float64" if precision else "float32"
    assert code == 0
    assert f"gpu float32 against numpy {reference}, {SIZE}" in out
    assert out.splitlines()[-1] == "PASS" and "FAIL" not in out


def test_compare_save_writes_four_images_of_the_frame_size(gpu, capsys, tmp_path):
    code, out, _ = run_cli(capsys, "compare", "classroom", "--size", SIZE, "--save",
                           tmp_path / "diff")
    assert code == 0
    names = sorted(p.name for p in (tmp_path / "diff").iterdir())
    assert names == ["a-numpy-float32.png", "b-gpu-float32.png", "difference-x16.png",
                     "error-mask.png"]
    for name in names:
        with Image.open(tmp_path / "diff" / name) as image:
            assert image.size == (48, 36)
        assert f"wrote {tmp_path / 'diff' / name}" in out


def test_compare_exits_1_and_prints_the_failed_gate(capsys, monkeypatch):
    """With a colour gate of 0, float32 against float64 must fail it (numpy only, no GPU)."""
    import marchlab.compare
    monkeypatch.setattr(marchlab.compare, "gates_against",
                        lambda precision, meshes=False: Gates(color=0.0))
    code, out, _ = run_cli(capsys, "compare", "classroom", "--size", "32x24", "--a", "numpy",
                           "--a-precision", "float64", "--b", "numpy", "--b-precision", "float32")
    assert code == 1
    assert re.search(r"^FAIL interior colour: ", out, re.M)
    assert out.splitlines()[-1].startswith("FAIL (")


# --- the gates that compare applies -----------------------------------------------------------

@pytest.fixture(scope="module")
def reference():
    """A numpy float32 frame of a ball in the middle of a 48x36 image."""
    scene = Scene(objects=(sphere(1.2),),
                  camera=Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0)))
    return (marchlab.render(scene, 48, 36, precision="float32", path_labels=True),
            scene.render.epsilon)


def gate_names(lines: list[str]) -> list[str]:
    return [line.split(":")[0] for line in lines]


def test_a_frame_passes_every_gate_against_itself(reference):
    frame, epsilon = reference
    assert failures(compare_frames(frame, frame, epsilon=epsilon), gates_against("float32")) == []


def test_colour_off_by_3_levels_inside_fails_the_colour_gate_only(reference):
    frame, epsilon = reference
    color = frame.color.copy()
    color[16:20, 22:26] += np.float32(3 / 255)         # a 4x4 block well inside the ball
    assert frame.hit[14:22, 20:28].all()               # and 2 px around it (erosion)
    c = compare_frames(frame, dataclasses.replace(frame, color=color), epsilon=epsilon)
    failed = failures(c, gates_against("float32"))
    colour = [line for line in failed if line.startswith("interior colour")]
    assert len(colour) == 1 and "(3.00/255)" in colour[0]
    # The 8-bit images may also differ by more than one level there; nothing else may fail.
    assert set(gate_names(failed)) - {"display"} == {"interior colour"}


def test_silhouette_moved_by_3_pixels_fails_the_coverage_gates(reference):
    frame, epsilon = reference
    moved = dataclasses.replace(frame, **{
        name: np.roll(getattr(frame, name), 3, axis=1)
        for name in ("color", "depth", "normal", "steps", "object_id", "hit", "path")})
    c = compare_frames(frame, moved, epsilon=epsilon)
    failed = failures(c, gates_against("float32"))
    differs = int((frame.hit != moved.hit).sum())
    coverage = [line for line in failed if line.startswith("coverage")]
    assert len(coverage) == 2
    assert re.match(rf"coverage: {c.hit_differs_far} pixels differ in hit more than 1 px",
                    coverage[0]) and c.hit_differs_far > 0
    assert coverage[1].startswith(f"coverage: {differs} pixels differ in hit (limit 0.05%")
