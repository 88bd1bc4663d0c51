"""A scene nests at most 64 levels deep, and a deeper one is refused before anything recurses.

The limit (scene_model.shapes.MAX_DEPTH) is checked three ways that must agree: on the text of
a file before Python's TOML reader sees it (brackets outside strings and comments, table
headers), on the parsed tables (scene_model/nesting.py), and on a tree built in Python, when
the node that goes beyond it is made. Each refusal is one line naming the file and the path to
the first node beyond the limit, and comes in well under a second however deep the input.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from marchlab import SceneError, load_scene, save_scene
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model import builder, nesting, shapes
from scene_model.builder import Scene, plane, sphere
from scene_model.errors import format_path
from scene_model.nesting import MAX_BRACKETS, too_deep_spans
from scene_model.scenefile import scene_from_dict
from scene_model.shapes import MAX_DEPTH, Translate, node_depth

TOO_DEEP = f"nested deeper than the limit of {MAX_DEPTH} levels"


def inline_unions(levels: int) -> str:
    """A sphere inside ``levels - 1`` unions, written as nested inline tables."""
    node = '{type = "sphere"}'
    for _ in range(levels - 1):
        node = '{type = "union", children = [' + node + "]}"
    return f"objects = [{node}]\n"


def inline_translates(levels: int) -> str:
    node = '{type = "sphere"}'
    for _ in range(levels - 1):
        node = '{type = "translate", child = ' + node + "}"
    return f"objects = [{node}]\n"


def header_unions(levels: int) -> str:
    """The same tree as `inline_unions`, written with ``[[objects.children...]]`` headers."""
    lines = []
    for depth in range(levels):
        lines.append(f"[[objects{'.children' * depth}]]")
        lines.append('type = "union"' if depth < levels - 1 else 'type = "sphere"')
    return "\n".join(lines) + "\n"


FORMS = {"inline_unions": inline_unions, "inline_translates": inline_translates,
         "header_unions": header_unions}


def load_text(tmp_path, text: str):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    return load_scene(path)


@pytest.mark.parametrize("form", FORMS)
def test_exactly_64_levels_load_and_the_tree_is_64_deep(tmp_path, form):
    scene = load_text(tmp_path, FORMS[form](MAX_DEPTH))
    assert node_depth(scene.objects[0]) == MAX_DEPTH


@pytest.mark.parametrize("levels", [MAX_DEPTH + 1, 200, 1000])
@pytest.mark.parametrize("form", FORMS)
def test_nesting_deeper_than_64_is_refused_before_parsing_in_inline_and_header_form(
        tmp_path, form, levels):
    path = tmp_path / "deep.toml"
    path.write_text(FORMS[form](levels))
    start = time.perf_counter()
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    elapsed = time.perf_counter() - start
    message = str(caught.value)
    assert elapsed < 0.5, f"{elapsed:.2f} s"
    assert message.startswith(f"{path}: objects") and TOO_DEEP in message
    assert "\n" not in message and len(message) < len(str(path)) + 200
    assert f" ... {'child' if form == 'inline_translates' else 'children'}" in message


def test_a_deep_inline_file_reaches_the_toml_reader_only_cut_to_the_bracket_limit(tmp_path,
                                                                                 monkeypatch):
    # The cut leaves an empty table one bracket below the limit, so that the walk of the
    # parsed tables finds it and names its path.
    seen = []
    real = nesting.tomllib.loads

    def spy(text):
        seen.append(text)
        return real(text)

    monkeypatch.setattr(nesting.tomllib, "loads", spy)
    path = tmp_path / "deep.toml"
    path.write_text(inline_unions(5000))          # 10 000 brackets: a RecursionError in tomllib
    with pytest.raises(SceneError, match=TOO_DEEP):
        load_scene(path)
    assert seen and all(too_deep_spans(text, MAX_BRACKETS + 1) == [] for text in seen)


def test_a_header_deeper_than_64_keys_is_refused_without_reading_the_file(tmp_path,
                                                                        monkeypatch):
    monkeypatch.setattr(nesting.tomllib, "loads", lambda text: pytest.fail("file was read"))
    path = tmp_path / "deep.toml"
    path.write_text(header_unions(1000))          # 4.5 MB: seconds to read
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value).endswith(f"{TOO_DEEP} (the table header on line "
                                      f"{2 * MAX_DEPTH + 1})")


def test_shorthand_keys_count_as_the_transform_levels_they_stand_for(tmp_path):
    # A sphere with position and rotation is three nodes: translate(rotate(sphere)).
    table = '{type = "union", position = [0, 0, 0], rotation = [0, 0, 0], children = [%s]}'
    node = '{type = "sphere", position = [0, 1, 0], rotation = [0, 0, 0]}'
    for _ in range(20):                           # 3 + 20 * 3 = 63 levels
        node = table % node
    scene = load_text(tmp_path, f"objects = [{node}]\n")
    assert node_depth(scene.objects[0]) == 63
    with pytest.raises(SceneError) as caught:
        load_text(tmp_path, f"objects = [{table % node}]\n")
    assert caught.value.path[:2] == ("objects", 0) and caught.value.problem == TOO_DEEP


def test_brackets_inside_strings_and_comments_do_not_count(tmp_path):
    text = ('description = "' + "[{" * 500 + '"\n'
            "# " + "[" * 500 + "\n"
            "[materials.default]\n"
            "[[objects]]\n"
            "type = 'sphere'  # {{{{{\n"
            'material = """' + "]]]" * 200 + '"""\n'
            '[materials."' + "]" * 300 + '"]\n')
    assert too_deep_spans(text) == []
    path = tmp_path / "odd.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match="unknown material"):   # read whole, judged on fields
        load_scene(path)


def test_deep_data_that_is_not_an_object_is_refused_naming_its_path(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("description = " + "[" * 300 + "]" * 300 + "\n")
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value).startswith(f"{path}: description[0][0]")
    assert TOO_DEEP in str(caught.value)


def test_a_deep_value_given_with_set_is_refused_naming_its_field():
    value = "[" * 1000 + "]" * 1000
    with pytest.raises(SceneError) as caught:
        load_scene("classroom", [f"objects[0].normal={value}"])
    assert str(caught.value) == f"classroom: objects[0].normal: {TOO_DEEP}"
    unions = inline_unions(MAX_DEPTH + 1).removeprefix("objects = ").strip()
    with pytest.raises(SceneError) as caught:
        load_scene("classroom", [f"objects={unions}"])
    assert caught.value.path[:4] == ("objects", 0, "children", 0)


def test_a_parsed_tree_deeper_than_64_is_refused_without_recursion():
    table = {"type": "sphere"}
    for _ in range(100_000):                      # far beyond Python's recursion limit
        table = {"type": "translate", "child": table}
    start = time.perf_counter()
    with pytest.raises(SceneError) as caught:
        scene_from_dict({"objects": [table]})
    assert time.perf_counter() - start < 0.5
    assert caught.value.path == ("objects", 0) + ("child",) * MAX_DEPTH


def test_a_tree_built_in_python_deeper_than_64_is_refused_when_the_node_is_made():
    node = sphere(1.0)
    for _ in range(MAX_DEPTH - 1):
        node = node.at(0.0, 0.1, 0.0)
    assert node_depth(node) == MAX_DEPTH
    Scene(objects=[node])                         # exactly the limit: a valid scene
    with pytest.raises(SceneError) as caught:
        node.rotate(0.0, 10.0, 0.0)
    assert caught.value.path == ("child",) * MAX_DEPTH and caught.value.problem == TOO_DEEP
    with pytest.raises(SceneError) as caught:
        node | sphere(2.0) | sphere(3.0)          # a union of it is one level more too
    assert caught.value.path[:3] == ("children", 0, "child")


def test_a_builder_depth_and_a_file_depth_agree(tmp_path):
    built = (sphere(0.5).at(0, 1, 0).rotate(0, 30, 0) | builder.box(0.5)).scale(2.0)
    assert node_depth(built) == 5
    path = tmp_path / "same.toml"
    save_scene(Scene(objects=[built]), path)
    assert node_depth(load_scene(path).objects[0]) == 5


def test_bracket_limit_leaves_room_for_every_tree_of_the_depth_limit():
    # objects = [{children = [{ ... }]}]: two brackets per level, and one more for a vector.
    assert MAX_BRACKETS >= 2 * MAX_DEPTH + 1
    assert too_deep_spans(inline_unions(MAX_DEPTH).replace(
        '{type = "sphere"}', '{type = "sphere", position = [0, 0, 0]}')) == []


def test_a_long_path_keeps_its_ends_around_an_ellipsis_and_a_short_one_is_whole():
    assert format_path(("objects", 2, "children", 0, "radius")) == "objects[2].children[0].radius"
    long = ("objects", 0) + ("children", 0) * 40 + ("child",)
    assert format_path(long) == ("objects[0].children[0].children[0].children[0] ... "
                                 "children[0].children[0].child")


# --- What a plane with a normal that is not unit length means ------------------------------------

def test_a_plane_with_a_long_normal_lies_at_offset_along_the_unit_normal():
    """``plane((0, 2, 0), 1)`` is the floor y = 1 (n = normal / |normal|), as documented."""
    sdf = build_scene_sdf([plane((0.0, 2.0, 0.0), 1.0)])
    distance, _ = sdf(np.array([[0.0, 1.0, 0.0], [0.0, 0.5, 0.0], [3.0, 4.0, -2.0]]))
    np.testing.assert_allclose(distance, [0.0, -0.5, 3.0], atol=1e-15)
    for doc in (builder.plane.__doc__, shapes.Plane.__doc__):
        assert "normal / |normal|" in doc


def test_translate_of_a_node_at_the_limit_names_the_deepest_branch():
    deep = sphere(1.0)
    for _ in range(MAX_DEPTH - 2):
        deep = Translate(deep, (0.0, 0.0, 0.0))
    node = sphere(1.0) | deep                     # the deep branch is the second child
    with pytest.raises(SceneError) as caught:
        Translate(node, (1.0, 0.0, 0.0))
    assert caught.value.path[:3] == ("child", "children", 1)
