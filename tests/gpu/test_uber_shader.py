"""The uber shader (`gpu_shader.uber`): one program text for every supported scene, drawing the
same Frame as the scene's specialised program.

The uber program computes every number with the expressions the specialised generator
writes, in the same order; only *which* expressions run is decided at run time. So the two
frames agree to the last bit on llvmpipe (measured: no pixel differs in any buffer); the
tolerances below (depth 1e-5 relative, colour 1e-4) leave room for a driver that schedules
the two programs' arithmetic differently, while the discrete buffers (hit, steps, object id,
path label) must be identical. Tests that draw take the ``gpu`` fixture and skip, with the
reason, where no OpenGL context can be made; the tests of the program text need no GPU.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gpu_shader.context import gl_context, is_software
from gpu_shader.render import render_program
from gpu_shader.uber import (OBJECTS_START, OBJECT_STRIDE, ROWS, SHAPES, SHAPE_ROW,
                             compare_specialised_uber, uber_program)
from marchlab import MarchlabError, load_scene
import marchlab
from scene_model.builder import (DirectionalLight, Fog, Scene, SolidBackground, SpotLight, box,
                                 disk, hex_prism, pyramid, sphere)
from scene_model.shapes import Primitive, Rotate, Scale, Translate

BUNDLED = ("classroom", "lights", "primitives")
BUNDLED_SIZE = (96, 72)
VARIANT_SIZE = (64, 48)
DEPTH_RTOL = 1e-5
COLOR_ATOL = 1e-4
NORMAL_ATOL = 1e-5
# A driver that rounds the two programs' SDF sums differently (NVIDIA's contracts a * b + c
# into one FMA where no `precise` forbids it) moves an SDF value by an ulp of the coordinates,
# 4.8e-7 at 4 m, and a central-difference normal by that over its 2 h = 2e-3 (measured on an
# H100: 5e-5 to 7e-5); llvmpipe compiles both alike and gives the same bits.
NORMAL_ATOL_HARDWARE = 5e-4


def with_settings(scene: Scene, **settings) -> Scene:
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **settings))


def with_lights(scene: Scene, *lights) -> Scene:
    return dataclasses.replace(scene, lights=tuple(lights))


def scaled_scene() -> Scene:
    """Scale nodes above and below a rotation: the distance is scaled back innermost first."""
    classroom = load_scene("classroom")
    objects = classroom.objects + (
        box(0.4, material="blue").rotate(0, 25, 10).scale(1.5).at(-0.2, 0.6, 1.6),
        sphere(0.5, material="red").scale(0.8).rotate(30, 0, 0).scale(1.25).at(2.6, 0.5, -1.0))
    return dataclasses.replace(classroom, objects=objects)


def newer_primitives_scene() -> Scene:
    """The primitives scene's floor and lights with a pyramid, a disk and a hexagonal prism,
    which the bundled scenes do not hold."""
    scene = load_scene("primitives")
    objects = scene.objects[:1] + (
        pyramid(1.2, 1.3, material="a").rotate(0, 20, 0).at(-2.0, 0.0, 0.0),
        disk(0.7, 0.16, material="b").rotate(70, 30, 0).at(0.0, 0.65, 0.0),
        hex_prism(0.45, 0.6, material="c").rotate(0, 30, 0).at(2.0, 0.45, 0.0))
    return dataclasses.replace(scene, objects=objects)


# Each variant changes one thing of a bundled scene; its name says which feature it checks.
VARIANTS = {
    "blinn_phong": lambda: with_settings(load_scene("classroom"), shading="blinn_phong"),
    "toon": lambda: with_settings(load_scene("primitives"), shading="toon", toon_bands=3),
    "normals": lambda: with_settings(load_scene("primitives"), shading="normals"),
    "depth": lambda: with_settings(load_scene("lights"), shading="depth"),
    "steps": lambda: with_settings(load_scene("classroom"), shading="steps"),
    "soft_shadows": lambda: with_settings(load_scene("lights"), shadows="soft"),
    "no_shadows": lambda: with_settings(load_scene("classroom"), shadows="none"),
    "reflections_depth_2": lambda: with_settings(load_scene("classroom"), reflection_depth=2),
    "fog_off": lambda: with_settings(load_scene("classroom"), fog=Fog(density=0.0)),
    "spot_and_directional_lights": lambda: with_lights(
        load_scene("classroom"), SpotLight(position=(1.0, 4.0, 2.0), direction=(-0.2, -1.0, -0.3)),
        DirectionalLight(direction=(0.5, -1.0, -0.4), color=(0.9, 0.8, 0.7), intensity=0.6)),
    "tetrahedron_normals": lambda: with_settings(load_scene("primitives"),
                                                 normal_method="tetrahedron"),
    "solid_background": lambda: with_settings(load_scene("primitives"),
                                              background=SolidBackground(color=(0.1, 0.2, 0.3))),
    "bounding_spheres": lambda: with_settings(load_scene("primitives"), bounding_spheres=True),
    "scale_transforms": scaled_scene,
    "pyramid_disk_hex_prism": newer_primitives_scene,
    "no_objects": lambda: dataclasses.replace(load_scene("lights"), objects=()),
}


def assert_uber_matches_specialised(scene: Scene, width: int, height: int):
    """The uber frame equals the specialised gpu frame (`assert_same_frame`)."""
    specialised = marchlab.render(scene, width, height, backend="gpu", path_labels=True)
    uber = render_program(scene, uber_program(scene, width, height), width, height)
    assert_same_frame(uber, specialised)


def assert_same_frame(uber, specialised):
    """Discrete buffers exactly equal; depth, normal and colour within the tolerances."""
    for name in ("hit", "steps", "object_id", "path"):
        differ = int((getattr(uber, name) != getattr(specialised, name)).sum())
        assert differ == 0, f"{name} differs in {differ} pixels"
    hit = specialised.hit
    assert np.isinf(uber.depth[~hit]).all()
    depth_error = np.abs(uber.depth[hit] - specialised.depth[hit]) / specialised.depth[hit]
    assert depth_error.max(initial=0.0) <= DEPTH_RTOL, "depth"
    atol = NORMAL_ATOL if is_software(gl_context()) else NORMAL_ATOL_HARDWARE
    assert np.abs(uber.normal - specialised.normal).max() <= atol, "normal"
    assert np.abs(uber.color - specialised.color).max() <= COLOR_ATOL, "colour"


# --- the same Frame as the specialised program -----------------------------------------------

@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_scene_holds_only_transformed_primitives(name):
    """The precondition of the comparison: each object is transforms above one primitive."""
    for node in load_scene(name).objects:
        while isinstance(node, (Translate, Rotate, Scale)):
            node = node.child
        assert isinstance(node, Primitive) and type(node) in SHAPES, node


@pytest.mark.parametrize("name", BUNDLED)
def test_uber_frame_equals_specialised_frame_on_bundled_scene(gpu, name):
    assert_uber_matches_specialised(load_scene(name), *BUNDLED_SIZE)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_uber_frame_equals_specialised_frame_on_feature_variant(gpu, variant):
    scene = VARIANTS[variant]()
    frame = marchlab.render(scene, *VARIANT_SIZE, backend="gpu")
    if variant != "no_objects":                     # a variant that hits nothing checks little
        assert 0 < frame.hit.sum() < frame.hit.size
    assert_uber_matches_specialised(scene, *VARIANT_SIZE)


def test_comparison_catches_a_sphere_one_percent_larger(gpu):
    """The comparison can fail: the uber program given a sphere 1% larger differs."""
    scene = load_scene("classroom")
    width, height = VARIANT_SIZE
    program = uber_program(scene, width, height)
    grown = program.parameters.copy()
    radius_row = OBJECTS_START + OBJECT_STRIDE * 1 + SHAPE_ROW          # object 1: red sphere
    assert grown[radius_row, 0] == 0.8
    grown[radius_row, 0] *= 1.01
    uber = render_program(scene, dataclasses.replace(program, parameters=grown), width, height)
    specialised = marchlab.render(scene, width, height, backend="gpu", path_labels=True)
    with pytest.raises(AssertionError):
        assert_same_frame(uber, specialised)


# --- one text for every scene ------------------------------------------------------------------

def test_uber_source_is_identical_for_different_scenes_and_sizes():
    classroom = uber_program(load_scene("classroom"), 320, 240)
    primitives = uber_program(with_settings(load_scene("primitives"), shading="toon",
                                            shadows="soft", normal_method="tetrahedron"), 64, 48)
    assert classroom.source == primitives.source
    assert classroom.parameters.shape == primitives.parameters.shape == (ROWS, 4)
    assert not np.array_equal(classroom.parameters, primitives.parameters)


def test_uber_source_holds_every_primitive_light_and_shading_function():
    source = uber_program(load_scene("classroom"), 32, 24).source
    every = ([f"sdf_{name[6:].lower()}(" for name in SHAPES.values()]
             + ["light_directional(", "light_point(", "light_spot(", "hard_shadow(",
                "soft_shadow(", "specular_phong(", "specular_blinn_phong(", "toon_band(",
                "shade_normals(", "shade_depth(", "apply_fog(", "checker(",
                "background_solid(", "background_sky(", "ray_meets_sphere("])
    assert [name for name in every if name not in source] == []


def test_uber_parameter_block_fits_the_smallest_uniform_block_gl_allows():
    """OpenGL promises at least 16 KiB per uniform block; the uber block is fixed in size."""
    assert ROWS * 16 <= 16384


# --- what it cannot hold: one line naming it ---------------------------------------------------

@pytest.mark.parametrize("scene_name, node", [("csg", "subtraction"), ("repetition", "repeat"),
                                              ("morph", "morph")])
def test_unsupported_node_gives_a_one_line_error_naming_it(scene_name, node):
    with pytest.raises(MarchlabError) as caught:
        uber_program(load_scene(scene_name), 32, 24)
    message = str(caught.value)
    assert "\n" not in message and repr(node) in message


def test_relaxed_marching_gives_a_one_line_error():
    scene = with_settings(load_scene("classroom"), relaxation="fixed")
    with pytest.raises(MarchlabError, match="relaxation = 'fixed'") as caught:
        uber_program(scene, 32, 24)
    assert "\n" not in str(caught.value)


def test_the_cone_prepass_gives_a_one_line_error():
    scene = with_settings(load_scene("classroom"), prepass="cone")
    with pytest.raises(MarchlabError, match="prepass = 'cone'") as caught:
        uber_program(scene, 32, 24)
    assert "\n" not in str(caught.value)


def test_a_textured_material_gives_a_one_line_error():
    scene = load_scene("classroom", ['materials.red.texture.image="uv_grid"'])
    with pytest.raises(MarchlabError, match="has a texture") as caught:
        uber_program(scene, 32, 24)
    assert "\n" not in str(caught.value)


def test_too_many_objects_gives_a_one_line_error():
    scene = Scene(objects=tuple(sphere(0.1).at(i, 0, 0) for i in range(33)))
    with pytest.raises(MarchlabError, match="at most 32 objects") as caught:
        uber_program(scene, 32, 24)
    assert "\n" not in str(caught.value)


# --- the timing comparison -----------------------------------------------------------------

def test_compare_reports_medians_of_alternating_draws_and_their_ratio(gpu):
    result = compare_specialised_uber(load_scene("lights"), 24, 18, repeat=3)
    for name in ("specialised", "uber"):
        draws = result[f"{name}_draws_ms"]
        assert len(draws) == 3 and min(draws) > 0
        assert result[f"{name}_ms"] == pytest.approx(float(np.median(draws)))
        assert result[f"{name}_compile_ms"] >= result[f"{name}_link_ms"] > 0
    assert result["ratio"] == pytest.approx(result["uber_ms"] / result["specialised_ms"])
