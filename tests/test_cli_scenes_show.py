"""``marchlab scenes`` and ``marchlab show``: listing the bundled scenes and printing one as TOML.

``scenes`` lists every bundled scene with its one-line description; ``show`` prints TOML that
loads back equal to the scene, with --set overrides applied.
"""

from __future__ import annotations

import pytest
from cli_helpers import run_cli

from marchlab import load_scene
import marchlab


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


def test_shader_prints_the_cone_prepass_program_after_the_frames_program(capsys):
    code, out, _ = run_cli(capsys, "shader", "classroom", "--set", "render.prepass=cone")
    assert code == 0
    frame, prepass = out.split("// ==== the cone pre-pass's fragment shader")
    assert "texelFetch(cone_starts" in frame and "tile_start(" not in frame
    assert "out_start = tile_start(" in prepass and "real cone_march(" in prepass
    code, out, _ = run_cli(capsys, "shader", "classroom", "--dialect", "opencl",
                           "--set", "render.prepass=cone")
    assert code == 0 and "__kernel void cone_prepass(" in out and "====" not in out
