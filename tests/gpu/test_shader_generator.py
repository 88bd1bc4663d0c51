"""The shader generator (`gpu_shader.generate`): a program holds only what its scene uses.

These tests read the generated text and `Program.features`; they need no OpenGL and never
skip. A function counts as *present* when the text defines or calls it (``name(``), so a
comment that mentions a word ("the checker cell") does not count.
"""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys
from typing import ClassVar

import numpy as np
import pytest

from gpu_shader.generate import generate
from marchlab import MarchlabError, load_scene, save_scene
from scene_model.builder import Scene, box, sphere
from scene_model.shapes import Box, Primitive, Repeat, Sphere, node_kinds, primitives

WIDTH, HEIGHT = 32, 24

# Top-level definitions in the generated text: "type name(" at the start of a line.
DEFINITION = re.compile(r"^\w+\s+(\w+)\s*\(", re.M)

# What a sphere-only scene (default settings: phong, one directional light, no shadows,
# no fog, no checker, no mirror) must not contain.
UNUSED_BY_A_SPHERE = ("sdf_box", "op_smooth_union", "op_union", "soft_shadow", "hard_shadow",
                      "light_visible", "apply_fog", "checker", "light_spot", "toon_band")
REFLECTION_LOOP = "for (int bounce"


def defined_functions(source: str) -> set[str]:
    return set(DEFINITION.findall(source))


def uses(source: str, function: str) -> bool:
    """Whether ``source`` defines or calls ``function``."""
    return re.search(rf"\b{function}\s*\(", source) is not None


@pytest.fixture
def sphere_file(tmp_path):
    """A scene file holding one sphere and every default setting."""
    path = tmp_path / "sphere.toml"
    save_scene(Scene(objects=(sphere(1.0),)), path)
    return path


# --- only what the scene uses --------------------------------------------------------------

def test_sphere_only_program_holds_no_unused_building_block(sphere_file):
    program = generate(load_scene(sphere_file), WIDTH, HEIGHT)
    assert "sdf_sphere" in defined_functions(program.source)
    assert "sdf_sphere" in program.features
    present = [name for name in UNUSED_BY_A_SPHERE if uses(program.source, name)]
    assert present == []
    assert REFLECTION_LOOP not in program.source
    assert not {"fog", "checker", "reflections"} & set(program.features)
    assert not [f for f in program.features if f.startswith("shadows:")]


# (--set overrides, functions added, functions removed, features added, features removed,
#  text that must appear)
FEATURE_SWITCHES = {
    "soft shadows": (["render.shadows=soft"], {"soft_shadow", "light_visible", "needs_shadow_ray"},
                     set(), {"shadows:soft"}, set(), None),
    # Hard shadow rays leave out the convex object they start on: its bit (own_object) and a
    # march_sdf that can leave an object out (op_union over the objects kept).
    "hard shadows": (["render.shadows=hard"], {"hard_shadow", "light_visible", "needs_shadow_ray",
                                               "own_object", "op_union"},
                     set(), {"shadows:hard", "shadows:skip_own", "op_union"}, set(), None),
    "hard shadows keeping their own object": (
        ["render.shadows=hard", "render.shadow_skip_own=false"],
        {"hard_shadow", "light_visible", "needs_shadow_ray"}, set(), {"shadows:hard"}, set(),
        None),
    "fog": (["render.fog.density=0.1"], {"apply_fog"}, set(), {"fog"}, set(), None),
    "checker": (["materials.default.checker.scale=0.5"],
                {"checker", "checker_parity"}, set(),
                {"checker"}, set(), None),
    # A texture brings the bilinear filter and its mapping's functions.
    "triplanar texture": (["materials.default.texture.mapping=\"triplanar\""],
                          {"texture_bilinear", "texture_repeat", "cube_face_coordinates",
                           "triplanar_weights", "texture_triplanar"}, set(),
                          {"texture_bilinear", "texture:triplanar"}, set(), None),
    "uv texture": (["materials.default.texture.mapping=\"uv\""],
                   {"texture_bilinear", "equirect_uv", "sphere_uv", "texture_sphere"}, set(),
                   {"texture_bilinear", "texture:sphere"}, set(), None),
    # A spot light is a point light limited to a cone, so it brings light_point along.
    "spot light": (["lights[0].type=spot"],
                   {"light_spot", "light_point", "attenuation", "spot_cone"},
                   {"light_directional"}, {"light:spot"}, {"light:directional"}, None),
    "toon": (["render.shading=toon"], {"toon_band", "shade_toon"}, {"shade_phong"},
             {"shading:toon"}, {"shading:phong"}, None),
    # With a mirror, trace is generated around the reflection loop: no pixel_color.
    "mirror": (["render.reflection_depth=1", "materials.default.kr=0.5"], set(), {"pixel_color"},
               {"reflections"}, set(), REFLECTION_LOOP),
}


@pytest.mark.parametrize("switch", list(FEATURE_SWITCHES))
def test_turning_a_feature_on_adds_exactly_its_functions(sphere_file, switch):
    overrides, added, removed, features_added, features_removed, text = FEATURE_SWITCHES[switch]
    plain = generate(load_scene(sphere_file), WIDTH, HEIGHT)
    with_it = generate(load_scene(sphere_file, overrides), WIDTH, HEIGHT)
    before, after = defined_functions(plain.source), defined_functions(with_it.source)
    assert (after - before, before - after) == (added, removed)
    assert (set(with_it.features) - set(plain.features),
            set(plain.features) - set(with_it.features)) == (features_added, features_removed)
    if text is not None:
        assert text not in plain.source and text in with_it.source


@pytest.mark.parametrize("overrides", [
    ["render.reflection_depth=1"],                         # bounces, but no mirror material
    ["render.shading=normals", "render.shadows=hard"],     # shadows only darken lit modes
    ["render.shading=depth", "render.fog.density=0.2"],    # fog only tints lit modes
], ids=["bounces-without-mirror", "shadows-in-normals-mode", "fog-in-depth-mode"])
def test_settings_without_visible_effect_add_no_code(sphere_file, overrides):
    """A setting that cannot change the image leaves the program as it was without it."""
    without = [o for o in overrides if not o.startswith(("render.reflection_depth",
                                                         "render.shadows", "render.fog"))]
    reference = generate(load_scene(sphere_file, without), WIDTH, HEIGHT)
    program = generate(load_scene(sphere_file, overrides), WIDTH, HEIGHT)
    assert program.source == reference.source
    assert program.features == reference.features


@pytest.mark.parametrize("second, added", [
    (box(0.5).at(2.0, 0.0, 0.0), {"sdf_box", "op_union", "op_translate"}),
    (None, {"op_smooth_union", "op_translate"}),
], ids=["box-beside", "smooth-union"])
def test_adding_shapes_adds_exactly_their_sdf_functions(second, added):
    plain = generate(Scene(objects=(sphere(1.0),)), WIDTH, HEIGHT)
    if second is None:
        objects = (sphere(1.0).smooth_union(sphere(0.5).at(1.0, 0.0, 0.0), k=0.2),)
    else:
        objects = (sphere(1.0), second)
    program = generate(Scene(objects=objects), WIDTH, HEIGHT)
    before, after = defined_functions(plain.source), defined_functions(program.source)
    assert (after - before, before - after) == (added, set())
    assert set(program.features) - set(plain.features) == added


def example_node(cls):
    """A small instance of the node class ``cls`` (children: a sphere and a moved box)."""
    names = {f.name for f in dataclasses.fields(cls)}
    if "children" in names:
        return cls(children=(Sphere(0.8), Box((0.6, 0.6, 0.6)).at(0.5, 0.3, 0.2)))
    if "child" in names:
        return cls(child=Box((0.4, 0.5, 0.3)))
    return cls()


def expected_function(kind: str, cls) -> str:
    """The GLSL name of a node kind: ``sdf_<kind>`` for shapes, ``op_<kind>`` otherwise."""
    return f"sdf_{kind}" if issubclass(cls, Primitive) else f"op_{kind}"


@pytest.mark.parametrize("kind", sorted(node_kinds()))
def test_every_node_kind_generates_its_function(kind):
    cls = node_kinds()[kind]
    program = generate(Scene(objects=(example_node(cls),)), WIDTH, HEIGHT)
    function = expected_function(kind, cls)
    assert function in defined_functions(program.source)
    assert function in program.features


def test_limited_repetition_generates_op_repeat_limited():
    node = Repeat(Sphere(0.3), (1.0, 0.0, 1.0), (2, 0, 2))
    program = generate(Scene(objects=(node,)), WIDTH, HEIGHT)
    functions = defined_functions(program.source)
    assert "op_repeat_limited" in functions and "op_repeat" not in functions


# --- the text depends on structure only ---------------------------------------------------

@pytest.mark.parametrize("overrides", [
    ["objects[1].position=[-1.5, 0.9, 0.2]"],
    ["objects[2].radius=0.7"],
    ["materials.red.color=[0.1, 0.9, 0.1]"],
    ["lights[0].position=[1.0, 7.0, -2.0]"],
    ["camera.position=[1.0, 3.0, 8.0]", "camera.fov=40"],
    ["render.max_steps=64", "render.epsilon=0.002", "render.reflection_depth=2"],
    ["render.fog.density=0.05"],
], ids=["move-object", "resize-object", "material-colour", "light-position", "camera",
        "march-settings", "fog-density"])
def test_changing_a_number_changes_parameters_not_source(overrides):
    plain = generate(load_scene("classroom"), WIDTH, HEIGHT)
    changed = generate(load_scene("classroom", overrides), WIDTH, HEIGHT)
    assert changed.source == plain.source
    assert changed.parameters.shape == plain.parameters.shape
    assert (changed.parameters != plain.parameters).any()


def test_a_morphs_t_across_one_half_changes_parameters_not_source():
    """The morph's t, and with it which child's id it shows, is a parameter: an animation
    that sweeps t compiles once."""
    plain = generate(load_scene("morph"), WIDTH, HEIGHT)
    changed = generate(load_scene("morph", ["objects[2].t=0.75"]), WIDTH, HEIGHT)
    assert changed.source == plain.source
    assert (changed.parameters != plain.parameters).any()


def test_image_size_changes_parameters_not_source():
    small = generate(load_scene("classroom"), 32, 24)
    large = generate(load_scene("classroom"), 64, 48)
    assert small.source == large.source
    assert (small.parameters != large.parameters).any()


def test_reassigning_a_material_changes_parameters_not_source():
    plain = generate(load_scene("classroom"), WIDTH, HEIGHT)
    changed = generate(load_scene("classroom", ['objects[1].material="blue"']), WIDTH, HEIGHT)
    assert (changed.parameters != plain.parameters).any()
    assert changed.source == plain.source


def test_adding_an_object_changes_source():
    scene = load_scene("classroom")
    more = dataclasses.replace(
        scene, objects=scene.objects + (sphere(0.3, material="red").at(0, 2, 0),))
    assert generate(more, WIDTH, HEIGHT).source != generate(scene, WIDTH, HEIGHT).source


@pytest.mark.parametrize("shadows, feature", [("none", None), ("soft", "shadows:soft")])
def test_switching_shadows_changes_source(shadows, feature):
    hard = generate(load_scene("classroom"), WIDTH, HEIGHT)        # classroom: hard shadows
    other = generate(load_scene("classroom", [f"render.shadows={shadows}"]), WIDTH, HEIGHT)
    assert other.source != hard.source
    assert [f for f in other.features if f.startswith("shadows:")] == ([feature] if feature else [])


# --- the parameter block -----------------------------------------------------------------

def scenes_to_check():
    """Every bundled scene and a few that exercise other branches of the generator."""
    scenes = {name: load_scene(name) for name in ("classroom", "csg", "lights", "primitives",
                                                  "repetition")}
    scenes["soft-toon-spot"] = load_scene("lights", ["render.shading=toon", "render.shadows=soft"])
    scenes["steps-mode"] = load_scene("classroom", ["render.shading=steps"])
    scenes["empty"] = Scene(objects=())
    scenes["no-lights"] = dataclasses.replace(Scene(objects=(sphere(1.0),)), lights=())
    return scenes


SCENES = scenes_to_check()


@pytest.mark.parametrize("name", list(SCENES))
def test_every_parameter_index_is_inside_the_declared_block(name):
    program = generate(SCENES[name], WIDTH, HEIGHT)
    source = program.source
    rows = int(re.search(r"^\s*vec4 U\[(\d+)\];", source, re.M).group(1))
    fixed = int(re.search(r"^(?:flat in )?vec4 P\[(\d+)\];", source, re.M).group(1))
    assert program.parameters.shape == (rows, 4)
    # drop declarations
    body = re.sub(r"^\s*(?:flat in )?vec4 [PU]\[\d+\];$", "", source, flags=re.M)
    p_indices = [int(i) for i in re.findall(r"\bP\[(\d+)\]", body)]
    u_indices = [int(i) for i in re.findall(r"\bU\[(\d+)\]", body)]
    assert p_indices, "the camera rows, at least, are read through P"
    assert max(p_indices) < fixed <= rows
    assert all(i < rows for i in u_indices)
    # Materials: U[first + stride * id + row] for every object id and row must be in the block.
    material = re.search(r"#define MATERIAL\(id, row\) U\[(\d+) \+ (\d+) \* \(id\) \+ \(row\)\]",
                         source)
    if material and SCENES[name].objects:
        first, stride = int(material.group(1)), int(material.group(2))
        count = len(list(primitives(SCENES[name].objects)))
        assert fixed <= first and first + stride * count - 1 < rows


@pytest.mark.parametrize("name", list(SCENES))
def test_define_names_are_unique(name):
    names = re.findall(r"^#define\s+(\w+)", generate(SCENES[name], WIDTH, HEIGHT).source, re.M)
    duplicates = sorted({n for n in names if names.count(n) > 1})
    assert names and duplicates == []


# --- what the generator refuses -----------------------------------------------------------

@pytest.fixture
def make_custom_node():
    """Makes a node of a kind the generator has never heard of; the kind is gone afterwards.

    `node_kinds` finds node classes through ``__subclasses__``, so a class left alive would
    show up in every later test that lists the kinds (docs, scene files). The class is made
    inside the test (a fixture's value lives until after its teardown), and the scene fields'
    type-hint cache, which holds it too, is cleared so that collection lets it die.
    """
    import gc

    from scene_model.fields import field_types, param

    def make(**values):
        @dataclasses.dataclass(frozen=True)
        class Blob(Primitive):
            kind: ClassVar[str] = "blob"
            radius: float = param(1.0, "Radius.")
        return Blob(**values)

    yield make
    field_types.cache_clear()
    gc.collect()
    assert "blob" not in node_kinds()


@pytest.mark.parametrize("where", ["alone", "inside-union-and-translate"])
def test_unknown_node_kind_is_a_one_line_error_naming_it(make_custom_node, where):
    blob = make_custom_node()
    node = blob if where == "alone" else sphere(1.0) | blob.at(1.0, 0.0, 0.0)
    with pytest.raises(MarchlabError) as caught:
        generate(Scene(objects=(node,)), WIDTH, HEIGHT)
    message = str(caught.value)
    del caught                           # the traceback would keep the class alive
    assert "'blob'" in message and "\n" not in message
    assert "--backend numpy" in message


def test_unknown_dialect_is_an_error_listing_the_known_ones():
    with pytest.raises(MarchlabError, match=r"unknown shader dialect 'hlsl' "
                       r"\(one of: glsl, glsl-compute, opencl, opencl-packets\)"):
        generate(Scene(objects=(sphere(1.0),)), WIDTH, HEIGHT, dialect="hlsl")


def test_generated_text_is_the_same_under_any_hash_seed():
    """The program cache is keyed by the text, so the text must not depend on set order.

    Python orders sets of strings by a per-process hash seed; two processes with different
    seeds must generate the same program, character for character.
    """
    script = ("import hashlib; from marchlab import load_scene; "
              "from gpu_shader.generate import generate; "
              "print(hashlib.sha256(generate(load_scene('csg'), 32, 24).source.encode())"
              ".hexdigest())")
    digests = set()
    for seed in ("1", "2", "3"):
        env = {**os.environ, "PYTHONHASHSEED": seed}
        done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                              text=True, timeout=60, check=True)
        digests.add(done.stdout.strip())
    assert len(digests) == 1


# (scene, overrides) -> (shadow functions defined, shadow functions not defined)
SHADOW_PAIRING = {
    "two lights: one pair": ("classroom", [], {"hard_shadow_pair", "lights_visible"},
                             {"light_visible", "hard_shadow"}),
    "three lights: a pair and one alone": ("lights", [],
                                           {"hard_shadow_pair", "lights_visible",
                                            "light_visible", "hard_shadow"}, set()),
    "soft shadows: no pairs": ("classroom", ["render.shadows=soft"],
                               {"light_visible", "soft_shadow"},
                               {"hard_shadow_pair", "lights_visible", "hard_shadow"}),
    "relaxed marching: no pairs": ("classroom", ["render.relaxation=auto"],
                                   {"light_visible", "hard_shadow"},
                                   {"hard_shadow_pair", "lights_visible"}),
}


@pytest.mark.parametrize("case", list(SHADOW_PAIRING))
def test_hard_shadow_rays_are_paired_where_the_march_allows_and_nothing_unused_is_emitted(case):
    """Pairs only with hard shadows and plain marching, in the one-ray programs; a function
    only where it is called (a scene whose lights are all paired has no light_visible)."""
    name, overrides, present, absent = SHADOW_PAIRING[case]
    for dialect in ("glsl", "opencl"):
        source = generate(load_scene(name, overrides), WIDTH, HEIGHT, dialect=dialect).source
        defined = defined_functions(source)
        assert present <= defined and not absent & defined, (dialect, defined & (present | absent))
        for function in defined & (present | absent | {"needs_shadow_ray"}):
            assert len(re.findall(rf"\b{function}\s*\(", source)) >= 2, function   # called
    packets = generate(load_scene(name, overrides), WIDTH, HEIGHT, dialect="opencl-packets")
    assert not {"hard_shadow_pair", "lights_visible"} & defined_functions(packets.source)


# --- path labels, only for the equivalence suite --------------------------------------------

PATH_LABEL_CODE = {"path_step", "path", "features", "surface_checker_parity",
                   "surface_texture_face"}


def code_words(source: str) -> set[str]:
    """The identifiers of ``source`` outside // comments."""
    return set(re.findall(r"\b\w+\b", re.sub(r"//[^\n]*", "", source)))


@pytest.mark.parametrize("dialect", ["glsl", "opencl"])
@pytest.mark.parametrize("name", ["classroom", "csg", "lights", "primitives", "repetition"])
def test_a_program_has_no_path_label_code_unless_asked_for_it(name, dialect):
    """A student's shader holds none of the path-label bookkeeping; asking for it adds the
    label's hash, the features of each shading and the Pixel's path field."""
    scene = load_scene(name)
    plain = generate(scene, WIDTH, HEIGHT, dialect=dialect)
    labelled = generate(scene, WIDTH, HEIGHT, dialect=dialect, path_labels=True)
    assert not PATH_LABEL_CODE & code_words(plain.source)
    assert {"path_step", "path", "features"} <= code_words(labelled.source)
    assert (plain.path_labels, labelled.path_labels) == (False, True)


@pytest.mark.parametrize("shading", ["steps", "normals", "depth", "phong"])
def test_path_labels_change_no_parameter_row(shading):
    """The labels are computed from what the program already has: the parameter block is
    the same with and without them, so frames differ only in their path buffer."""
    scene = load_scene("classroom", [f"render.shading={shading}"])
    plain = generate(scene, WIDTH, HEIGHT)
    labelled = generate(scene, WIDTH, HEIGHT, path_labels=True)
    assert np.array_equal(plain.parameters, labelled.parameters)


@pytest.mark.parametrize("dialect", ["glsl", "opencl", "opencl-packets"])
def test_a_lit_scene_without_lights_has_no_diffuse_or_specular_term(dialect):
    """Without lights a surface shows its ambient term only: the shading sum has no block,
    and no light, shadow, diffuse or specular function is emitted."""
    scene = load_scene("classroom", ["render.shading=toon"])
    scene = dataclasses.replace(scene, lights=())
    source = generate(scene, WIDTH, HEIGHT, dialect=dialect).source
    for function in ("diffuse", "specular_phong", "toon_band", "light_point", "light_visible",
                     "hard_shadow", "hard_shadow_pair"):
        assert not uses(source, function), function
    assert uses(source, "shade_toon")
