"""Scene files: the position/rotation/scale shorthand, and nested CSG written by hand.

A table's ``position``, ``rotation`` and ``scale`` keys load as Translate(Rotate(Scale(node)));
the writer uses them only where that is the node's own order. A nested tree written by hand
loads as the tree it describes, and an error in it names its path in the file
(``objects[0].children[0].children[0].scale``).
"""

from __future__ import annotations

import tomllib

import pytest

from marchlab import SceneError, load_scene
from scene_model.scene import Scene
from scene_model.scenefile import scene_to_toml
from scene_model.shapes import (Box, Rotate, Scale, SmoothUnion, Sphere, Subtraction, Torus,
                                Translate)


# --- The position / rotation / scale shorthand ---------------------------------------------------

def test_shorthand_keys_load_as_translate_of_rotate_of_scale(tmp_path):
    path = tmp_path / "shorthand.toml"
    path.write_text('[[objects]]\ntype = "box"\nhalf_size = [1, 2, 3]\n'
                    'scale = 2\nrotation = [0, 45, 0]\nposition = [1, 2, 3]\n')
    (node,) = load_scene(path).objects
    assert node == Translate(Rotate(Scale(Box((1.0, 2.0, 3.0)), 2.0), (0.0, 45.0, 0.0)),
                             (1.0, 2.0, 3.0))


def test_single_shorthand_key_wraps_in_only_its_transform(tmp_path):
    path = tmp_path / "shorthand.toml"
    path.write_text('[[objects]]\ntype = "sphere"\nrotation = [10, 20, 30]\n')
    (node,) = load_scene(path).objects
    assert node == Rotate(Sphere(1.0), (10.0, 20.0, 30.0))


def test_saving_translate_rotate_scale_writes_the_shorthand_keys(tmp_path):
    node = Translate(Rotate(Scale(Sphere(0.5), 2.0), (0.0, 45.0, 0.0)), (1.0, 2.0, 3.0))
    text = scene_to_toml(Scene(objects=(node,)))
    assert "position = [1.0, 2.0, 3.0]" in text
    assert "rotation = [0.0, 45.0, 0.0]" in text
    assert "scale = 2.0" in text
    assert '"translate"' not in text and '"rotate"' not in text and '"scale"' not in text
    (table,) = tomllib.loads(text)["objects"]
    assert table == {"type": "sphere", "material": "default", "radius": 0.5,
                     "position": [1.0, 2.0, 3.0], "rotation": [0.0, 45.0, 0.0], "scale": 2.0}


def test_rotate_of_translate_is_not_saved_as_shorthand_on_the_primitive(tmp_path):
    # rotation + position on one table would mean Translate(Rotate(x)): a different shape.
    node = Rotate(Translate(Sphere(0.5), (1.0, 0.0, 0.0)), (0.0, 90.0, 0.0))
    (table,) = tomllib.loads(scene_to_toml(Scene(objects=(node,))))["objects"]
    assert table["type"] == "translate"
    assert "position" not in table
    assert table["rotation"] == [0.0, 90.0, 0.0]


# --- Nested CSG written by hand ------------------------------------------------------------------

NESTED_CSG = """\
[[objects]]
type = "subtraction"

[[objects.children]]
type = "smooth_union"
k = 0.2

[[objects.children.children]]
type = "box"
half_size = [1, 1, 1]
rotation = [0, 45, 0]

[[objects.children.children]]
type = "torus"
major_radius = 1.5
minor_radius = 0.3

[[objects.children]]
type = "sphere"
radius = 1.2
"""


def test_hand_written_nested_csg_loads_as_the_tree_it_describes(tmp_path):
    path = tmp_path / "nested.toml"
    path.write_text(NESTED_CSG)
    (node,) = load_scene(path).objects
    assert type(node) is Subtraction
    blend, cutter = node.children
    assert type(blend) is SmoothUnion and blend.k == 0.2
    rotated_box, torus = blend.children
    assert rotated_box == Rotate(Box((1.0, 1.0, 1.0)), (0.0, 45.0, 0.0))
    assert torus == Torus(1.5, 0.3)
    assert cutter == Sphere(1.2)


def test_hand_written_nested_csg_reports_errors_at_their_path_in_the_file(tmp_path):
    path = tmp_path / "nested.toml"
    path.write_text(NESTED_CSG.replace("rotation = [0, 45, 0]", "scale = -2"))
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value).startswith(f"{path}: objects[0].children[0].children[0].scale: ")
