"""Scene files: TOML round trips of bundled, random and awkward scenes.

The contract under test (scene_model/scenefile.py): ``load_scene(p) == scene`` after
``save_scene(scene, p)``, with every float back bit for bit; and the writer is deterministic.
The shorthand keys, error messages and overrides are checked in test_scenefile_shorthand.py,
test_scenefile_errors.py and test_scenefile_overrides.py.
"""

from __future__ import annotations

import math
import tomllib

import pytest
from hypothesis import Phase, assume, given, settings
from hypothesis import strategies as st

from marchlab import SceneError, load_scene, save_scene
import marchlab
from scene_model.bodies import Body, PhysicsSettings
from scene_model.scene import (Camera, Checker, DirectionalLight, Fog, Material, PointLight,
                               RenderSettings, Scene, SkyBackground, SolidBackground, SpotLight)
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
