"""Scene overrides (``load_scene(name, ["field.path=value"])``, the CLI's --set) through the API.

An override changes the field it names; a bad one raises `SceneError` naming the scene, the
field and the problem, and a malformed one quotes the assignment.
"""

from __future__ import annotations

import pytest

from marchlab import SceneError, load_scene
from scene_model.scenefile import scene_path


def source_of(err: SceneError) -> str:
    """The file part of an error's message (a bundled scene may be named or given by path)."""
    return str(err).split(": ", 1)[0]


def names_classroom(err: SceneError) -> bool:
    return source_of(err) in ("classroom", str(scene_path("classroom")))


def test_override_changes_the_named_field():
    scene = load_scene("classroom", ["render.max_steps=64", "objects[1].radius=0.5",
                                     "render.shading=normals"])
    assert scene.render.max_steps == 64
    assert scene.render.shading == "normals"
    assert scene.objects[1].child.radius == 0.5      # objects[1] uses the position shorthand


@pytest.mark.parametrize("assignment, field, problem", [
    ("render.max_stepz=64", "render.max_stepz", "did you mean 'max_steps'?"),
    ("objects[99].radius=1", "objects[99]", "no such entry"),
    ("render.max_steps=0", "render.max_steps", ">= 1"),
    ("camera.fov=wide", "camera.fov", "must be a number"),
], ids=["unknown_field", "index_out_of_range", "value_out_of_range", "word_for_number"])
def test_bad_override_names_the_scene_the_field_and_the_problem(assignment, field, problem):
    with pytest.raises(SceneError) as caught:
        load_scene("classroom", [assignment])
    assert names_classroom(caught.value)
    assert str(caught.value).startswith(f"{source_of(caught.value)}: {field}: ")
    assert problem in str(caught.value)


@pytest.mark.parametrize("assignment", ["render.max_steps", "=5", "[0].radius=1",
                                        "objects[1]radius=1", "render..max_steps=1"])
def test_malformed_override_raises_scene_error_quoting_it(assignment):
    with pytest.raises(SceneError) as caught:
        load_scene("classroom", [assignment])
    assert names_classroom(caught.value)
    assert repr(assignment) in str(caught.value)
