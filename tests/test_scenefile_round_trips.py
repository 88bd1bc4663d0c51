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
from scene_model.fields import DIRECTION, Each
from scene_model.scene import (Camera, Checker, CubeMapBackground, DirectionalLight,
                               EquirectBackground, Fog, Material, PointLight, RenderSettings,
                               Scene, SkyBackground, SolidBackground, SpotLight, StudioBackground,
                               Texture)
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Intersection,
                                Morph, Plane, Pyramid, Repeat, Rotate, RoundBox, Scale,
                                SmoothIntersection, SmoothSubtraction, SmoothUnion, Sphere,
                                Subtraction, Torus, Translate, Union, primitives as primitives_of)


BUNDLED = marchlab.bundled_scene_names()
TOP_LEVEL_KEYS = {"description", "camera", "render", "materials", "lights", "objects", "meshes",
                  "physics", "bodies", "keyframes"}


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
# Each number is drawn from the range its field declares (scene_model/fields.py), and includes
# awkward floats on purpose where the range allows them: 0.1 + 0.2 (not 0.3), the tiniest
# normal and subnormal numbers, the ends of the ranges and -0.0 (whose sign `==` cannot see).

AWKWARD = [0.1 + 0.2, 1e-300, 5e-324, 1 / 3, 1e-9, 1e-6, 123456.789123456789,
           math.nextafter(1e6, 0.0), 1e6, 1e7]
AWKWARD = AWKWARD + [-x for x in AWKWARD] + [0.0, -0.0, 1.0]


def declared_range(cls, name):
    """The `Range` a field's check declares (for a vector, the one each component obeys)."""
    check = cls.__dataclass_fields__[name].metadata["check"]
    return check.check if isinstance(check, Each) else check


def numbers(cls, name):
    """Floats the field ``cls.name`` allows: awkward ones, and any in its declared range."""
    rule = declared_range(cls, name)
    inside = [x for x in AWKWARD if rule(x) is None]
    anywhere = st.floats(rule.lo, rule.hi, exclude_min=rule.lo_open, exclude_max=rule.hi_open)
    return st.sampled_from(inside) | anywhere.filter(lambda x: rule(x) is None)


def integers(cls, name):
    rule = declared_range(cls, name)
    return st.integers(rule.lo, rule.hi)


def vectors_of(elements):
    return st.tuples(elements, elements, elements)


def vectors(cls, name):
    return vectors_of(numbers(cls, name))


UNIT = st.sampled_from([0.0, -0.0, 1.0, 0.1 + 0.2, 1e-300, 5e-324]) | st.floats(0.0, 1.0)
COLORS = st.tuples(UNIT, UNIT, UNIT)
POINTS = vectors(Translate, "offset")
SIZES = numbers(Sphere, "radius")
DIRECTIONS = POINTS.filter(lambda v: DIRECTION(v) is None)
NAMES = st.text(max_size=6)                   # TOML keys may be empty, dotted, quoted, unicode
# Material names the random trees use: keys TOML must quote, escape or keep apart.
MATERIAL_NAMES = ["default", "", "a.b", 'say "hi"', "two words", "\u00e9t\u00e9", "tab\there"]


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
    half_size = draw(vectors_of(SIZES))
    radius = draw(st.floats(min_value=1e-6, max_value=min(half_size)))
    return RoundBox(half_size, radius, material=draw(material))


def primitive_nodes(material):
    """Every primitive kind, with random valid parameters and a material from the scene."""
    return st.one_of(
        st.builds(Sphere, SIZES, material=material),
        st.builds(Box, vectors_of(SIZES), material=material),
        round_boxes(material),
        st.builds(Plane, DIRECTIONS, numbers(Plane, "offset"), material=material),
        st.builds(Torus, SIZES, SIZES, material=material),
        st.builds(CappedCylinder, SIZES, SIZES, material=material),
        valid(Capsule, a=POINTS, b=POINTS, radius=SIZES, material=material),
        st.builds(Cone, SIZES, SIZES, material=material),
        st.builds(Pyramid, SIZES, SIZES, material=material),
        valid(Disk, radius=SIZES, thickness=SIZES, material=material),
        st.builds(HexPrism, SIZES, SIZES, material=material),
    )


PERIODS = vectors_of(st.just(0.0) | SIZES).filter(lambda v: any(c != 0 for c in v))
COUNTS = st.none() | vectors_of(integers(Repeat, "count"))
ANGLES = vectors(Rotate, "degrees")
TRANSFORM_KINDS = ["translate", "rotate", "scale", "repeat"]


def wrap(kind: str, node, draw):
    """``node`` inside one transform of ``kind`` with random parameters."""
    if kind == "translate":
        return Translate(node, draw(POINTS))
    if kind == "rotate":
        return Rotate(node, draw(ANGLES))
    if kind == "scale":
        return Scale(node, draw(SIZES))
    return Repeat(node, draw(PERIODS), draw(COUNTS))


@st.composite
def transform_chains(draw, inner):
    """``inner`` wrapped in 0..6 transforms in any order, e.g. Scale(Rotate(Translate(x)))."""
    node = draw(inner)
    for kind in draw(st.lists(st.sampled_from(TRANSFORM_KINDS), max_size=6)):
        node = wrap(kind, node, draw)
    return node


def trees(material):
    """SDF trees mixing every primitive, CSG operator (plain and smooth), morph and transform."""
    def extend(inner):
        kids = st.lists(inner, min_size=1, max_size=3).map(tuple)
        return st.one_of(
            st.builds(Union, kids), st.builds(Intersection, kids), st.builds(Subtraction, kids),
            st.builds(SmoothUnion, kids, SIZES), st.builds(SmoothIntersection, kids, SIZES),
            st.builds(SmoothSubtraction, kids, SIZES),
            st.builds(Morph, st.tuples(inner, inner), UNIT),
            st.builds(Translate, inner, POINTS), st.builds(Rotate, inner, ANGLES),
            st.builds(Scale, inner, SIZES), st.builds(Repeat, inner, PERIODS, COUNTS),
            transform_chains(inner),
        )
    return st.recursive(primitive_nodes(material), extend, max_leaves=8)


# Image files by absolute path: a relative one is read relative to the file it is saved in.
IMAGE_FILES = st.text(max_size=8).filter(lambda t: "\x00" not in t).map(
    lambda t: f"/images/{t}.png")
SHADING = ["phong", "blinn_phong", "toon", "stripes", "normals", "depth", "steps"]
# A material's pattern: none, a checker or a texture (of a file or a built-in image).
TEXTURES = st.builds(Texture, IMAGE_FILES | st.just("uv_grid"),
                     st.sampled_from(["triplanar", "uv"]), SIZES,
                     numbers(Texture, "sharpness"), COLORS)
PATTERNS = st.one_of(st.just({}), st.builds(lambda c: {"checker": c},
                                            st.builds(Checker, COLORS, COLORS, SIZES)),
                     st.builds(lambda t: {"texture": t}, TEXTURES))
MATERIALS = st.builds(lambda pattern, **fields: Material(**pattern, **fields), PATTERNS,
                      color=COLORS, ka=UNIT, kd=UNIT, ks=UNIT,
                      shininess=numbers(Material, "shininess"), kr=UNIT,
                      transparency=UNIT, ior=numbers(Material, "ior"),
                      shading=st.none() | st.sampled_from(SHADING),
                      absorption=vectors(Material, "absorption"))
ATTENUATION = dict(constant=numbers(PointLight, "constant"),
                   linear=numbers(PointLight, "linear"),
                   quadratic=numbers(PointLight, "quadratic"))
INTENSITIES = numbers(PointLight, "intensity")
# A light's own ambient, diffuse and specular colours, each present or not.
OWN_COLORS = dict(ambient=st.none() | COLORS, diffuse=st.none() | COLORS,
                  specular=st.none() | COLORS)
LIGHTS = st.one_of(
    st.builds(PointLight, position=POINTS, color=COLORS, intensity=INTENSITIES, **ATTENUATION,
              **OWN_COLORS),
    st.builds(DirectionalLight, DIRECTIONS, COLORS, INTENSITIES, **OWN_COLORS),
    valid(SpotLight, position=POINTS, direction=DIRECTIONS, color=COLORS,
          intensity=INTENSITIES, inner_angle=numbers(SpotLight, "inner_angle"),
          outer_angle=numbers(SpotLight, "outer_angle"), **ATTENUATION, **OWN_COLORS),
)
ENVIRONMENTS = dict(intensity=numbers(StudioBackground, "intensity"),
                    rotation=numbers(StudioBackground, "rotation"))
BACKGROUNDS = (st.builds(SolidBackground, COLORS) | st.builds(SkyBackground, COLORS, COLORS)
               | st.builds(StudioBackground, integers(StudioBackground, "size"), **ENVIRONMENTS)
               | st.builds(CubeMapBackground, st.tuples(*[IMAGE_FILES] * 6), **ENVIRONMENTS)
               | st.builds(EquirectBackground, IMAGE_FILES, **ENVIRONMENTS))
CAMERAS = valid(Camera, position=POINTS, look_at=POINTS, up=DIRECTIONS,
                fov=numbers(Camera, "fov"))
RENDER_SETTINGS = valid(
    RenderSettings,
    max_steps=integers(RenderSettings, "max_steps"), epsilon=numbers(RenderSettings, "epsilon"),
    max_distance=numbers(RenderSettings, "max_distance"),
    normal_method=st.sampled_from(["central", "tetrahedron"]),
    normal_step=numbers(RenderSettings, "normal_step"),
    shadows=st.sampled_from(["none", "hard", "soft"]),
    penumbra_k=numbers(RenderSettings, "penumbra_k"),
    surface_offset=numbers(RenderSettings, "surface_offset"),
    reflection_depth=integers(RenderSettings, "reflection_depth"),
    fresnel=st.sampled_from(["exact", "schlick"]),
    shading=st.sampled_from(SHADING),
    toon_bands=integers(RenderSettings, "toon_bands"), ambient=COLORS,
    gamma=numbers(RenderSettings, "gamma"),
    fog=st.builds(Fog, COLORS, numbers(Fog, "density")), background=BACKGROUNDS)


TREES = trees(st.sampled_from(MATERIAL_NAMES))

PHYSICS = st.none() | st.builds(
    PhysicsSettings, gravity=vectors(PhysicsSettings, "gravity"),
    dt=numbers(PhysicsSettings, "dt"),
    integrator=st.sampled_from(["semi_implicit", "explicit", "verlet"]),
    solver=st.sampled_from(["sequential", "simultaneous"]),
    seed=integers(PhysicsSettings, "seed"), restitution=UNIT,
    friction=numbers(PhysicsSettings, "friction"), density=numbers(PhysicsSettings, "density"),
    plane_restitution=UNIT, plane_friction=numbers(PhysicsSettings, "plane_friction"))


def bodies(material):
    """Bodies with mass, density or neither (never both), optional restitution and friction."""
    weight = st.one_of(st.just({}), st.builds(lambda m: {"mass": m}, numbers(Body, "mass")),
                       st.builds(lambda d: {"density": d}, numbers(Body, "density")))
    return st.builds(lambda weight, **kwargs: Body(**weight, **kwargs), weight,
                     position=vectors(Body, "position"), velocity=vectors(Body, "velocity"),
                     angular_velocity=vectors(Body, "angular_velocity"),
                     radius=numbers(Body, "radius"), restitution=st.none() | UNIT,
                     friction=st.none() | numbers(Body, "friction"), material=material)

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
    largest = math.nextafter(1e6, 0.0)        # the largest coordinate below the limit
    scene = Scene(camera=Camera(position=(-0.0, 5e-324, largest)),
                  objects=(Translate(Plane((0.0, 1.0, -0.0), -1e-300), offset),))
    loaded = round_trip(scene, tmp_path)
    assert loaded.objects[0].offset[0] == 0.30000000000000004
    assert loaded.objects[0].offset[1] == 1e-300
    assert math.copysign(1.0, loaded.objects[0].offset[2]) == -1.0
    assert math.copysign(1.0, loaded.objects[0].child.normal[2]) == -1.0
    assert math.copysign(1.0, loaded.camera.position[0]) == -1.0
    assert loaded.camera.position[1:] == (5e-324, largest)
    assert_identical(loaded, scene)
