"""How ``marchlab`` reports a user's mistakes: exit code 2, one stderr line, no traceback.

The line names the file, the field and the problem (bad scene files, a bad --size, --set or
output suffix), and no output file is written. Most checks call `marchlab.cli.main(argv)`
in-process; a few run the real command in a subprocess to prove it end to end.
"""

from __future__ import annotations

import pytest
from cli_helpers import assert_one_line_error, run_cli, run_marchlab

from scene_model.scenefile import scene_path


TWO_OBJECTS = '[[objects]]\ntype = "plane"\n\n[[objects]]\ntype = "sphere"\n\n'
UNION = '[[objects]]\ntype = "plane"\n\n[[objects]]\ntype = "union"\n[[objects.children]]\n'
MORPH = ('[[objects]]\ntype = "plane"\n\n[[objects]]\ntype = "morph"\nt = {t}\n'
         + '[[objects.children]]\ntype = "sphere"\n' * 2)

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
    ("glass_index_below_air", '[materials.default]\ntransparency = 1.0\nior = 0.7\n',
     "materials.default.ior", "must be >= 1 (got 0.7)"),
    ("glass_transparency_above_one", '[materials.default]\ntransparency = 1.5\n',
     "materials.default.transparency", "between 0 and 1"),
    ("glass_negative_absorption", '[materials.default]\nabsorption = [0.1, -0.2, 0.0]\n',
     "materials.default.absorption[1]", "must be >= 0 (got -0.2)"),
    ("unknown_fresnel", '[render]\nfresnel = "snell"\n', "render.fresnel", "exact"),
    ("texture_with_checker", '[materials.default]\nchecker = {}\ntexture = {}\n',
     "materials.default.texture", "checker or texture, not both"),
    ("unknown_texture_mapping", '[materials.default]\ntexture = { mapping = "spherical" }\n',
     "materials.default.texture.mapping", "'triplanar', 'uv'"),
    ("unknown_built_in_texture", '[materials.default]\ntexture = { image = "uv_gird" }\n',
     "materials.default.texture.image", "no built-in image (built-in: uv_grid"),
    ("texture_sharpness_below_1", '[materials.default]\ntexture = { sharpness = 0.5 }\n',
     "materials.default.texture.sharpness", "must be >= 1"),
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
    ("morph_t_above_one", MORPH.format(t=1.5), "objects[1].t",
     "must be between 0 and 1 (got 1.5)"),
    ("morph_t_below_zero", MORPH.format(t=-0.25), "objects[1].t",
     "must be between 0 and 1 (got -0.25)"),
    ("morph_three_children", MORPH.format(t=0.5) + '[[objects.children]]\ntype = "box"\n',
     "objects[1].children", "must have exactly 2 children (got 3)"),
    ("morph_one_child", MORPH.format(t=0.5).replace('[[objects.children]]\ntype = "sphere"\n', "",
                                                    1),
     "objects[1].children", "must have exactly 2 children (got 1)"),
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
