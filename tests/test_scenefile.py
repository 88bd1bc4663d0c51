"""Scene files: TOML round trips, the position/rotation/scale shorthand, and error messages.

The contract under test (scene_model/scenefile.py): ``load_scene(p) == scene`` after
``save_scene(scene, p)``, with every float back bit for bit; the writer is deterministic; and
every bad input raises `SceneError` whose text is ``FILE: FIELD.PATH: problem``, the path being
the one a user sees in the file (``objects[1].children[0].radius``, ``objects[0].scale``).
"""

from __future__ import annotations

import math
import tomllib

import pytest
import tomlkit
from hypothesis import Phase, assume, given, settings
from hypothesis import strategies as st

from marchlab import SceneError, load_scene, save_scene
import marchlab
from scene_model.bodies import Body, PhysicsSettings
from scene_model.scene import (Camera, Checker, DirectionalLight, Fog, Material, PointLight,
                               RenderSettings, Scene, SkyBackground, SolidBackground, SpotLight)
from scene_model.scenefile import scene_path, scene_to_toml
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Intersection, Plane, Repeat,
                                Rotate, RoundBox, Scale, SmoothIntersection, SmoothSubtraction,
                                SmoothUnion, Sphere, Subtraction, Torus, Translate, Union,
                                primitives as primitives_of)

BUNDLED = marchlab.bundled_scene_names()
TOP_LEVEL_KEYS = {"description", "camera", "render", "materials", "lights", "objects", "physics",
                  "bodies"}


def round_trip(scene: Scene, tmp_path, name: str = "scene.toml") -> Scene:
    """Save ``scene`` to a file under ``tmp_path`` and load it back."""
    path = tmp_path / name
    save_scene(scene, path)
    return load_scene(path)


def assert_identical(loaded: Scene, original: Scene) -> None:
    """Dataclass equality, plus equal reprs: repr shows every float exactly (and -0.0's sign),
    which ``==`` does not (``-0.0 == 0.0``)."""
    assert loaded == original
    assert repr(loaded) == repr(original)


# --- Bundled scenes ----------------------------------------------------------------------------

def test_at_least_the_classroom_scene_is_bundled():
    assert "classroom" in BUNDLED


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_scene_round_trips_through_a_saved_file(name, tmp_path):
    original = load_scene(name)
    assert_identical(round_trip(original, tmp_path), original)


@pytest.mark.parametrize("name", BUNDLED)
def test_saving_a_reloaded_bundled_scene_gives_byte_identical_text(name, tmp_path):
    first, second = tmp_path / "first.toml", tmp_path / "second.toml"
    save_scene(load_scene(name), first)
    save_scene(load_scene(first), second)
    assert second.read_bytes() == first.read_bytes()


@pytest.mark.parametrize("name", BUNDLED)
def test_saved_bundled_scene_is_valid_toml_with_only_scene_keys(name, tmp_path):
    path = tmp_path / "scene.toml"
    save_scene(load_scene(name), path)
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    assert set(data) <= TOP_LEVEL_KEYS
    assert data["description"] == load_scene(name).description


# --- Random scenes -----------------------------------------------------------------------------
# Floats include the awkward ones on purpose: 0.1 + 0.2 (not 0.3), the tiniest normal and
# subnormal numbers, the largest float and -0.0 (whose sign `==` cannot see).

AWKWARD = [0.1 + 0.2, 1e-300, 5e-324, 1 / 3, 1e300, 1.7976931348623157e308, 123456789.123456789]
REALS = st.sampled_from(AWKWARD + [-x for x in AWKWARD] + [-0.0, 0.0]) | st.floats(
    allow_nan=False, allow_infinity=False)
POSITIVE = st.sampled_from(AWKWARD) | st.floats(min_value=0.0, exclude_min=True,
                                                allow_infinity=False)
NONNEGATIVE = POSITIVE | st.sampled_from([0.0, -0.0])      # -0.0 >= 0, so it is allowed
UNIT = st.sampled_from([0.0, -0.0, 1.0, 0.1 + 0.2, 1e-300, 5e-324]) | st.floats(0.0, 1.0)
COLORS = st.tuples(UNIT, UNIT, UNIT)
VECTORS = st.tuples(REALS, REALS, REALS)
NONZERO_VECTORS = VECTORS.filter(lambda v: any(c != 0 for c in v))
NAMES = st.text(max_size=6)                   # TOML keys may be empty, dotted, quoted, unicode
# Material names the random trees use: keys TOML must quote, escape or keep apart.
MATERIAL_NAMES = ["default", "", "a.b", 'say "hi"', "two words", "\u00e9t\u00e9", "tab\there"]


def vectors_of(elements):
    return st.tuples(elements, elements, elements)


@st.composite
def valid(draw, cls, **fields):
    """``cls(**drawn fields)``, discarding draws that break a cross-field rule of ``cls``."""
    kwargs = {name: draw(strategy) for name, strategy in fields.items()}
    try:
        return cls(**kwargs)
    except SceneError:
        assume(False)


@st.composite
def round_boxes(draw, material):
    half_size = draw(vectors_of(POSITIVE))
    radius = draw(st.floats(min_value=0.0, max_value=min(half_size), exclude_min=True))
    return RoundBox(half_size, radius, material=draw(material))


def primitive_nodes(material):
    """Every primitive kind, with random valid parameters and a material from the scene."""
    return st.one_of(
        st.builds(Sphere, POSITIVE, material=material),
        st.builds(Box, vectors_of(POSITIVE), material=material),
        round_boxes(material),
        st.builds(Plane, NONZERO_VECTORS, REALS, material=material),
        st.builds(Torus, POSITIVE, POSITIVE, material=material),
        st.builds(CappedCylinder, POSITIVE, POSITIVE, material=material),
        valid(Capsule, a=VECTORS, b=VECTORS, radius=POSITIVE, material=material),
        st.builds(Cone, POSITIVE, POSITIVE, material=material),
    )


PERIODS = vectors_of(NONNEGATIVE).filter(lambda v: any(c != 0 for c in v))
COUNTS = st.none() | vectors_of(st.integers(0, 2**63 - 1))
TRANSFORM_KINDS = ["translate", "rotate", "scale", "repeat"]


def wrap(kind: str, node, draw):
    """``node`` inside one transform of ``kind`` with random parameters."""
    if kind == "translate":
        return Translate(node, draw(VECTORS))
    if kind == "rotate":
        return Rotate(node, draw(VECTORS))
    if kind == "scale":
        return Scale(node, draw(POSITIVE))
    return Repeat(node, draw(PERIODS), draw(COUNTS))


@st.composite
def transform_chains(draw, inner):
    """``inner`` wrapped in 0..6 transforms in any order, e.g. Scale(Rotate(Translate(x)))."""
    node = draw(inner)
    for kind in draw(st.lists(st.sampled_from(TRANSFORM_KINDS), max_size=6)):
        node = wrap(kind, node, draw)
    return node


def trees(material):
    """SDF trees mixing every primitive, CSG operator (plain and smooth) and transform."""
    def extend(inner):
        kids = st.lists(inner, min_size=1, max_size=3).map(tuple)
        return st.one_of(
            st.builds(Union, kids), st.builds(Intersection, kids), st.builds(Subtraction, kids),
            st.builds(SmoothUnion, kids, POSITIVE), st.builds(SmoothIntersection, kids, POSITIVE),
            st.builds(SmoothSubtraction, kids, POSITIVE),
            st.builds(Translate, inner, VECTORS), st.builds(Rotate, inner, VECTORS),
            st.builds(Scale, inner, POSITIVE), st.builds(Repeat, inner, PERIODS, COUNTS),
            transform_chains(inner),
        )
    return st.recursive(primitive_nodes(material), extend, max_leaves=8)


MATERIALS = st.builds(Material, COLORS, UNIT, UNIT, UNIT, POSITIVE, UNIT,
                      st.none() | st.builds(Checker, COLORS, COLORS, POSITIVE))
ATTENUATION = dict(constant=NONNEGATIVE, linear=NONNEGATIVE, quadratic=NONNEGATIVE)
LIGHTS = st.one_of(
    valid(PointLight, position=VECTORS, color=COLORS, intensity=NONNEGATIVE, **ATTENUATION),
    st.builds(DirectionalLight, NONZERO_VECTORS, COLORS, NONNEGATIVE),
    valid(SpotLight, position=VECTORS, direction=NONZERO_VECTORS, color=COLORS,
          intensity=NONNEGATIVE, inner_angle=st.floats(0.0, 89.0),
          outer_angle=st.floats(0.0, 90.0, exclude_min=True, exclude_max=True), **ATTENUATION),
)
BACKGROUNDS = st.builds(SolidBackground, COLORS) | st.builds(SkyBackground, COLORS, COLORS)
CAMERAS = valid(Camera, position=VECTORS, look_at=VECTORS, up=NONZERO_VECTORS,
                fov=st.floats(0.0, 180.0, exclude_min=True, exclude_max=True))
RENDER_SETTINGS = st.builds(
    RenderSettings,
    max_steps=st.integers(1, 2**63 - 1), epsilon=POSITIVE, max_distance=POSITIVE,
    normal_method=st.sampled_from(["central", "tetrahedron"]), normal_step=POSITIVE,
    shadows=st.sampled_from(["none", "hard", "soft"]), penumbra_k=POSITIVE,
    surface_offset=NONNEGATIVE, reflection_depth=st.integers(0, 16),
    shading=st.sampled_from(["phong", "blinn_phong", "toon", "normals", "depth", "steps"]),
    toon_bands=st.integers(2, 2**63 - 1), ambient=COLORS, gamma=POSITIVE,
    fog=st.builds(Fog, COLORS, NONNEGATIVE), background=BACKGROUNDS)


TREES = trees(st.sampled_from(MATERIAL_NAMES))

PHYSICS = st.none() | st.builds(
    PhysicsSettings, gravity=VECTORS, dt=POSITIVE,
    integrator=st.sampled_from(["semi_implicit", "explicit", "verlet"]),
    solver=st.sampled_from(["sequential", "simultaneous"]), seed=st.integers(0, 2**63 - 1),
    restitution=UNIT, friction=NONNEGATIVE, density=POSITIVE, plane_restitution=UNIT,
    plane_friction=NONNEGATIVE)


def bodies(material):
    """Bodies with mass, density or neither (never both), optional restitution and friction."""
    weight = st.one_of(st.just({}), st.builds(lambda m: {"mass": m}, POSITIVE),
                       st.builds(lambda d: {"density": d}, POSITIVE))
    return st.builds(lambda weight, **kwargs: Body(**weight, **kwargs), weight,
                     position=VECTORS, velocity=VECTORS, angular_velocity=VECTORS,
                     radius=POSITIVE, restitution=st.none() | UNIT,
                     friction=st.none() | NONNEGATIVE, material=material)

# Whole scenes are big: on a failure, shrink to one small example and skip the slow "explain"
# phase, so a broken writer is reported in seconds rather than minutes.
QUICK_TO_REPORT = dict(report_multiple_bugs=False,
                       phases=[phase for phase in Phase if phase is not Phase.explain])


@st.composite
def scenes(draw):
    objects = draw(st.lists(TREES, max_size=3))
    moving = draw(st.lists(bodies(st.sampled_from(MATERIAL_NAMES)), max_size=2))
    used = [prim.material for prim in primitives_of(objects)] + [b.material for b in moving]
    names = dict.fromkeys(draw(st.lists(NAMES, min_size=1, max_size=2)) + used)
    return Scene(description=draw(st.text(max_size=20)), camera=draw(CAMERAS),
                 render=draw(RENDER_SETTINGS),
                 materials={name: draw(MATERIALS) for name in names},
                 lights=draw(st.lists(LIGHTS, max_size=3)), objects=objects,
                 physics=draw(PHYSICS), bodies=moving)


@settings(max_examples=100, **QUICK_TO_REPORT)
@given(scenes())
def test_random_scene_round_trips_exactly(tmp_path_factory, scene):
    tmp_path = tmp_path_factory.mktemp("scene")
    assert_identical(round_trip(scene, tmp_path), scene)


@settings(max_examples=40, **QUICK_TO_REPORT)
@given(scenes())
def test_random_scene_saves_as_valid_toml_and_the_writer_is_deterministic(tmp_path_factory,
                                                                           scene):
    tmp_path = tmp_path_factory.mktemp("scene")
    first, second = tmp_path / "first.toml", tmp_path / "second.toml"
    save_scene(scene, first)
    save_scene(load_scene(first), second)
    assert set(tomllib.loads(first.read_text(encoding="utf-8"))) <= TOP_LEVEL_KEYS
    assert second.read_bytes() == first.read_bytes()


@settings(**QUICK_TO_REPORT)
@given(transform_chains(primitive_nodes(st.just("default"))))
def test_random_transform_chain_round_trips_exactly(tmp_path_factory, node):
    scene = Scene(objects=(node,))
    assert_identical(round_trip(scene, tmp_path_factory.mktemp("chain")), scene)


BALL = Sphere(0.5)
AWKWARD_CHAINS = {
    "translate_translate": Translate(Translate(BALL, (1, 0, 0)), (0, 2, 0)),
    "rotate_translate": Rotate(Translate(BALL, (1, 0, 0)), (0, 90, 0)),
    "scale_rotate_translate": Scale(Rotate(Translate(BALL, (1, 0, 0)), (0, 90, 0)), 2.0),
    "scale_translate": Scale(Translate(BALL, (1, 0, 0)), 2.0),
    "rotate_scale": Rotate(Scale(BALL, 2.0), (10, 0, 0)),
    "translate_scale_rotate": Translate(Scale(Rotate(BALL, (10, 0, 0)), 2.0), (0, 1, 0)),
    "scale_scale": Scale(Scale(BALL, 2.0), 3.0),
    "rotate_rotate": Rotate(Rotate(BALL, (10, 0, 0)), (0, 20, 0)),
    "translate_rotate_scale_translate_rotate_scale":
        Translate(Rotate(Scale(Translate(Rotate(Scale(BALL, 2.0), (1, 2, 3)), (4, 5, 6)), 0.5),
                         (7, 8, 9)), (1, 1, 1)),
    "translate_repeat_translate":
        Translate(Repeat(Translate(BALL, (0.1, 0, 0)), (2, 0, 0), (1, 0, 0)), (0, 1, 0)),
    "translate_of_union": Translate(Union((BALL, Rotate(Box(), (0, 45, 0)))), (0, 1, 0)),
    "scale_of_rotated_subtraction": Scale(Rotate(Subtraction((Box(), BALL)), (0, 30, 0)), 1.5),
}


@pytest.mark.parametrize("node", AWKWARD_CHAINS.values(), ids=AWKWARD_CHAINS.keys())
def test_awkward_transform_chain_round_trips_exactly(node, tmp_path):
    scene = Scene(objects=(node,))
    assert_identical(round_trip(scene, tmp_path), scene)


def test_awkward_floats_come_back_bit_for_bit_including_the_sign_of_zero(tmp_path):
    offset = (0.1 + 0.2, 1e-300, -0.0)
    scene = Scene(camera=Camera(position=(-0.0, 5e-324, 1.7976931348623157e308)),
                  objects=(Translate(Plane((0.0, 1.0, -0.0), -1e-300), offset),))
    loaded = round_trip(scene, tmp_path)
    assert loaded.objects[0].offset[0] == 0.30000000000000004
    assert loaded.objects[0].offset[1] == 1e-300
    assert math.copysign(1.0, loaded.objects[0].offset[2]) == -1.0
    assert math.copysign(1.0, loaded.objects[0].child.normal[2]) == -1.0
    assert math.copysign(1.0, loaded.camera.position[0]) == -1.0
    assert loaded.camera.position[1:] == (5e-324, 1.7976931348623157e308)
    assert_identical(loaded, scene)


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


# --- Overrides (--set) through the API -----------------------------------------------------------

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


def test_a_file_that_is_not_utf8_is_refused_in_one_line(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'description = "caf\xe9"\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert str(caught.value) == f"{path}: not UTF-8 text, as TOML requires (byte 0xe9 at offset 18)"


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
