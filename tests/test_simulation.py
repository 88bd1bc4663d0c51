"""Scenes with bodies: the [physics] and [[bodies]] tables, the world built from them, and the
scene drawn at each time step (scene_model/bodies.py, marchlab/simulation.py).

The bundled `bounce` scene has six bodies (four dropped, two colliding) over one floor plane.
"""

from __future__ import annotations

import dataclasses
import math
import typing

import numpy as np
import pytest

from gpu_shader.generate import generate
from marchlab import MarchlabError, SceneError, load_scene, render, save_scene
from marchlab.simulation import build_world, frame_plan, simulate, simulate_scene, static_planes
import physics
from scene_model.bodies import (INTEGRATOR_NAMES, SOLVER_NAMES, Body, Integrator, PhysicsSettings,
                                Solver)
from scene_model.builder import Material, Scene, plane, sphere
from scene_model.scene import rendered_scene, scene_at, scene_objects
from scene_model.shapes import Translate, primitives


@pytest.fixture(scope="module")
def bounce() -> Scene:
    return load_scene("bounce")


def drop_scene(**physics_settings) -> Scene:
    """One ball of radius 0.5 dropped from 2 m onto a floor."""
    return Scene(materials={"default": Material()}, objects=(plane(),),
                 physics=PhysicsSettings(**physics_settings),
                 bodies=(Body(position=(0.0, 2.0, 0.0), radius=0.5, restitution=0.5),))


# --- The scene file ------------------------------------------------------------------------------

def test_scene_with_physics_and_bodies_round_trips_exactly_including_absent_values(tmp_path):
    scene = Scene(materials={"default": Material(), "red": Material(color=(1, 0, 0))},
                  physics=PhysicsSettings(gravity=(0.0, -1.62, -0.0), dt=1 / 30, seed=2**63 - 1,
                                          integrator="verlet", solver="simultaneous"),
                  bodies=(Body(mass=0.1 + 0.2, velocity=(1e-300, -0.0, 5e-324)),
                          Body(density=7800.0, restitution=1.0, friction=0.0,
                               material="red"),
                          Body()))
    path = tmp_path / "bodies.toml"
    save_scene(scene, path)
    loaded = load_scene(path)
    assert loaded == scene and repr(loaded) == repr(scene)     # repr sees -0.0 and every bit


def test_a_scene_without_bodies_is_saved_without_physics_or_bodies_keys(tmp_path):
    path = tmp_path / "static.toml"
    save_scene(load_scene("classroom"), path)
    assert "physics" not in path.read_text() and "bodies" not in path.read_text()


BAD_VALUES = [
    ("bodies[0].radius=-1", "bodies[0].radius", "must be positive"),
    ("bodies[2].restitution=1.5", "bodies[2].restitution", "between 0 and 1"),
    ("bodies[1].friction=-0.1", "bodies[1].friction", "must be >= 0"),
    ("bodies[4].mass=2", "bodies[4].density", "give mass or density, not both"),
    ("bodies[3].material=gold", "bodies[3].material", "unknown material 'gold'"),
    ("bodies[0].raduis=1", "bodies[0].raduis", "did you mean 'radius'?"),
    ("bodies[0].velocity=[1, 2]", "bodies[0].velocity", "3 components"),
    ("physics.dt=0", "physics.dt", "must be positive"),
    ("physics.integrator=rk4", "physics.integrator", "must be one of"),
    ("physics.solver=jacobi", "physics.solver", "must be one of"),
    ("physics.seed=-1", "physics.seed", ">= 0"),
    ("physics.seed=1.5", "physics.seed", "must be an integer"),
    ("physics.gravity=[0, nan, 0]", "physics.gravity[1]", "finite"),
    ("physics.plane_restitution=2", "physics.plane_restitution", "between 0 and 1"),
    ("physics.gravty=[0, 0, 0]", "physics.gravty", "did you mean 'gravity'?"),
]


@pytest.mark.parametrize("assignment, field, problem", BAD_VALUES,
                         ids=[case[0] for case in BAD_VALUES])
def test_bad_physics_or_body_value_is_a_one_line_error_naming_its_field(assignment, field,
                                                                        problem):
    with pytest.raises(SceneError) as caught:
        load_scene("bounce", [assignment])
    message = str(caught.value)
    assert message.split(": ", 1)[1].startswith(f"{field}: "), message
    assert problem in message and "\n" not in message


def test_an_unknown_physics_backend_is_refused_in_one_line_naming_the_choices():
    with pytest.raises(physics.PhysicsError) as caught:
        simulate(physics.World(), 1.0, backend="quantum")
    message = str(caught.value)
    assert "backend" in message and "'cpu'" in message and "'gpu'" in message
    assert "\n" not in message


def test_integrator_and_solver_names_are_the_ones_physics_accepts():
    assert typing.get_args(Integrator) == INTEGRATOR_NAMES
    assert typing.get_args(Solver) == SOLVER_NAMES
    assert set(INTEGRATOR_NAMES) == set(physics.INTEGRATORS)
    assert set(SOLVER_NAMES) == set(physics.SOLVERS)


# --- The world -----------------------------------------------------------------------------------

def test_build_world_masses_are_four_thirds_pi_r_cubed_rho_to_1e_12(bounce):
    scene = load_scene("bounce", ["bodies[1].mass=2.5"])
    world = build_world(scene)
    default_density = scene.physics.density
    for index, body in enumerate(scene.bodies):
        if body.mass is not None:
            expected = body.mass
        else:
            rho = body.density if body.density is not None else default_density
            expected = 4 / 3 * math.pi * body.radius ** 3 * rho
        assert world.mass[index] == pytest.approx(expected, rel=1e-12), index
    assert world.mass[1] == 2.5
    assert scene.bodies[4].density == 2000.0 and scene.bodies[0].density is None


def test_build_world_takes_missing_body_values_from_the_physics_section(bounce):
    world = build_world(bounce)
    settings = bounce.physics
    np.testing.assert_array_equal(world.restitution, [0.0, 0.5, 0.8, 1.0, 0.9, 0.9])
    np.testing.assert_array_equal(world.friction, [settings.friction] * 6)
    np.testing.assert_array_equal(world.position, [b.position for b in bounce.bodies])
    np.testing.assert_array_equal(world.velocity, [b.velocity for b in bounce.bodies])
    assert (world.dt, world.integrator, world.solver) == (settings.dt, "semi_implicit",
                                                          "sequential")
    np.testing.assert_array_equal(world.plane_restitution, [settings.plane_restitution])


def test_exact_planes_come_from_top_level_planes_moved_by_translate_only_the_rest_are_shapes():
    scene = Scene(materials={"default": Material()}, objects=(
        plane(normal=(0, 2, 0), offset=0.5).at(0, 1, 0).at(3, 0.25, 0),   # y = 0.5 + 1.25
        plane(normal=(1, 0, 0), offset=-4),                               # x = -4
        plane(normal=(0, 0, 1)).rotate(0, 90, 0),                         # rotated: a shape
        plane() | sphere(1),                                              # in CSG: a shape
        sphere(1).at(0, 5, 0)))                                           # a shape
    assert static_planes(scene) == [((0.0, 1.0, 0.0), 1.75), ((1.0, 0.0, 0.0), -4.0)]
    world = build_world(scene)
    np.testing.assert_array_equal(world.plane_normal, [[0, 1, 0], [1, 0, 0]])
    np.testing.assert_array_equal(world.plane_offset, [1.75, -4.0])
    assert [shape.name for shape in world.shapes] == ["objects[2]", "objects[3]", "objects[4]"]


def test_a_scene_drop_is_the_physics_drop_bit_for_bit():
    """The same ball stepped through the scene and through physics directly."""
    scene = drop_scene(integrator="verlet", dt=1 / 200, plane_friction=0.4)
    plan = frame_plan(scene.physics.dt, fps=20, seconds=2.0)
    from_scene = simulate_scene(scene, plan)

    world = physics.World(dt=1 / 200, integrator="verlet")
    world.add_sphere((0, 2, 0), radius=0.5, density=1000.0, restitution=0.5, friction=0.5)
    world.add_plane((0, 1, 0), 0.0, restitution=0.0, friction=0.4)
    direct = physics.simulate(world, 1.95, record_every=10)

    assert from_scene.positions.shape == (40, 1, 3)
    np.testing.assert_array_equal(from_scene.positions, direct.positions)
    np.testing.assert_array_equal(from_scene.velocities, direct.velocities)
    assert len(direct.events) > 0                       # it did bounce in those 2 s


def test_a_body_whose_mass_would_overflow_is_refused_naming_its_radius():
    # The radius is refused by its declared range (at most 1e6 m) when the scene is read, so a
    # world is never built with an infinite mass.
    with pytest.raises(SceneError) as caught:
        load_scene("bounce", ["bodies[2].radius=1e200"])
    assert str(caught.value) == "bounce: bodies[2].radius: must be <= 1e6 (got 1e+200)"


@pytest.mark.parametrize("fps, every, exact", [(30, 8, True), (240, 1, True), (7, 34, False),
                                               (1000, 1, False)])
def test_a_frame_is_recorded_every_round_one_over_fps_dt_steps(fps, every, exact):
    plan = frame_plan(1 / 240, fps, seconds=2.0)
    assert (plan.record_every, plan.exact, plan.frames) == (every, exact, round(2.0 * fps))
    assert plan.frame_seconds == every / 240


# --- Drawing the bodies --------------------------------------------------------------------------

def test_bodies_are_translated_spheres_after_the_objects(bounce):
    objects = scene_objects(bounce)
    assert objects[:len(bounce.objects)] == bounce.objects
    for body, node in zip(bounce.bodies, objects[len(bounce.objects):]):
        assert isinstance(node, Translate) and node.offset == body.position
        assert (node.child.radius, node.child.material) == (body.radius, body.material)
    assert len(objects) == len(bounce.objects) + len(bounce.bodies)


def test_static_object_ids_are_the_same_with_or_without_bodies(bounce):
    with_bodies = render(bounce, 48, 36)
    without = render(dataclasses.replace(bounce, bodies=()), 48, 36)
    static = len(list(primitives(bounce.objects)))
    seen = with_bodies.object_id < static
    np.testing.assert_array_equal(with_bodies.object_id[seen], without.object_id[seen])
    drawn = set(np.unique(with_bodies.object_id[with_bodies.object_id >= static]).tolist())
    assert drawn == set(range(static, static + len(bounce.bodies)))   # every ball is visible


def test_moving_the_bodies_changes_shader_parameters_not_its_source(bounce):
    start = np.array([body.position for body in bounce.bodies])
    later = start + np.array([0.0, -0.5, 0.1])
    a = generate(rendered_scene(scene_at(bounce, start)), 64, 48)
    b = generate(rendered_scene(scene_at(bounce, later)), 64, 48)
    assert a.source == b.source
    assert not np.array_equal(a.parameters, b.parameters)


def test_scene_at_moves_the_bodies_and_nothing_else(bounce):
    positions = np.arange(18.0).reshape(6, 3)
    moved = scene_at(bounce, positions)
    assert [body.position for body in moved.bodies] == [tuple(row) for row in positions.tolist()]
    assert dataclasses.replace(moved, bodies=bounce.bodies) == bounce
    with pytest.raises(ValueError):
        scene_at(bounce, positions[:5])


def test_rendered_scene_is_idempotent_and_leaves_no_bodies(bounce):
    once = rendered_scene(bounce)
    assert once.bodies == () and rendered_scene(once) == once
    assert once.objects == scene_objects(bounce)


# --- Plans that cannot be carried out, and progress ----------------------------------------------

@pytest.mark.parametrize("dt, fps, seconds, message", [
    (1 / 240, 1e308, 1e308, "more frames than can be counted"),
    (1e-6, 1e-308, 1e308, "than can be counted"),        # 1 / (fps dt) overflows to inf
    (1 / 240, 5e-324, 1e308, "less than one frame"),
], ids=["frames_overflow", "steps_per_frame_overflow", "no_frame"])
def test_frame_plan_refuses_counts_a_float_cannot_hold_in_one_line(dt, fps, seconds, message):
    with pytest.raises(MarchlabError) as caught:
        frame_plan(dt, fps, seconds)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_simulate_scene_reports_progress_up_to_the_last_step_and_the_same_trajectory(bounce):
    plan = frame_plan(bounce.physics.dt, fps=10, seconds=2.0)      # 20 frames, 456 steps
    reports = []
    watched = simulate_scene(bounce, plan, progress=lambda done, total: reports.append(
        (done, total)))
    assert reports[-1] == (plan.steps, plan.steps)
    assert [done for done, _ in reports] == sorted(done for done, _ in reports)
    assert len(reports) >= plan.steps // 64                       # a report every 64 steps
    np.testing.assert_array_equal(watched.positions, simulate_scene(bounce, plan).positions)

