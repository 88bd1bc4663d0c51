"""Convex bodies in scenes: ``shape = "convex"`` with a ``solid`` in ``[[bodies]]``, its
validation, the world built from it, the renderers drawing it where the physics has it, the
gpu step refusing it, and a saved and resumed run (scene_model/bodies.py,
marchlab/colliders.py body_solid, marchlab/simulation.py build_world and drawn_poses).

A convex body's ``position`` and ``rotation`` place its solid's own origin and axes (the
node's frame); the world moves its centre of mass along its principal axes, found by
integrating the SDF on a grid (physics/convex.py; right to about 1e-4 of the size). The
drawing checks are exact: the posed scene's SDF at the physics' surface samples.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import physics
from marchlab.colliders import body_solid
from marchlab.simulation import body_rotations, build_world, drawn_poses, simulate
from physics.quaternions import rotation_matrices
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import Body, Material, PhysicsSettings, Scene, plane
from scene_model.errors import SceneError
from scene_model.geometry import rotation_matrix
from scene_model.scene import scene_at, scene_objects
from scene_model.scenefile import load_scene, save_scene
from scene_model.shapes import Box, Cone, HexPrism, Intersection, Rotate, Sphere, Translate

from cli_helpers import assert_one_line_error, run_cli

CONVEX = """\
[physics]
restitution = 0.0

[materials.default]

[materials.blue]
color = [0.15, 0.35, 0.85]

[[objects]]
type = "plane"

[[bodies]]
shape = "sphere"
position = [1.0, 0.5, 0.0]
radius = 0.1

[[bodies]]
{body}
"""
CONE = """shape = "convex"
position = [0.5, 0.25, -0.25]
rotation = [0.0, 0.0, 90.0]
solid = { type = "cone", radius = 0.3, height = 0.6, material = "blue" }"""


def scene_file(tmp_path, body=CONE, name="convex.toml"):
    path = tmp_path / name
    path.write_text(CONVEX.format(body=body))
    return path


# --- The scene file ------------------------------------------------------------------------------

def test_a_convex_body_and_its_nested_solid_round_trip_through_a_saved_file(tmp_path):
    """save_scene then load_scene gives back the same scene (== and repr, so every float bit
    for bit), the body's solid included: an intersection of a turned box and a moved sphere,
    each with its material."""
    solid = Intersection((Rotate(Box((0.3, 0.2, 0.25), material="blue"), (10.0, 20.0, 30.0)),
                          Translate(Sphere(0.35), (0.05, 0.0, 0.0))))
    original = load_scene(scene_file(tmp_path))
    original = dataclasses.replace(original, bodies=original.bodies + (
        Body(shape="convex", position=(-1.0, 0.5, 0.0), rotation=(5.0, -15.0, 25.0),
             solid=solid, angular_velocity=(1.0, 2.0, 3.0), density=700.0),))
    path = tmp_path / "saved.toml"
    save_scene(original, path)
    loaded = load_scene(path)
    assert loaded == original and repr(loaded) == repr(original)
    assert loaded.bodies[1].solid == Cone(radius=0.3, height=0.6, material="blue")
    assert loaded.bodies[2].solid == solid


BAD_BODIES = {
    "union": ('shape = "convex"\nsolid = { type = "union", children = [{ type = "sphere" }, '
              '{ type = "box" }] }', "a union is not convex"),
    "torus": ('shape = "convex"\nsolid = { type = "torus" }', "a torus is not convex"),
    "union_inside_an_intersection": (
        'shape = "convex"\nsolid = { type = "intersection", children = [{ type = "sphere" }, '
        '{ type = "union", children = [{ type = "box" }] }] }', "is not convex"),
    "plane": ('shape = "convex"\nsolid = { type = "plane" }', "a plane is not bounded"),
    "moved_plane": ('shape = "convex"\nsolid = { type = "translate", offset = [0.0, 1.0, 0.0], '
                    'child = { type = "plane" } }', "is not bounded"),
    "missing_solid": ('shape = "convex"', "a convex body needs a solid"),
    "solid_on_a_box": ('shape = "box"\nsolid = { type = "sphere", radius = 0.2 }',
                       "only a convex body has a solid"),
}


@pytest.mark.parametrize("case", BAD_BODIES)
def test_a_bad_convex_body_is_a_scene_error_naming_bodies_1_solid(tmp_path, case):
    body, problem = BAD_BODIES[case]
    path = scene_file(tmp_path, body)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: bodies[1].solid: "), message
    assert problem in message and "\n" not in message


@pytest.mark.parametrize("case", BAD_BODIES)
def test_simulating_a_bad_convex_body_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys,
                                                                            case):
    body, problem = BAD_BODIES[case]
    path = scene_file(tmp_path, body)
    before = sorted(tmp_path.iterdir())
    code, _, stderr = run_cli(capsys, "simulate", path, "--seconds", "0.1", "--size", "16x12",
                              "-o", tmp_path / "out.gif", "--csv", tmp_path / "out.csv")
    assert_one_line_error(code, stderr)
    assert f"{path}: bodies[1].solid: " in stderr and problem in stderr, stderr
    assert sorted(tmp_path.iterdir()) == before


# --- The world built from it ---------------------------------------------------------------------

def test_a_cones_centre_of_mass_is_placed_h_over_4_up_its_turned_axis_within_1e_4_m(tmp_path):
    """The cone (r 0.3, h 0.6) at position p turned 90 degrees about z: its centre of mass
    is at p + Rz(90) (0, h/4, 0) = p + (-0.15, 0, 0) within 1e-4 m (the grid's centroid is
    4e-5 m off), exactly (1e-12) at p + R centroid of its solid, and its principal axes are
    R axes; mass = density x volume, 1000 x pi r^2 h / 3, within 2e-3 (the grid's volume is
    4e-4 off)."""
    scene = load_scene(scene_file(tmp_path))
    world = build_world(scene)
    body = scene.bodies[1]
    solid = body_solid(body.solid)
    turn = rotation_matrix(body.rotation)
    assert world.kind.tolist() == [physics.solids.SPHERE, physics.solids.CONVEX]
    np.testing.assert_allclose(world.position[1], np.add(body.position, (-0.15, 0.0, 0.0)),
                               rtol=0, atol=1e-4)
    np.testing.assert_allclose(world.position[1], body.position + turn @ solid.centroid,
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(rotation_matrices(world.orientation[1:])[0], turn @ solid.axes,
                               rtol=0, atol=1e-12)
    assert world.mass[1] == pytest.approx(1000.0 * math.pi * 0.3 ** 2 * 0.6 / 3, rel=2e-3)
    np.testing.assert_allclose(world.principal_inertia[1], world.mass[1] * solid.gyration,
                               rtol=1e-12)


def test_body_solid_is_built_once_per_node():
    """The world and the drawing use the same solid (the same centroid and axes)."""
    node = Cone(radius=0.3, height=0.6, material="blue")
    assert body_solid(node) is body_solid(Cone(radius=0.3, height=0.6, material="blue"))


# --- Drawn where the physics has it --------------------------------------------------------------

@pytest.fixture(scope="module")
def tumbled():
    """A sphere, a box and an off-centre, turned convex solid (a moved, turned cone: its
    centre of mass and principal axes are not its node's origin and axes) thrown up spinning
    and stepped 0.5 s in free flight (the floor is never reached), with its world."""
    solid = Translate(Rotate(Cone(radius=0.3, height=0.5), (30.0, -50.0, 70.0)),
                      (0.1, -0.2, 0.05))
    scene = Scene(materials={"default": Material()}, objects=(plane(),),
                  physics=PhysicsSettings(restitution=0.0),
                  bodies=(Body(shape="sphere", position=(-1.0, 3.0, 0.0), radius=0.2),
                          Body(shape="box", position=(1.0, 3.0, 0.0), half_size=(0.3, 0.2, 0.1),
                               rotation=(10.0, 20.0, 30.0), angular_velocity=(3.0, -2.0, 1.0)),
                          Body(shape="convex", position=(0.0, 3.0, 0.0),
                               rotation=(25.0, -40.0, 60.0), velocity=(0.0, 2.0, 0.0),
                               angular_velocity=(2.0, -3.0, 4.0), solid=solid)))
    world = build_world(scene)
    world.step(120)
    return scene, world


def test_the_tumbled_convex_body_turned_far_from_its_start(tumbled):
    """Otherwise the pose checks below would also pass with the scene's initial rotation."""
    scene, world = tumbled
    start = rotation_matrix(scene.bodies[2].rotation) @ body_solid(scene.bodies[2].solid).axes
    now = rotation_matrices(world.orientation[2:])[0]
    cos = (np.trace(start.T @ now) - 1) / 2
    assert math.degrees(math.acos(np.clip(cos, -1, 1))) > 60
    assert world.position[:, 1].min() > 1.0                      # and never reached the floor


def test_the_drawn_solid_has_the_physics_surface_samples_on_its_surface_to_1e_9_m(tumbled):
    """The scene posed by `drawn_poses` (its own origin and axes where the world's centre of
    mass and principal axes put them) has its SDF 0 within 1e-9 m at every surface sample of
    the body placed by the world, x + R(q) s_i: the picture shows the body where the physics
    has it. Posed the old way (the world's centre and turn as the node's origin and turn),
    the same points are centimetres off."""
    scene, world = tumbled
    positions, rotations = drawn_poses(scene, world.position, world.orientation)
    sdf = build_scene_sdf(scene_objects(scene_at(scene, positions, rotations=rotations)))
    solid = body_solid(scene.bodies[2].solid)
    points = world.position[2] + solid.samples @ rotation_matrices(world.orientation[2:])[0].T
    assert np.abs(sdf(points)[0]).max() < 1e-9
    naive = scene_at(scene, world.position, rotations=body_rotations(world.orientation))
    assert np.abs(build_scene_sdf(scene_objects(naive))(points)[0]).max() > 1e-2


def test_drawn_poses_leave_spheres_and_boxes_at_their_centres_and_turns(tumbled):
    """Only a convex body's pose changes: the others' rows are the world's centres and
    `body_rotations` of their orientations, exactly."""
    scene, world = tumbled
    positions, rotations = drawn_poses(scene, world.position, world.orientation)
    np.testing.assert_array_equal(positions[:2], world.position[:2])
    np.testing.assert_array_equal(rotations[:2], body_rotations(world.orientation[:2]))
    assert positions.shape == rotations.shape == (3, 3)


# --- The gpu step --------------------------------------------------------------------------------

def test_the_gpu_step_refuses_a_convex_body_in_one_line_before_making_a_gl_context(
        tmp_path, monkeypatch):
    """In float32 with the simultaneous solver (what the gpu step needs) the convex body is
    refused by `gpu_shader.physics.check_world` in one line naming it, before any OpenGL
    context is asked for (so the test needs no GL)."""
    import gpu_shader.physics

    def no_context(*args, **kwargs):
        raise AssertionError("the refusal must come before the OpenGL context")

    monkeypatch.setattr(gpu_shader.physics, "gl_context", no_context)
    scene = load_scene(scene_file(tmp_path), ["physics.solver=simultaneous"])
    with pytest.raises(physics.PhysicsError) as caught:
        simulate(build_world(scene, np.float32), 0.1, backend="gpu", scene=scene)
    message = str(caught.value)
    assert "\n" not in message
    assert "body 1" in message and "convex" in message, message
    assert message.endswith("use the cpu backend"), message


# --- Saved and resumed ---------------------------------------------------------------------------

LANDING = """shape = "convex"
position = [0.0, 0.35, 0.0]
rotation = [20.0, 10.0, 0.0]
angular_velocity = [0.0, 0.0, 3.0]
restitution = 0.5
solid = { type = "hex_prism", apothem = 0.15, half_length = 0.25 }"""


def test_a_resumed_run_with_a_landing_convex_body_is_bit_identical(tmp_path):
    """A hex prism dropped tumbling lands (step 38) and bounces; the world saved at
    step 48 (`physics.save_state`) and loaded into a world built afresh from the scene
    carries on to step 96 exactly as the run that never stopped: positions, velocities,
    spins, orientations, events and time, tolerance 0."""
    scene = load_scene(scene_file(tmp_path, LANDING))
    assert isinstance(scene.bodies[1].solid, HexPrism)
    straight = build_world(scene)
    straight.step(96)
    first = build_world(scene)
    first.step(48)
    assert len(first.events) > 0                      # it has landed: warm-started contacts
    physics.save_state(first, tmp_path / "state.npz")
    resumed = build_world(scene)
    physics.load_state(resumed, tmp_path / "state.npz")
    resumed.step(48)
    for name in ("position", "velocity", "angular_velocity", "orientation", "active"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(straight, name),
                                      err_msg=name)
    np.testing.assert_array_equal(resumed.events, straight.events)
    assert (resumed.steps, resumed.time) == (straight.steps, straight.time)
