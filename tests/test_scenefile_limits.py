"""Every number of a scene has a range that means something, declared once with its field.

The ranges live in the ``check`` of each field (scene_model/fields.py, scene.py, shapes.py,
bodies.py); the same object refuses a value, names the bound in the message and writes the
*allowed* column of docs/scene-format.md. These tests walk every scene class, so a field added
without a range, or a range that does not refuse what it says, is caught.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import types
import typing

import numpy as np
import pytest

from marchlab import SceneError, docgen, load_scene
from scene_model.fields import (COORDINATE, MAX_COORDINATE, MAX_SIZE, MIN_SIZE, POINT, SIZE,
                                SIZES, Each, Range, Record, number_text)
from scene_model.scene import Camera, PointLight, RenderSettings, SpotLight
from scene_model.mesh_objects import MeshObject, mesh_kinds
from scene_model.scenefile import scene_path
from scene_model.shapes import Capsule, Sphere


def record_classes() -> list[type]:
    """Every concrete scene class of scene_model (a test's own node classes left out)."""
    found, stack = [], [Record]
    while stack:
        cls = stack.pop()
        stack.extend(cls.__subclasses__())
        # Only classes declared as dataclasses: a base such as ProceduralMesh adds no field.
        if "__dataclass_fields__" in cls.__dict__ and cls.__module__.startswith("scene_model."):
            found.append(cls)
    return sorted(found, key=lambda c: c.__name__)


def make(cls, **values):
    """``cls(**values)``, filling the fields that have no default (a node's children: two
    spheres, which every operator takes, a morph exactly)."""
    for f in dataclasses.fields(cls):
        if f.name not in values and f.default is dataclasses.MISSING \
                and f.default_factory is dataclasses.MISSING:
            values[f.name] = (Sphere(), Sphere()) if f.name == "children" else Sphere()
    return cls(**values)


def default_of(f: dataclasses.Field):
    return f.default_factory() if f.default is dataclasses.MISSING else f.default


def ranged_fields():
    """``(cls, field, range, is_vector)`` for every field whose check is a Range."""
    for cls in record_classes():
        for f in dataclasses.fields(cls):
            check = f.metadata.get("check")
            rule = check.check if isinstance(check, Each) else check
            if isinstance(rule, Range):
                yield pytest.param(cls, f, rule, isinstance(check, Each),
                                   id=f"{cls.__name__}.{f.name}")


def just_beyond(rule: Range) -> list:
    """The nearest values outside ``rule`` on each side."""
    if isinstance(rule.lo, int) and isinstance(rule.hi, int):
        return [rule.lo - 1, rule.hi + 1]
    return [rule.lo if rule.lo_open else math.nextafter(rule.lo, -math.inf),
            rule.hi if rule.hi_open else math.nextafter(rule.hi, math.inf)]


def with_component(f, value):
    """The field's default vector (zeros if absent) with component 0 set to ``value``."""
    default = default_of(f) or (0, 0, 0)
    return (value,) + tuple(default[1:])


# --- Ranges ----------------------------------------------------------------------------------

@pytest.mark.parametrize("cls, f, rule, is_vector", list(ranged_fields()))
def test_every_range_refuses_the_nearest_value_beyond_each_end_naming_the_field(cls, f, rule,
                                                                               is_vector):
    for bad in just_beyond(rule):
        value = with_component(f, bad) if is_vector else bad
        with pytest.raises(SceneError) as caught:
            make(cls, **{f.name: value})
        expected_path = (f.name, 0) if is_vector else (f.name,)
        assert caught.value.path == expected_path, str(caught.value)
        bound = "positive" if rule.positive and bad <= 0 else number_text(
            rule.lo if bad < rule.hi else rule.hi)
        assert bound in caught.value.problem and "\n" not in str(caught.value)


def test_every_number_field_of_the_scene_declares_a_range_or_a_rule():
    """A number field with no check at all would accept 1e308; each must say what it allows."""
    unchecked = []
    for cls in record_classes():
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            if _holds_numbers(hints[f.name]) and f.metadata.get("check") is None:
                unchecked.append(f"{cls.__name__}.{f.name}")
    assert unchecked == []


def _holds_numbers(hint) -> bool:
    if hint in (int, float):
        return True
    return any(_holds_numbers(arg) for arg in typing.get_args(hint) if arg is not Ellipsis)


def _is_vector(hint) -> bool:
    """A tuple, or an optional tuple (``Int3 | None``)."""
    return typing.get_origin(hint) is tuple or any(typing.get_origin(arg) is tuple
                                                   for arg in typing.get_args(hint))


COORDINATE_FIELDS = {"Camera.position", "Camera.look_at", "PointLight.position",
                     "SpotLight.position", "Translate.offset", "Capsule.a", "Capsule.b",
                     "Body.position", "Motion.pivot"} | {
                     f"{cls.__name__}.position" for cls in (MeshObject, *mesh_kinds().values())}
SIZE_FIELDS = {"Sphere.radius", "Box.half_size", "RoundBox.half_size", "RoundBox.radius",
               "Torus.major_radius", "Torus.minor_radius", "CappedCylinder.radius",
               "CappedCylinder.half_height", "Capsule.radius", "Cone.radius", "Cone.height",
               "Pyramid.base", "Pyramid.height", "Disk.radius", "Disk.thickness",
               "HexPrism.apothem", "HexPrism.half_length",
               "SmoothUnion.k", "SmoothIntersection.k", "SmoothSubtraction.k", "Scale.factor",
               "Checker.scale", "Texture.scale", "Body.radius", "Body.half_size",
               "Body.half_length"} | {
               f"{cls.__name__}.{f.name}" for cls in (MeshObject, *mesh_kinds().values())
               for f in dataclasses.fields(cls)
               if f.name in ("scale", "radius", "width", "depth", "size", "height", "base",
                             "major", "minor")}


def fields_checked_by(*checks) -> dict[str, tuple]:
    return {f"{cls.__name__}.{f.name}": (cls, f) for cls in record_classes()
            for f in dataclasses.fields(cls) if f.metadata.get("check") in checks}


def test_every_coordinate_beyond_1e6_is_refused_naming_its_field():
    fields = fields_checked_by(POINT)
    assert set(fields) == COORDINATE_FIELDS
    for name, (cls, f) in fields.items():
        for bad in (1.000001e6, -1.000001e6, 1e308):
            with pytest.raises(SceneError) as caught:
                make(cls, **{f.name: (0.5, bad, 0.25)})
            assert caught.value.path == (f.name, 1), name
            assert f"must be {'<=' if bad > 0 else '>='}" in caught.value.problem, name
        make(cls, **{f.name: (MAX_COORDINATE, -MAX_COORDINATE, 2.0)})   # the ends are allowed


def test_every_size_outside_1e_minus_6_to_1e6_is_refused_naming_its_field():
    fields = fields_checked_by(SIZE, SIZES)
    assert set(fields) == SIZE_FIELDS
    for name, (cls, f) in fields.items():
        is_vector = f.metadata["check"] is SIZES
        for bad, problem in ((1e-300, "must be >= 1e-6"), (0.999e-6, "must be >= 1e-6"),
                             (1.001e6, "must be <= 1e6"), (0.0, "must be positive"),
                             (-1.0, "must be positive")):
            value = (bad, 1.0, 1.0) if is_vector else bad
            with pytest.raises(SceneError) as caught:
                make(cls, **{f.name: value})
            assert caught.value.path == ((f.name, 0) if is_vector else (f.name,)), name
            assert caught.value.problem.startswith(problem), (name, str(caught.value))


def test_a_plane_offset_is_a_coordinate():
    assert fields_checked_by(COORDINATE).keys() == {"Plane.offset"}


def test_epsilon_must_be_less_than_max_distance_naming_epsilon():
    with pytest.raises(SceneError) as caught:
        load_scene("classroom", ["render.max_distance=0.5", "render.epsilon=0.5"])
    assert str(caught.value).endswith("render.epsilon: must be less than max_distance 0.5 "
                                      "(got 0.5)")
    assert RenderSettings(epsilon=0.4, max_distance=0.5).epsilon == 0.4


@pytest.mark.parametrize("cls", [PointLight, SpotLight])
def test_attenuation_cannot_divide_by_zero_because_constant_is_at_least_1e_minus_3(cls):
    # constant + linear d + quadratic d^2 >= constant for d >= 0, as linear, quadratic >= 0.
    for constant in (0.0, 1e-300, 0.999e-3):
        with pytest.raises(SceneError) as caught:
            cls(constant=constant, linear=1.0, quadratic=1.0)
        assert caught.value.path == ("constant",)
    for term in ("linear", "quadratic"):
        with pytest.raises(SceneError):
            cls(**{term: -1e-9})
    weakest = cls(constant=1e-3, linear=0.0, quadratic=0.0)
    assert 1 / weakest.constant == pytest.approx(1000.0)


def test_a_spot_light_soft_edge_is_at_least_a_tenth_of_a_degree():
    with pytest.raises(SceneError) as caught:
        SpotLight(inner_angle=29.95, outer_angle=30.0)
    assert str(caught.value) == ("inner_angle: must be less than outer_angle 30.0 by at least "
                                 "0.1 degrees (got 29.95)")
    assert SpotLight(inner_angle=29.9, outer_angle=30.0).inner_angle == 29.9


def test_capsule_ends_closer_than_1e_minus_6_are_refused_naming_b():
    with pytest.raises(SceneError) as caught:
        Capsule(a=(0.0, 0.0, 0.0), b=(1e-300, 0.0, 0.0))
    assert caught.value.path == ("b",) and "at least 1e-6 from a" in str(caught.value)
    assert Capsule(a=(0.0, 0.0, 0.0), b=(1e-6, 0.0, 0.0)).b == (1e-6, 0.0, 0.0)


def test_physics_dt_out_of_range_is_refused_naming_physics_dt():
    for value, problem in (("1e308", "must be <= 0.1 (got 1e+308)"),
                           ("1e-300", "must be >= 1e-6 (got 1e-300)"),
                           ("0", "must be positive (got 0.0)")):
        with pytest.raises(SceneError) as caught:
            load_scene("bounce", [f"physics.dt={value}"])
        assert str(caught.value) == f"bounce: physics.dt: {problem}"


def test_the_field_reference_states_each_declared_range_in_its_allowed_column():
    text = docgen.reference()
    for cls in record_classes():
        for f in dataclasses.fields(cls):
            check = f.metadata.get("check")
            if check is not None:
                row = f"| `{f.name}` |"
                assert any(line.startswith(row) and f"| {check.allowed} |" in line
                           for line in text.splitlines()), f"{cls.__name__}.{f.name}"


def test_the_limits_section_of_the_docs_names_the_declared_bounds():
    text = docgen.DOC.read_text()
    limits = text[text.index("## Limits"):text.index(docgen.BEGIN)]
    assert number_text(MAX_COORDINATE) == "1e6" and "±10⁶" in limits
    assert number_text(MIN_SIZE) == "1e-6" and number_text(MAX_SIZE) == "1e6"
    assert "from 10⁻⁶ to 10⁶" in limits and "100 000" in limits and "64 levels" in limits


# --- Numbers must be numbers, of any size ----------------------------------------------------

def numeric_leaves(tree, path=()):
    """``(path, value)`` of every number (not bool) in a parsed TOML tree."""
    items = tree.items() if isinstance(tree, dict) else enumerate(tree)
    for key, value in items:
        if isinstance(value, (dict, list)):
            yield from numeric_leaves(value, path + (key,))
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            yield path + (key,), value


def override_path(path) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path).lstrip(".")


BUNDLED_LEAVES = [(name, override_path(path))
                  for name in ("classroom", "bounce", "csg", "lights", "repetition")
                  for path, _ in numeric_leaves(tomllib.loads(scene_path(name).read_text()))]


@pytest.mark.parametrize("name, field", BUNDLED_LEAVES)
def test_a_quoted_number_is_refused_for_every_number_of_the_bundled_scenes(name, field):
    with pytest.raises(SceneError) as caught:
        load_scene(name, [f'{field}="50"'])
    message = str(caught.value)
    assert "must be a number (got '50')" in message and "\n" not in message
    assert message.split(": ")[1].startswith(field.split(".")[0])


def _quoted(hint):
    """A value of the shape ``hint`` asks for with "50" for every number: "50", a tuple of
    them, or one such tuple in a list of them (``tuple[Vec3, ...]``, keyframes)."""
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    if typing.get_origin(hint) is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return (_quoted(args[0]),)
        return tuple(_quoted(a) for a in args)
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        return _quoted(args[0])
    return "50"


def test_a_quoted_number_is_refused_for_every_number_field_of_every_class():
    for cls in record_classes():
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            if _holds_numbers(hints[f.name]):
                value = _quoted(hints[f.name])
                with pytest.raises(SceneError) as caught:
                    make(cls, **{f.name: value})
                assert caught.value.path[0] == f.name
                assert "must be a number (got '50')" in caught.value.problem


def test_a_quoted_fov_in_a_scene_file_is_refused(tmp_path):
    path = tmp_path / "quoted.toml"
    path.write_text('[camera]\nfov = "50"\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value) == f"{path}: camera.fov: must be a number (got '50')"


def int_fields():
    """``(cls, field, is_vector)`` for every field holding integers (max_steps, count, ...)."""
    for cls in record_classes():
        for f in dataclasses.fields(cls):
            hint = typing.get_type_hints(cls)[f.name]
            if _holds_numbers(hint) and float not in _leaf_types(hint):
                yield pytest.param(cls, f, _is_vector(hint), id=f"{cls.__name__}.{f.name}")


def _leaf_types(hint) -> set:
    args = [a for a in typing.get_args(hint) if a is not Ellipsis]
    return {hint} if not args else set().union(*map(_leaf_types, args))


@pytest.mark.parametrize("cls, f, is_vector", list(int_fields()))
def test_an_integer_too_large_for_c_is_refused_in_one_line(cls, f, is_vector):
    for huge in (2**63, 10**30, -(10**30), 10**5000):
        value = (huge, 0, 0) if is_vector else huge
        with pytest.raises(SceneError) as caught:
            make(cls, **{f.name: value})
        assert caught.value.path[0] == f.name and "\n" not in str(caught.value)
        assert "must be" in caught.value.problem


@pytest.mark.parametrize("value", ["9223372036854775808", str(10**30), "1" + "0" * 5000])
def test_an_integer_too_large_for_c_is_refused_in_one_line_from_a_file_and_from_set(tmp_path,
                                                                                   value):
    path = tmp_path / "huge.toml"
    path.write_text(f"[render]\nmax_steps = {value}\n")
    for load in (lambda: load_scene(path), lambda: load_scene("classroom",
                                                              [f"render.max_steps={value}"])):
        with pytest.raises(SceneError) as caught:
            load()
        message = str(caught.value)
        assert "\n" not in message and len(message) < 200
        assert "render.max_steps" in message or message.startswith(f"{path}: has an integer")


def test_an_integer_too_large_for_a_float_is_refused_naming_its_field():
    with pytest.raises(SceneError) as caught:
        load_scene("classroom", ["camera.fov=1" + "0" * 400])
    assert str(caught.value) == "classroom: camera.fov: is too large (got an integer of 401 digits)"


def test_numpy_scalars_are_numbers_and_numpy_bools_are_not():
    assert RenderSettings(max_steps=np.int64(64), epsilon=np.float32(0.5)).max_steps == 64
    assert type(Camera(fov=np.float32(45.0)).fov) is float
    with pytest.raises(SceneError, match="must be a number"):
        Camera(fov=np.bool_(True))
    with pytest.raises(SceneError, match="must be an integer"):
        RenderSettings(max_steps=np.float64(64.0))
