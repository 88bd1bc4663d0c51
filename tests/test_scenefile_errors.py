"""Scene files: every bad input raises `SceneError` with a one-line message.

The message is ``FILE: FIELD.PATH: problem``, the path being the one a user sees in the file
(``objects[1].children[0].radius``, ``objects[0].scale``); a missing file, a TOML syntax error,
text that is not UTF-8, a file with no scene in it, a folder and a missing default material are
named the same way.
"""

from __future__ import annotations

import tomllib

import pytest
import tomlkit

from marchlab import SceneError, load_scene


# --- Bad input -----------------------------------------------------------------------------------
# A small valid scene; each case changes one value and names the path and problem expected.

BASE = """\
description = "a small scene to break"

[camera]
position = [0.0, 1.0, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]

[render]
max_steps = 32

[materials.default]

[materials.red]
color = [0.9, 0.1, 0.1]

[[lights]]
type = "point"
position = [0.0, 5.0, 5.0]

[[lights]]
type = "spot"
inner_angle = 20.0
outer_angle = 30.0

[[objects]]
type = "plane"
material = "red"

[[objects]]
type = "union"
[[objects.children]]
type = "sphere"
radius = 0.5
[[objects.children]]
type = "box"
position = [1.0, 0.0, 0.0]

[[objects]]
type = "sphere"
radius = 0.5
position = [0.0, 0.5, 0.0]
"""

NAN, INF = float("nan"), float("inf")

# (id, where to write, value, field path in the message, fragment of the problem)
BAD_VALUES = [
    ("negative_radius", ("objects", 2, "radius"), -1.0, "objects[2].radius", "must be positive"),
    ("nan_radius", ("objects", 2, "radius"), NAN, "objects[2].radius", "finite"),
    ("inf_radius", ("objects", 2, "radius"), INF, "objects[2].radius", "finite"),
    ("nan_vector_component", ("camera", "position", 1), NAN, "camera.position[1]", "finite"),
    ("unknown_primitive_type", ("objects", 2, "type"), "spher", "objects[2].type",
     "did you mean 'sphere'?"),
    ("unknown_light_type", ("lights", 0, "type"), "pointt", "lights[0].type",
     "did you mean 'point'?"),
    ("unknown_object_key", ("objects", 2, "raduis"), 1.0, "objects[2].raduis",
     "did you mean 'radius'?"),
    ("unknown_render_key", ("render", "max_stepz"), 64, "render.max_stepz",
     "did you mean 'max_steps'?"),
    ("unknown_top_level_key", ("object",), [], "object", "did you mean 'objects'?"),
    ("string_for_number", ("objects", 2, "radius"), "big", "objects[2].radius",
     "must be a number"),
    ("float_for_integer", ("render", "max_steps"), 32.5, "render.max_steps",
     "must be an integer"),
    ("integer_below_minimum", ("render", "max_steps"), 0, "render.max_steps", ">= 1"),
    ("two_component_vector", ("camera", "position"), [0.0, 1.0], "camera.position",
     "3 components"),
    ("unknown_shading_mode", ("render", "shading"), "normal", "render.shading",
     "must be one of"),
    ("unknown_material", ("objects", 2, "material"), "gold", "objects[2].material",
     "unknown material 'gold'"),
    ("colour_above_one", ("materials", "red", "color"), [1.5, 0.0, 0.0],
     "materials.red.color", "between 0 and 1"),
    ("colour_below_zero", ("lights", 0, "color"), [1.0, -0.1, 1.0], "lights[0].color",
     "between 0 and 1"),
    ("spot_inner_equal_to_outer", ("lights", 1, "inner_angle"), 30.0, "lights[1].inner_angle",
     "less than outer_angle"),
    ("spot_inner_above_outer", ("lights", 1, "inner_angle"), 40.0, "lights[1].inner_angle",
     "less than outer_angle"),
    ("camera_up_parallel_to_view", ("camera", "up"), [0.0, -2.0, -10.0], "camera.up",
     "parallel"),
    ("nested_negative_radius", ("objects", 1, "children", 0, "radius"), -2.0,
     "objects[1].children[0].radius", "must be positive"),
    ("nested_unknown_material", ("objects", 1, "children", 0, "material"), "gold",
     "objects[1].children[0].material", "unknown material 'gold'"),
    ("nested_unknown_type", ("objects", 1, "children", 1, "type"), "bx",
     "objects[1].children[1].type", "did you mean 'box'?"),
    ("shorthand_negative_scale", ("objects", 0, "scale"), -1.0, "objects[0].scale",
     "must be positive"),
    ("nested_shorthand_zero_scale", ("objects", 1, "children", 1, "scale"), 0.0,
     "objects[1].children[1].scale", "must be positive"),
    ("nested_shorthand_short_position", ("objects", 1, "children", 1, "position"), [1.0, 0.0],
     "objects[1].children[1].position", "3 components"),
    ("shorthand_rotation_component_not_a_number", ("objects", 2, "rotation"), [0.0, "x", 0.0],
     "objects[2].rotation[1]", "must be a number"),
    ("shorthand_nan_position", ("objects", 2, "position"), [0.0, NAN, 0.0],
     "objects[2].position[1]", "finite"),
]


def broken_scene(tmp_path, where, value):
    """BASE with ``value`` written at ``where``, saved as tmp_path/broken.toml."""
    data = tomllib.loads(BASE)
    target = data
    for step in where[:-1]:
        target = target[step]
    target[where[-1]] = value
    path = tmp_path / "broken.toml"
    path.write_text(tomlkit.dumps(data), encoding="utf-8")
    return path


def test_base_scene_of_the_error_cases_is_valid(tmp_path):
    path = tmp_path / "base.toml"
    path.write_text(BASE)
    scene = load_scene(path)
    assert len(scene.objects) == 3 and len(scene.lights) == 2


def test_nan_is_written_as_toml_nan_in_the_error_cases(tmp_path):
    path = broken_scene(tmp_path, ("objects", 2, "radius"), NAN)
    assert "radius = nan" in path.read_text()


@pytest.mark.parametrize("where, value, field, problem",
                         [case[1:] for case in BAD_VALUES], ids=[case[0] for case in BAD_VALUES])
def test_bad_value_raises_scene_error_naming_file_field_and_problem(tmp_path, where, value,
                                                                     field, problem):
    path = broken_scene(tmp_path, where, value)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: {field}: "), message
    assert problem in message
    assert "\n" not in message


@pytest.mark.parametrize("table, problem", [
    ('type = "pyramid"\nbase = 0.0', "objects[0].base: must be positive (got 0.0)"),
    ('type = "pyramid"\nheight = -1.0', "objects[0].height: must be positive (got -1.0)"),
    ('type = "disk"\nradius = 0.0', "objects[0].radius: must be positive (got 0.0)"),
    ('type = "disk"\nthickness = -0.1', "objects[0].thickness: must be positive (got -0.1)"),
    ('type = "disk"\nradius = 0.5\nthickness = 1.5',
     "objects[0].thickness: must not exceed twice the radius 0.5 (got 1.5)"),
    ('type = "hex_prism"\napothem = 0.0', "objects[0].apothem: must be positive (got 0.0)"),
    ('type = "hex_prism"\nhalf_length = -2.0',
     "objects[0].half_length: must be positive (got -2.0)"),
], ids=["pyramid_base", "pyramid_height", "disk_radius", "disk_thickness",
        "disk_thicker_than_wide", "hex_prism_apothem", "hex_prism_half_length"])
def test_pyramid_disk_and_hex_prism_sizes_are_refused_in_one_line_naming_the_field(
        tmp_path, table, problem):
    path = tmp_path / "shape.toml"
    path.write_text(f"[materials.default]\n\n[[objects]]\n{table}\n")
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value) == f"{path}: {problem}"


def test_missing_file_raises_scene_error_naming_the_file(tmp_path):
    path = tmp_path / "nowhere.toml"
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert "no such file" in str(caught.value)


def test_unknown_bundled_name_raises_scene_error_listing_the_bundled_scenes():
    with pytest.raises(SceneError) as caught:
        load_scene("no_such_bundled_scene")
    assert str(caught.value).startswith("no_such_bundled_scene: ")
    assert "classroom" in str(caught.value)


def test_toml_syntax_error_names_the_file_and_the_line(tmp_path):
    path = tmp_path / "syntax.toml"
    path.write_text('[camera]\nfov = 50.0\nposition == [0.0, 1.0, 5.0]\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: TOML syntax error: ")
    assert "line 3" in message
    assert "\n" not in message


def test_error_in_a_material_name_with_a_newline_stays_on_one_line(tmp_path):
    # A key may hold any string in TOML; the message must still be one line for the CLI.
    path = tmp_path / "odd_key.toml"
    path.write_text('[materials."two\\nlines"]\ncolor = [2.0, 0.0, 0.0]\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert "\n" not in str(caught.value)
    assert "color" in str(caught.value)


def test_a_file_that_is_not_utf8_is_refused_in_one_line(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'description = "caf\xe9"\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value) == f"{path}: not UTF-8 text, as TOML requires (byte 0xe9 at offset 18)"


@pytest.mark.parametrize("text", ["", "\n\n", "# a scene, one day\n"])
def test_a_file_with_no_scene_in_it_is_refused_in_one_line(tmp_path, text):
    # An empty file is a file saved too soon, not a wish for the default scene.
    path = tmp_path / "empty.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value) == (f"{path}: holds no scene (the file is empty, or comments "
                                 "only): write at least a [camera] table or one [[objects]]")


def test_a_folder_is_not_taken_for_a_scene(tmp_path):
    with pytest.raises(SceneError) as caught:
        load_scene(tmp_path)
    assert str(caught.value) == f"{tmp_path}: is a folder, not a scene file"


def test_a_primitive_without_material_needs_a_default_material(tmp_path):
    path = tmp_path / "nodefault.toml"
    path.write_text('[materials.red]\n\n[[objects]]\ntype = "sphere"\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value) == (f"{path}: objects[0].material: no material given, and no "
                                 "material named 'default' is defined (defined: red)")
