"""A point or spot light inside a solid lights nothing; render says so in one line
(marchlab/light_check.py)."""

import dataclasses
import warnings

import pytest

from marchlab.light_check import lights_inside
from marchlab.render import render
from scene_model.bodies import Body
from scene_model.scenefile import bundled_scene_names, load_scene
from tests.cli_helpers import run_cli


def classroom_with_light_at(position, index=1):
    scene = load_scene("classroom")
    lights = list(scene.lights)
    lights[index] = dataclasses.replace(lights[index], position=position)
    return dataclasses.replace(scene, lights=tuple(lights))


def test_a_light_at_a_spheres_centre_is_inside_it_by_its_radius():
    """classroom's objects[2] is the mirror sphere of radius 1 at (0, 1, -0.6): a light at
    its centre is 1 m below its surface (the exact SDF, 1e-12)."""
    (line,) = lights_inside(classroom_with_light_at((0.0, 1.0, -0.6)))
    assert line.startswith("lights[1] (point at (0, 1, -0.6)) is inside objects[2], 1 m below")


def test_a_light_just_outside_a_surface_and_directional_lights_are_not_reported():
    assert lights_inside(classroom_with_light_at((0.0, 2.0 + 1e-9, -0.6))) == []
    scene = load_scene("lights")
    assert all("directional" not in line for line in lights_inside(scene))


def test_a_light_inside_a_body_names_the_body():
    scene = dataclasses.replace(classroom_with_light_at((3.0, 3.0, 3.0)),
                                bodies=(Body(position=(3.0, 3.0, 3.1), radius=0.5,
                                             material="red"),))
    (line,) = lights_inside(scene)
    assert "inside bodies[0]" in line


@pytest.mark.parametrize("name", bundled_scene_names())
def test_no_bundled_scene_hides_a_light_inside_a_solid(name):
    assert lights_inside(load_scene(name)) == []


def test_render_warns_once_per_hidden_light_and_still_renders():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        frame = render(classroom_with_light_at((0.0, 1.0, -0.6)), 16, 12)
    assert frame.image("color").shape == (12, 16, 3)
    assert [str(w.message) for w in caught if "lights nothing" in str(w.message)] == [
        "lights[1] (point at (0, 1, -0.6)) is inside objects[2], 1 m below its surface: it "
        "lights nothing"]


def test_the_command_prints_the_warning_in_one_line_and_writes_the_image(tmp_path, capsys):
    out = tmp_path / "hidden.png"
    code, _, err = run_cli(capsys, "render", "classroom", "--set", "lights[1].position=[0,1,-0.6]",
                           "-o", out, "--size", "16x12", "--backend", "numpy")
    assert code == 0 and out.exists()
    assert err.strip().splitlines() == [
        "marchlab: warning: lights[1] (point at (0, 1, -0.6)) is inside objects[2], 1 m below "
        "its surface: it lights nothing"]
