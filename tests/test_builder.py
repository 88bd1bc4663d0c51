"""Building scenes in Python (scene_model/builder.py and the operators of scene_model/shapes.py).

The builder must give the very same dataclasses a scene file gives: ``sphere(1).at(0, 1, 0)``
is ``Translate(Sphere(1.0), (0.0, 1.0, 0.0))``, values are normalised (ints to floats, lists to
tuples) so a built scene equals the loaded one, and a bad value fails at construction with the
name of its field.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from marchlab import SceneError, load_scene
import marchlab
from scene_model import builder
from scene_model.builder import (Camera, Checker, Material, PointLight, Scene, SpotLight, box,
                                 capsule, cone, intersection, plane, round_box, sphere, torus,
                                 union)
from scene_model.shapes import (Intersection, Repeat, Rotate, Scale, SmoothIntersection,
                                SmoothSubtraction, SmoothUnion, Sphere, Subtraction, Translate,
                                Union)


# --- Shapes and operators ----------------------------------------------------------------------

def test_at_wraps_the_node_in_a_translate_with_a_float_offset():
    node = sphere(1).at(0, 1, 0)
    assert node == Translate(Sphere(1.0), (0.0, 1.0, 0.0))
    assert type(node.child.radius) is float
    assert all(type(c) is float for c in node.offset)


def test_translate_is_the_same_as_at():
    assert sphere(1).translate(1, 2, 3) == sphere(1).at(1, 2, 3)


def test_union_of_three_shapes_is_one_flat_union():
    a, b, c = sphere(1), box(1), torus()
    assert a | b | c == Union((a, b, c))
    assert a | (b | c) == Union((a, b, c))
    assert (a | b) | (c | a) == Union((a, b, c, a))


def test_intersection_of_three_shapes_is_one_flat_intersection():
    a, b, c = sphere(1), box(1), torus()
    assert a & b & c == Intersection((a, b, c))
    assert a & (b & c) == Intersection((a, b, c))


def test_union_and_intersection_nest_rather_than_flatten_into_each_other():
    a, b, c = sphere(1), box(1), torus()
    assert (a & b) | c == Union((Intersection((a, b)), c))
    assert (a | b) & c == Intersection((Union((a, b)), c))


def test_minus_builds_a_subtraction_of_the_second_from_the_first():
    a, b = box(1), sphere(1.3)
    assert a - b == Subtraction((a, b))


def test_union_and_intersection_functions_equal_the_operators():
    a, b, c = sphere(1), box(1), torus()
    assert union(a, b, c) == a | b | c
    assert intersection(a, b, c) == a & b & c


@pytest.mark.parametrize("method, cls", [("smooth_union", SmoothUnion),
                                         ("smooth_intersection", SmoothIntersection),
                                         ("smooth_subtraction", SmoothSubtraction)])
def test_smooth_methods_build_the_smooth_node_with_its_blend_width(method, cls):
    a, b = sphere(1), box(1)
    node = getattr(a, method)(b, 1)
    assert node == cls((a, b), 1.0)
    assert type(node.k) is float


def test_rotate_scale_and_repeat_wrap_the_node():
    ball = sphere(0.5)
    assert ball.rotate(0, 45, 0) == Rotate(ball, (0.0, 45.0, 0.0))
    assert ball.rotate(y=45) == Rotate(ball, (0.0, 45.0, 0.0))
    assert ball.scale(2) == Scale(ball, 2.0)
    assert ball.repeat([2, 0, 1]) == Repeat(ball, (2.0, 0.0, 1.0), None)
    assert ball.repeat([2, 0, 1], [3, 0, 1]) == Repeat(ball, (2.0, 0.0, 1.0), (3, 0, 1))


def test_transforms_apply_in_the_order_written():
    # rotate first, then move: the outermost node is the last call.
    cube = box(1)
    assert cube.rotate(0, 45, 0).at(0, 1, 0) == Translate(Rotate(cube, (0.0, 45.0, 0.0)),
                                                          (0.0, 1.0, 0.0))
    assert cube.at(0, 1, 0).rotate(0, 45, 0) == Rotate(Translate(cube, (0.0, 1.0, 0.0)),
                                                       (0.0, 45.0, 0.0))


def test_box_with_one_size_is_a_cube():
    assert box(2).half_size == (2.0, 2.0, 2.0)
    assert box(1, 2, 3).half_size == (1.0, 2.0, 3.0)


# --- Normalisation: a built scene equals the same scene from a file ------------------------------

def test_values_are_normalised_to_floats_ints_and_tuples():
    node = capsule([0, 0, 0], [0, 1, 0], 1).repeat([1, 0, 0], [2, 0, 0])
    assert node.child.a == (0.0, 0.0, 0.0) and type(node.child.a) is tuple
    assert all(type(c) is float for c in node.child.a + node.child.b + node.period)
    assert node.count == (2, 0, 0) and all(type(c) is int for c in node.count)
    scene = Scene(objects=[node], lights=[PointLight(position=[0, 5, 0])],
                  camera=Camera(position=[0, 1, 5], fov=45))
    assert type(scene.objects) is tuple and type(scene.lights) is tuple
    assert scene.lights[0].position == (0.0, 5.0, 0.0)
    assert type(scene.camera.fov) is float and type(scene.camera.position) is tuple


BUILT_AS_FILE = """\
description = "built in Python, or written by hand"

[camera]
position = [0, 2, 6]
look_at = [0, 1, 0]
fov = 45

[materials.default]

[materials.floor]
checker = { scale = 2 }

[materials.red]
color = [1, 0, 0]
shininess = 16

[[lights]]
type = "point"
position = [2, 4, 3]

[[lights]]
type = "spot"
inner_angle = 10
outer_angle = 20

[[objects]]
type = "plane"
material = "floor"

[[objects]]
type = "sphere"
radius = 1
material = "red"
position = [0, 1, 0]

[[objects]]
type = "subtraction"
rotation = [0, 45, 0]
position = [3, 1, 0]
[[objects.children]]
type = "box"
half_size = [1, 1, 1]
[[objects.children]]
type = "sphere"
radius = 1.3

[[objects]]
type = "smooth_union"
k = 0.3
scale = 2
[[objects.children]]
type = "sphere"
radius = 0.6
[[objects.children]]
type = "sphere"
radius = 0.6
position = [0.8, 0, 0]

[[objects]]
type = "repeat"
period = [4, 0, 0]
count = [1, 0, 0]
[objects.child]
type = "torus"
major_radius = 1
minor_radius = 0.25
material = "red"
"""


def test_builder_scene_equals_the_same_scene_loaded_from_a_file(tmp_path):
    built = Scene(
        description="built in Python, or written by hand",
        camera=Camera(position=[0, 2, 6], look_at=[0, 1, 0], fov=45),
        materials={"default": Material(), "floor": Material(checker=Checker(scale=2)),
                   "red": Material(color=[1, 0, 0], shininess=16)},
        lights=[PointLight(position=[2, 4, 3]), SpotLight(inner_angle=10, outer_angle=20)],
        objects=[plane(material="floor"),
                 sphere(1, material="red").at(0, 1, 0),
                 (box(1) - sphere(1.3)).rotate(0, 45, 0).at(3, 1, 0),
                 sphere(0.6).smooth_union(sphere(0.6).at(0.8, 0, 0), k=0.3).scale(2),
                 torus(1, 0.25, material="red").repeat([4, 0, 0], [1, 0, 0])],
    )
    path = tmp_path / "same.toml"
    path.write_text(BUILT_AS_FILE)
    loaded = load_scene(path)
    assert built == loaded
    assert repr(built) == repr(loaded)      # repr tells 1 from 1.0 and a list from a tuple


def example_code(docstring: str) -> str:
    """The indented code block after the first ``::`` of a docstring."""
    block = docstring.split("::", 1)[1]
    lines = []
    for line in block.splitlines()[1:]:
        if line.strip() and not line.startswith("    "):
            break
        lines.append(line[4:])
    return "\n".join(lines)


def test_module_docstring_example_builds_a_scene():
    namespace = {}
    exec(example_code(builder.__doc__), namespace)
    assert isinstance(namespace["scene"], Scene)


# --- Bad values fail at construction, naming the field -------------------------------------------

BAD_CONSTRUCTIONS = {
    "negative_sphere_radius": (lambda: sphere(-1), "radius"),
    "nan_sphere_radius": (lambda: sphere(math.nan), "radius"),
    "bool_sphere_radius": (lambda: sphere(True), "radius"),
    "zero_box_side": (lambda: box(1, 0, 1), "half_size"),
    "round_box_radius_above_half_size": (lambda: round_box(0.5, 1, 1, radius=0.6), "radius"),
    "capsule_with_equal_ends": (lambda: capsule([0, 1, 0], (0.0, 1.0, 0.0)), "b"),
    "negative_torus_tube": (lambda: torus(1, -0.25), "minor_radius"),
    "zero_cone_height": (lambda: cone(0.5, 0), "height"),
    "zero_plane_normal": (lambda: plane((0, 0, 0)), "normal"),
    "repeat_with_zero_period": (lambda: sphere().repeat((0, 0, 0)), "period"),
    "repeat_with_negative_period": (lambda: sphere().repeat((1, -1, 0)), "period"),
    "repeat_with_negative_count": (lambda: sphere().repeat((1, 1, 1), (1, -1, 0)), "count"),
    "repeat_with_float_count": (lambda: sphere().repeat((1, 1, 1), (1.5, 1, 1)), "count"),
    "zero_scale_factor": (lambda: sphere().scale(0), "factor"),
    "zero_smooth_union_width": (lambda: sphere().smooth_union(box(), 0), "k"),
    "short_offset": (lambda: sphere().at(1, 2, [3, 4]), "offset"),
    "colour_above_one": (lambda: Material(color=(1.5, 0, 0)), "color"),
    "spot_inner_not_below_outer": (lambda: SpotLight(inner_angle=30, outer_angle=30),
                                   "inner_angle"),
    "camera_up_along_view": (lambda: Camera(position=(0, 5, 0), look_at=(0, 0, 0),
                                            up=(0, 1, 0)), "up"),
}


@pytest.mark.parametrize("make, field", BAD_CONSTRUCTIONS.values(), ids=BAD_CONSTRUCTIONS.keys())
def test_bad_value_raises_scene_error_at_construction_naming_the_field(make, field):
    with pytest.raises(SceneError) as caught:
        make()
    assert caught.value.path[:1] == (field,)
    assert str(caught.value).startswith(f"{field}")


def test_scene_using_an_undefined_material_raises_scene_error_naming_it():
    with pytest.raises(SceneError) as caught:
        Scene(objects=[plane(), sphere(1, material="gold").at(0, 1, 0)],
              materials={"default": Material()})
    assert "'gold'" in str(caught.value)
    assert "materials" in str(caught.value)


def test_scene_using_only_defined_materials_builds():
    scene = Scene(objects=[plane(), sphere(1, material="gold")],
                  materials={"default": Material(), "gold": Material(color=(1, 0.8, 0.2))})
    assert [prim.material for prim in (scene.objects[0], scene.objects[1])] == ["default",
                                                                                "gold"]


# --- A built scene renders -----------------------------------------------------------------------

def test_built_scene_renders_with_object_ids_in_depth_first_order():
    # Four spheres in a row, nested so that depth-first order (A, B, C, D) differs from both
    # their left-to-right order (D, B, C, A) and a breadth-first walk (C comes first).
    a = sphere(0.65, material="a").at(2.25, 0, 0)
    b = sphere(0.65, material="b").at(-0.75, 0, 0)
    c = sphere(0.65, material="c").at(0.75, 0, 0)
    d = sphere(0.65, material="d").rotate(0, 30, 0).at(-2.25, 0, 0)
    scene = Scene(camera=Camera(position=(0, 0, 10), look_at=(0, 0, 0), fov=30),
                  materials={name: Material() for name in "abcd"},
                  objects=[(a | b).scale(1), c, union(d)])
    frame = marchlab.render(scene, 16, 12)
    assert sorted(np.unique(frame.object_id[frame.hit])) == [0, 1, 2, 3]
    assert np.all(frame.object_id[~frame.hit] == -1)
    columns = np.arange(16)[None, :].repeat(12, axis=0)
    mean_column = {i: columns[frame.object_id == i].mean() for i in range(4)}
    assert sorted(mean_column, key=mean_column.get) == [3, 1, 2, 0]
