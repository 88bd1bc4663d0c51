"""The scene editor's operations (scene_model/editing.py): node paths, adding, duplicating,
deleting and moving nodes, fields by path, lights and materials, object ids, undo and redo.

Every edit returns a valid `Scene`; a refused one raises `SceneError` with a one-line message
naming the place; ids agree with those the NumPy reference assigns; an edited scene comes
back equal from its TOML file; `set_field` agrees with ``--set`` on the same path and value.
"""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from marchlab.render import render
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.bodies import Body
from scene_model.camera import camera_rays
from scene_model.editing import (DUPLICATE_OFFSET, History, add_light, add_material,
                                 add_mesh, addable_mesh_kinds, delete_mesh, duplicate_mesh,
                                 add_object, default_node, delete, delete_light,
                                 delete_material, duplicate, get_field, node_at,
                                 node_field_path, object_path, primitive_ids, primitive_path,
                                 replace_node, reparent, set_field)
from scene_model.errors import SceneError
from scene_model.mesh_world import scene_meshes
from scene_model.scene import Camera, Material, Scene, scene_objects
from scene_model.scenefile import bundled_scene_names, load_scene, scene_to_toml
from scene_model.shapes import (Box, Plane, Primitive, Rotate, Scale, SmoothUnion, Sphere,
                                Subtraction, Translate, Union, children, node_kinds, primitives)

N_ARY = ["union", "intersection", "subtraction", "smooth_union", "smooth_intersection",
         "smooth_subtraction"]
UNARY = ["translate", "rotate", "scale", "repeat"]


def tree_scene() -> Scene:
    """A floor, a translated union holding a rotated box and a smooth union, a subtraction."""
    blob = SmoothUnion((Sphere(0.3), Translate(Sphere(0.3), (0.4, 0.0, 0.0))), 0.1)
    group = Translate(Union((Sphere(0.5), Rotate(Box(), (0.0, 30.0, 0.0)), blob)),
                      (0.0, 1.0, 0.0))
    cut = Subtraction((Box(), Translate(Sphere(0.6), (0.0, 0.3, 0.0))))
    return Scene(objects=(Plane(), group, cut))


def count(nodes) -> int:
    return sum(1 for _ in primitives(nodes))


def all_paths(scene: Scene) -> list[tuple]:
    """Every node path of the scene, depth first."""
    found = []

    def walk(nodes, prefix):
        for index, node in enumerate(nodes):
            found.append(prefix + (index,))
            walk(children(node), prefix + (index,))
    walk(scene.objects, ())
    return found


def same_or_shifted(copy, node) -> bool:
    """Whether ``copy`` is ``node``, or ``node`` (a translate) moved by DUPLICATE_OFFSET."""
    if copy == node:
        return True
    shifted = tuple(np.add(node.offset, DUPLICATE_OFFSET))
    return type(node) is Translate and copy == Translate(node.child, shifted)


def round_trip(scene: Scene, tmp_path) -> Scene:
    path = tmp_path / "edited.toml"
    path.write_text(scene_to_toml(scene))
    return load_scene(path)


def one_line_error(call, *args) -> str:
    with pytest.raises(SceneError) as caught:
        call(*args)
    message = str(caught.value)
    assert "\n" not in message
    return message


# --- Node paths ------------------------------------------------------------------------------

def test_node_path_indexes_objects_then_children():
    scene = tree_scene()
    assert node_at(scene, (1,)) is scene.objects[1]
    assert node_at(scene, (1, 0)) is scene.objects[1].child
    assert node_at(scene, (1, 0, 2, 1, 0)) == Sphere(0.3)
    assert node_at(scene, (2, 1)).offset == (0.0, 0.3, 0.0)


@pytest.mark.parametrize("path, message", [
    ((5,), "objects[5]: no such object (there are 3)"),
    ((1, 1), "objects[1].child: no child 1 (a translate has one, index 0)"),
    ((1, 0, 7), "objects[1].child.children[7]: no such child (there are 3)"),
    ((0, 0), "objects[0]: a plane is a primitive and has no children"),
    ((), "a node path is a non-empty tuple of indices such as (2, 0) (got ())"),
    ("objects", "a node path is a tuple of indices such as (2, 0) (got 'objects')"),
])
def test_bad_node_path_is_named_in_one_line(path, message):
    assert one_line_error(node_at, tree_scene(), path) == message


def test_replace_node_changes_that_node_and_nothing_else():
    scene = tree_scene()
    edited = replace_node(scene, (1, 0, 0), Sphere(0.9))
    assert node_at(edited, (1, 0, 0)) == Sphere(0.9)
    assert edited.objects[0] is scene.objects[0] and edited.objects[2] is scene.objects[2]
    assert node_at(edited, (1, 0, 1)) is node_at(scene, (1, 0, 1))
    assert edited.objects[1].offset == scene.objects[1].offset


# --- Adding ----------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", N_ARY)
def test_add_object_appends_to_every_operator_kind(kind):
    scene, parent = add_object(tree_scene(), default_node(kind))
    edited, path = add_object(scene, Sphere(0.2), parent)
    assert path == parent + (2,)
    assert node_at(edited, path) == Sphere(0.2)
    assert count(edited.objects) == count(scene.objects) + 1


def test_add_object_at_top_level_returns_the_last_index():
    edited, path = add_object(tree_scene(), Sphere(0.2))
    assert path == (3,) and edited.objects[3] == Sphere(0.2)


@pytest.mark.parametrize("kind", UNARY)
def test_adding_into_a_transform_is_refused_saying_it_holds_one_child(kind):
    scene, parent = add_object(tree_scene(), default_node(kind))
    message = one_line_error(add_object, scene, Sphere(), parent)
    assert message == (f"objects[3]: a {kind} holds exactly one child; add the shape to a "
                       f"union or another operator instead")


def test_adding_into_a_primitive_is_refused():
    assert (one_line_error(add_object, tree_scene(), Sphere(), (0,))
            == "objects[0]: a plane is a primitive and holds no children")


def test_added_node_brings_the_default_material_into_a_scene_without_it():
    scene = load_scene("classroom")
    assert "default" not in scene.materials
    edited, _ = add_object(scene, default_node("sphere"))
    assert edited.materials == {**scene.materials, "default": Material()}


def test_node_with_an_unknown_material_is_refused_naming_it():
    message = one_line_error(add_object, tree_scene(), Sphere(material="gold"))
    assert "unknown material 'gold'" in message


@pytest.mark.parametrize("kind", sorted(node_kinds()))
def test_default_node_of_every_kind_makes_a_scene_that_shows_it(kind):
    """Each "Add" menu entry gives a valid scene in which the default camera sees the node."""
    scene, path = add_object(Scene(), default_node(kind))
    frame = render(scene, 16, 12, backend="numpy")
    ids = set(np.unique(frame.object_id[frame.hit]))
    assert ids and ids <= set(primitive_ids(scene, path))
    assert all(p.material == "default" for p in primitives(scene.objects))


def test_default_node_of_unknown_kind_lists_the_kinds():
    message = one_line_error(default_node, "sphear")
    assert message.startswith("unknown node type 'sphear' (one of: box, capped_cylinder")


# --- Duplicating, deleting, moving -------------------------------------------------------------

def test_duplicate_of_a_translated_object_goes_after_it_shifted_half_a_metre():
    scene = load_scene("classroom")
    edited, path = duplicate(scene, (2,))
    assert path == (3,)
    assert edited.objects[:3] == scene.objects[:3] and edited.objects[4:] == scene.objects[3:]
    shifted = np.add(scene.objects[2].offset, DUPLICATE_OFFSET)
    assert edited.objects[3].offset == tuple(shifted)
    assert edited.objects[3].child == scene.objects[2].child


def test_duplicate_inside_a_transform_copies_the_transform_too():
    scene = load_scene("classroom")
    edited, path = duplicate(scene, (2, 0))
    assert path == (3, 0) and node_at(edited, path) == node_at(scene, (2, 0))
    assert len(edited.objects) == len(scene.objects) + 1


def test_duplicate_of_an_untransformed_object_gets_a_translate():
    scene = tree_scene()
    edited, path = duplicate(scene, (2,))
    assert path == (3, 0) and node_at(edited, path) == scene.objects[2]
    assert edited.objects[3] == Translate(scene.objects[2], DUPLICATE_OFFSET)


def test_duplicate_inside_an_operator_stays_in_that_operator():
    scene = tree_scene()
    edited, path = duplicate(scene, (1, 0, 0))
    assert path == (1, 0, 1, 0)
    assert len(node_at(edited, (1, 0)).children) == 4
    assert node_at(edited, path) == Sphere(0.5)
    assert node_at(edited, (1, 0, 2)) == node_at(scene, (1, 0, 1))


def test_delete_removes_only_that_node():
    scene = tree_scene()
    edited = delete(scene, (1, 0, 1))
    assert node_at(edited, (1, 0)).children == (Sphere(0.5), node_at(scene, (1, 0, 2)))
    assert count(edited.objects) == count(scene.objects) - 1


def test_deleting_a_shape_inside_a_transform_deletes_the_transform():
    scene = tree_scene()
    edited = delete(scene, (2, 1, 0))                # the sphere cut from the box
    assert edited.objects[2] == Subtraction((Box(),))


def test_deleting_the_last_child_deletes_the_ancestors_it_empties():
    scene = Scene(objects=(Plane(), Translate(Union((Scale(Sphere(), 0.5),)), (0, 1, 0))))
    assert delete(scene, (1, 0, 0, 0)).objects == (Plane(),)


def test_deleting_every_object_leaves_an_empty_valid_scene(tmp_path):
    scene = load_scene("classroom")
    for _ in scene.objects:
        scene = delete(scene, (0,))
    assert scene.objects == () and round_trip(scene, tmp_path) == scene


def test_reparent_moves_a_branch_into_an_operator():
    scene = tree_scene()
    edited, path = reparent(scene, (0,), (1, 0))      # the floor into the union
    assert path == (0, 0, 3)                          # the union is now objects[0]
    assert node_at(edited, path) == Plane()
    assert count(edited.objects) == count(scene.objects)


def test_reparent_takes_the_transforms_above_the_node_along():
    scene = tree_scene()
    edited, path = reparent(scene, (1, 0, 1, 0), None)    # the box inside the rotate
    assert path == (3, 0) and edited.objects[3] == node_at(scene, (1, 0, 1))


def test_reparent_deletes_the_operator_it_leaves_empty():
    scene = Scene(objects=(Union((Sphere(),)), Union((Box(),))))
    edited, path = reparent(scene, (0, 0), (1,))
    assert edited.objects == (Union((Box(), Sphere())),) and path == (0, 1)


def test_reparent_into_its_own_parent_moves_it_last():
    scene = tree_scene()
    edited, path = reparent(scene, (1, 0, 0), (1, 0))
    assert path == (1, 0, 2)
    assert node_at(edited, (1, 0)).children == node_at(scene, (1, 0)).children[1:] + (
        Sphere(0.5),)


def test_reparent_into_an_ancestor_with_one_child_keeps_the_ancestor():
    scene = Scene(objects=(Union((Union((Sphere(),)),)),))
    edited, path = reparent(scene, (0, 0, 0), (0,))
    assert edited.objects == (Union((Sphere(),)),) and path == (0, 0)


@pytest.mark.parametrize("target", [(1, 0), (1, 0, 2)])
def test_moving_a_node_into_itself_or_its_descendant_is_refused(target):
    message = one_line_error(reparent, tree_scene(), (1, 0), target)
    assert message == "objects[1].child: cannot move a node into itself or its own descendant"


@pytest.mark.parametrize("edit", ["add", "duplicate", "delete", "move_out"])
def test_a_morph_keeps_its_two_children_refusing_in_one_line(edit):
    """A morph blends exactly two shapes: an edit that would leave it one or three is refused,
    naming the morph."""
    scene = Scene(objects=(Plane(), Sphere(0.5).morph(Box(), 0.3)))
    call = {"add": lambda: add_object(scene, Sphere(), (1,)),
            "duplicate": lambda: duplicate(scene, (1, 0)),
            "delete": lambda: delete(scene, (1, 1)),
            "move_out": lambda: reparent(scene, (1, 0), None)}[edit]
    message = one_line_error(call)
    assert message.startswith("objects[1].children: must have exactly 2 children (got ")


def test_moving_into_a_transform_is_refused():
    message = one_line_error(reparent, tree_scene(), (0,), (2, 1))
    assert message.startswith("objects[2].children[1]: a translate holds exactly one child")


EDITS = st.lists(st.tuples(st.sampled_from(["add", "duplicate", "delete", "reparent"]),
                           st.sampled_from(sorted(node_kinds())), st.integers(0, 10 ** 6),
                           st.integers(0, 10 ** 6)), min_size=1, max_size=8)


# What an edit that would give a morph other than two children is told (shapes.Morph).
TWO_CHILDREN = "children: must have exactly 2 children (got "


@settings(max_examples=40)
@given(edits=EDITS)
def test_random_edits_keep_counts_ids_and_the_file_round_trip(edits, tmp_path_factory):
    scene = tree_scene()
    for action, kind, a, b in edits:
        paths = all_paths(scene)
        holders = [None] + [p for p in paths if hasattr(node_at(scene, p), "children")]
        before = count(scene.objects)
        if action == "add" or not paths:
            node = default_node(kind)
            try:
                scene, path = add_object(scene, node, holders[a % len(holders)])
            except SceneError as err:                    # a third child for a morph
                assert TWO_CHILDREN in str(err)
                continue
            assert node_at(scene, path) == node and count(scene.objects) == before + count([node])
            continue
        path = paths[a % len(paths)]
        node = node_at(scene, path)
        if action == "duplicate":
            try:
                scene, copy = duplicate(scene, path)
            except SceneError as err:                    # a copy beside a morph's child
                assert TWO_CHILDREN in str(err)
                continue
            assert same_or_shifted(node_at(scene, copy), node)
            assert count(scene.objects) >= before + count([node])
        elif action == "delete":
            try:
                scene = delete(scene, path)
            except SceneError as err:                    # a morph left with one child
                assert TWO_CHILDREN in str(err)
                continue
            assert count(scene.objects) <= before - count([node])
        else:
            target = holders[b % len(holders)]
            try:
                scene, moved = reparent(scene, path, target)
            except SceneError as err:
                if TWO_CHILDREN in str(err):             # into or out of a morph
                    continue
                assert "into itself or its own descendant" in str(err)
                assert target[:1] == path[:1]
                continue
            assert node_at(scene, moved) == node and count(scene.objects) == before
    ids = [i for k in range(len(scene.objects)) for i in primitive_ids(scene, (k,))]
    assert ids == list(range(count(scene.objects)))
    assert round_trip(scene, tmp_path_factory.mktemp("edits")) == scene


# --- Fields by path ----------------------------------------------------------------------------

SET_EXAMPLES = [("render.epsilon", 0.002), ("materials.red.shininess", 12),
                ("lights.0.position", [1, 2, 3]), ("objects.2.radius", 0.75),
                ("camera.fov", 40), ("render.fog.density", 0.05),
                ("objects[1].position[1]", 1.5), ("physics.dt", 0.002),
                ("materials.gold.color", [1.0, 0.8, 0.2]), ("render.shading", "toon"),
                ("objects[0].rotation", [10, 0, 0])]


def as_override(path: str, value) -> str:
    """The ``--set`` assignment of the same change (indices in brackets, value as TOML)."""
    brackets = ".".join(f"[{s}]" if s.isdigit() else s for s in path.split("."))
    return f"{brackets.replace('.[', '[')}={json.dumps(value)}"


@pytest.mark.parametrize("path, value", SET_EXAMPLES)
def test_set_field_equals_the_same_override_of_the_scene_file(path, value):
    scene = load_scene("classroom")
    edited = set_field(scene, path, value)
    assert edited == load_scene("classroom", [as_override(path, value)])
    got = get_field(edited, path)
    assert got == (tuple(value) if isinstance(value, list) else value)


@pytest.mark.parametrize("path, value", [
    ("objects.2.radius", -1), ("render.epsilon", 100), ("camera.fov", "wide"),
    ("objects[1].material", "gold"), ("render.max_stepz", 3), ("lights[5].color", [1, 1, 1]),
    ("objects[0].position", [0, 1e9, 0]), ("materials.red.checker.scale", 0),
    ("camera.position", [0, 0.8, 0]),
])
def test_rejected_value_reads_as_the_scene_file_error(path, value):
    message = one_line_error(set_field, load_scene("classroom"), path, value)
    with pytest.raises(SceneError) as from_file:
        load_scene("classroom", [as_override(path, value)])
    assert f"classroom: {message}" == str(from_file.value)


def test_position_none_removes_the_translate_and_a_value_adds_it_back():
    scene = load_scene("classroom")
    bare = set_field(scene, "objects[1].position", None)
    assert bare.objects[1] == scene.objects[1].child
    assert get_field(bare, "objects[1].position") is None
    assert set_field(bare, "objects[1].position", scene.objects[1].offset) == scene


def test_node_field_path_names_shorthand_fields_as_the_file_does():
    scene = load_scene("csg")
    assert node_field_path(scene, (1,), "offset") == "objects[1].position"
    assert node_field_path(scene, (2, 0, 0, 0), "radius") == "objects[2].children[0].radius"
    assert node_field_path(scene, (2, 0, 0), "offset") == "objects[2].children[0].position"
    tree = tree_scene()
    path = node_field_path(tree, (1, 0, 1), "degrees")
    assert path == "objects[1].children[1].rotation"
    assert get_field(set_field(tree, path, (0, 60, 0)), path) == (0.0, 60.0, 0.0)
    assert "has no field 'radius'" in one_line_error(node_field_path, tree, (0,), "radius")


def test_set_field_takes_well_under_5_ms_on_the_classroom_scene():
    scene = load_scene("classroom")
    times = []
    for step in range(100):
        start = time.perf_counter()
        set_field(scene, "lights.0.position", (step * 0.01, 6.0, 4.0))
        times.append(time.perf_counter() - start)
    assert np.median(times) < 5e-3 / 5


# --- Lights and materials ----------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["point", "directional", "spot"])
def test_add_light_appends_a_default_light_of_that_kind(kind):
    scene = load_scene("classroom")
    edited, index = add_light(scene, kind)
    assert index == 2 and edited.lights[:2] == scene.lights
    assert edited.lights[2].kind == kind and edited.lights[2] == type(edited.lights[2])()


def test_deleting_every_light_leaves_a_valid_scene(tmp_path):
    scene = load_scene("classroom")
    second = scene.lights[1]
    scene = delete_light(scene, 0)
    assert scene.lights == (second,)
    scene = delete_light(scene, 0)
    assert scene.lights == () and round_trip(scene, tmp_path) == scene
    assert one_line_error(delete_light, scene, 0) == "lights[0]: no such entry (there are 0)"


def test_add_material_picks_the_first_free_name_and_refuses_a_taken_one():
    scene = Scene(materials={"default": Material(), "material_1": Material()})
    edited, name = add_material(scene)
    assert name == "material_2" and edited.materials[name] == Material()
    assert (one_line_error(add_material, scene, "default")
            == "materials.default: a material of this name already exists")


def test_delete_material_in_use_is_refused_naming_its_users():
    scene = load_scene("classroom")
    message = one_line_error(delete_material, scene, "red")
    assert message == ("materials.red: is still used by objects[1].child; give them another "
                       "material first")
    unused, _ = add_material(scene, "spare")
    assert delete_material(unused, "spare") == scene


# --- Object ids --------------------------------------------------------------------------------

def spheres_at_known_centres() -> tuple[Scene, list[tuple], np.ndarray]:
    """Small spheres 3 m apart in a nested tree, two bodies; leaf paths and world centres."""
    def ball(x):
        return Translate(Sphere(0.1), (x, 0.0, 0.0))
    inner = Translate(SmoothUnion((ball(3.0), ball(6.0)), 0.01), (3.0, 0.0, 0.0))
    objects = (ball(0.0), Union((ball(3.0), inner, ball(12.0))), ball(15.0))
    scene = Scene(objects=objects, bodies=(Body(position=(0.0, 5.0, 0.0)),
                                           Body(position=(3.0, 5.0, 0.0))))
    leaves = [(0, 0), (1, 0, 0), (1, 1, 0, 0, 0), (1, 1, 0, 1, 0), (1, 2, 0), (2, 0)]
    centres = np.array([[0, 0, 0], [3, 0, 0], [6, 0, 0], [9, 0, 0], [12, 0, 0], [15, 0, 0],
                        [0, 5, 0], [3, 5, 0]], dtype=float)
    return scene, leaves, centres


def test_primitive_ids_and_paths_agree_with_the_reference_ids():
    scene, leaves, centres = spheres_at_known_centres()
    assert all(isinstance(node_at(scene, leaf), Primitive) for leaf in leaves)
    _, ids = build_scene_sdf(scene_objects(scene), with_ids=True)(centres)
    assert list(ids[:6]) == [primitive_ids(scene, leaf)[0] for leaf in leaves]
    assert [primitive_path(scene, i) for i in ids] == leaves + [("body", 0), ("body", 1)]
    assert [object_path(scene, i) for i in ids] == [(0,), (1,), (1,), (1,), (1,), (2,),
                                                    ("body", 0), ("body", 1)]
    assert primitive_ids(scene, (1,)) == (1, 2, 3, 4)
    assert primitive_ids(scene, (1, 1)) == (2, 3)
    assert object_path(scene, -1) is None and object_path(scene, 8) is None


def test_clicked_pixel_selects_the_object_whose_surface_it_shows():
    """The object a click selects is the one whose own SDF is 0 at the pixel's hit point."""
    scene = load_scene("csg")
    frame = render(scene, 32, 24, backend="numpy")
    origin, directions = camera_rays(scene.camera, 32, 24)
    hit = frame.hit
    points = origin + frame.depth[hit][:, None] * directions[hit]
    distances = np.stack([np.abs(build_scene_sdf([obj])(points)[0]) for obj in scene.objects])
    nearest = np.argmin(distances, axis=0)
    clear = np.sort(distances, axis=0)[1] > 0.05            # away from where two objects meet
    selected = np.array([object_path(scene, i)[0] for i in frame.object_id[hit]])
    assert clear.sum() > 100 and len(set(nearest[clear])) == len(scene.objects)
    np.testing.assert_array_equal(selected[clear], nearest[clear])


# --- Undo and redo -----------------------------------------------------------------------------

def scenes(n: int) -> list[Scene]:
    return [Scene(camera=Camera(fov=10.0 + 0.5 * i)) for i in range(n)]


def test_undo_and_redo_walk_the_pushed_scenes():
    s0, s1, s2 = scenes(3)
    history = History(s0)
    assert not history.can_undo and not history.can_redo
    history.push(s1, "one")
    history.push(s2, "two")
    assert history.undo_labels == ("two", "one")
    assert history.undo() == s1 and history.undo() == s0 and not history.can_undo
    assert history.undo() == s0                               # nothing left: unchanged
    assert history.redo_labels == ("one", "two")
    assert history.redo() == s1 and history.redo() == s2 and not history.can_redo
    assert history.scene == s2


def test_pushes_with_the_same_coalesce_key_make_one_step():
    s0, *drag = scenes(6)
    history = History(s0)
    for scene in drag:
        history.push(scene, "drag fov", coalesce="camera.fov")
    assert history.undo_labels == ("drag fov",) and history.scene == drag[-1]
    assert history.undo() == s0


def test_seal_undo_or_another_key_end_a_coalesced_step():
    s0, s1, s2, s3, s4 = scenes(5)
    history = History(s0)
    history.push(s1, "a", coalesce="k")
    history.seal()
    history.push(s2, "a", coalesce="k")
    history.push(s3, "b", coalesce="other")
    assert history.undo_labels == ("b", "a", "a")
    history.undo()
    history.push(s4, "a", coalesce="k")
    assert history.undo_labels == ("a", "a", "a")


def test_push_after_undo_drops_the_redo_branch():
    s0, s1, s2, s3 = scenes(4)
    history = History(s0)
    history.push(s1, "one")
    history.push(s2, "two")
    history.undo()
    history.push(s3, "three")
    assert not history.can_redo and history.undo_labels == ("three", "one")


def test_pushing_the_current_scene_is_not_a_step():
    s0, s1 = scenes(2)
    history = History(s0)
    history.push(s1, "one")
    history.undo()
    history.push(s0, "nothing")
    assert history.can_redo and not history.can_undo


def test_history_keeps_the_last_limit_steps():
    many = scenes(260)
    history = History(many[0])
    for i, scene in enumerate(many[1:], start=1):
        history.push(scene, f"step {i}")
    assert len(history.undo_labels) == 200
    while history.can_undo:
        history.undo()
    assert history.scene == many[59]


# --- Round trip through the file ---------------------------------------------------------------

@pytest.mark.parametrize("name", bundled_scene_names(meshes=False))
def test_scene_edited_by_every_operation_comes_back_from_its_file(name, tmp_path):
    scene = load_scene(name)
    scene, group = add_object(scene, default_node("smooth_union"))
    scene, torus = add_object(scene, default_node("torus"), group)
    scene, _ = duplicate(scene, torus)
    scene, _ = reparent(scene, (0,), group)
    group = (len(scene.objects) - 1,)
    scene = delete(scene, group + (1, 0))       # the sphere, and the translate holding it
    scene, light = add_light(scene, "spot")
    scene = set_field(scene, f"lights[{light}].inner_angle", 12.5)
    scene, material = add_material(scene)
    scene = set_field(scene, f"materials.{material}.kr", 0.25)
    scene = set_field(scene, node_field_path(scene, group + (1,), "material"), material)
    scene = set_field(scene, node_field_path(scene, group + (2,), "offset"), (0, 1, 0))
    assert node_at(scene, group + (1,)).material == material
    assert node_at(scene, group + (2,)).offset == (0.0, 1.0, 0.0)
    scene = set_field(scene, "objects[0].scale", 1.5)      # wraps objects[0] in a scale node
    scene = set_field(scene, "render.fog.density", 0.125)
    assert round_trip(scene, tmp_path) == scene


# --- Mesh nodes ------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", addable_mesh_kinds())
def test_an_added_mesh_of_each_procedural_kind_is_drawn_and_saved(kind, tmp_path):
    scene = load_scene("meshes")
    edited, index = add_mesh(scene, kind)
    assert index == len(scene.meshes) and edited.meshes[:index] == scene.meshes
    assert edited.meshes[index].kind == kind
    meshes, _ = scene_meshes(edited)
    assert len(meshes) == len(scene_meshes(scene)[0]) + 1 and len(meshes[-1].triangles) > 0
    assert round_trip(edited, tmp_path).meshes == edited.meshes


def test_a_mesh_takes_the_scenes_first_material_where_none_is_called_default():
    scene = load_scene("museum")
    assert "default" not in scene.materials
    edited, index = add_mesh(scene, "cube")
    assert edited.meshes[index].material == next(iter(scene.materials))


def test_an_obj_model_a_group_and_an_unknown_kind_are_not_added_with_defaults():
    for kind in ("obj", "group", "sphere"):
        with pytest.raises(SceneError, match="unknown mesh type"):
            add_mesh(load_scene("meshes"), kind)


def test_a_duplicated_mesh_node_follows_its_original_moved_with_its_children():
    scene = load_scene("museum")
    index = next(i for i, node in enumerate(scene.meshes) if node.children)
    edited, copy = duplicate_mesh(scene, index)
    original, duplicate = edited.meshes[index], edited.meshes[copy]
    assert copy == index + 1 and duplicate.children == original.children
    assert duplicate.position == tuple(a + b for a, b in zip(original.position,
                                                             DUPLICATE_OFFSET))
    assert edited.meshes[:copy] + edited.meshes[copy + 1:] == scene.meshes


def test_deleting_meshes_stops_at_the_last_one():
    scene = load_scene("meshes")
    while len(scene.meshes) > 1:
        scene = delete_mesh(scene, 0)
    with pytest.raises(SceneError, match="at least one mesh"):
        delete_mesh(scene, 0)
    with pytest.raises(SceneError, match="no such entry"):
        delete_mesh(scene, 3)
