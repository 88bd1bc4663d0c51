"""Every static object of a scene is a collider, through the renderer's own SDF.

The bundled ramp, bowl and table against closed forms (marchlab/colliders.py builds their
shapes from reference_cpu's SDF and normals), the coefficients taken from the materials, and
the warning for a repetition whose distance may overestimate.
"""

import math
import warnings

import numpy as np
import pytest

import marchlab
import physics
from marchlab.colliders import scene_shapes, shape_objects, unsafe_distance
from marchlab.simulation import build_world
from scene_model.builder import (Body, Material, PhysicsSettings, Scene, box, capped_cylinder,
                                 plane, sphere)

G = 9.81


def test_every_top_level_object_but_the_translated_planes_becomes_a_shape():
    scene = Scene(materials={"default": Material()}, objects=(
        plane().at(0, 1, 0), plane(normal=(1, 1, 0)).rotate(0, 0, 10), box(1) - sphere(1.2),
        sphere(0.5).at(3, 0, 0)))
    world = build_world(scene)
    assert len(world.plane_offset) == 1
    assert [shape.name for shape in world.shapes] == ["objects[1]", "objects[2]", "objects[3]"]
    assert shape_objects(scene) == list(scene.objects[1:])


def test_a_ball_dropped_onto_a_box_no_longer_falls_through_it():
    """The user report that started this: a ball dropped onto a box fell straight through."""
    scene = Scene(materials={"default": Material()}, objects=(box(1, 0.5, 1).at(0, 0.5, 0),),
                  bodies=(Body(position=(0.2, 3.0, 0.0), radius=0.25),))
    run = physics.simulate(build_world(scene), 3.0)
    assert run.positions[:, 0, 1].min() >= 1.0 + 0.25 - 1e-3
    assert run.positions[-1, 0, 1] == pytest.approx(1.25, abs=2e-4)


@pytest.mark.parametrize("dtype, tolerance", [(np.float64, 1e-9), (np.float32, 1e-4)])
def test_ramp_ball_rolls_at_five_sevenths_g_sin_30(dtype, tolerance):
    """The bundled ramp: released at rest on a box turned 30 degrees, friction 0.5, the ball
    rolls without slipping, s = a t^2 / 2 + a h t / 2 with a = 5/7 g sin 30 (the second term
    is semi-implicit Euler's, integrators.py). Measured: a within 2e-12 relative in float64,
    9e-6 in float32."""
    scene = marchlab.load_scene("ramp")
    world = build_world(scene, dtype)
    run = physics.simulate(world, 1.0)
    down = -np.array([math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0])
    s = (run.positions[:, 0] - run.positions[0, 0]) @ down
    a, h, t = 5 / 7 * G * 0.5, world.dt, run.times
    np.testing.assert_allclose(s, 0.5 * a * t * t + 0.5 * a * h * t, rtol=tolerance,
                               atol=tolerance)
    # no slip: the contact point v + w x (-r n) is at rest
    normal = np.array([-0.5, math.cos(math.radians(30)), 0.0])
    slip = run.velocities[:, 0] + np.cross(run.angular_velocities[:, 0],
                                           -scene.bodies[0].radius * normal)
    assert np.abs(slip).max() < 100 * tolerance


def test_ramp_ball_launched_sliding_starts_rolling_at_the_closed_form_time_within_one_step():
    """Sent down the slope at v0 = 2 m/s without spin, the ball slides: friction slows the
    slip v - w r by g (7/2 mu cos 30 - sin 30) (the linear part loses mu g cos 30 - g sin 30,
    the spin gains 5/2 mu g cos 30 / r), so rolling starts at
    t* = v0 / (g (7/2 mu cos 30 - sin 30)) = 0.2007 s for mu = 0.5."""
    scene = marchlab.load_scene("ramp")
    down = -np.array([math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0])
    world = build_world(scene)
    world.velocity[0] = 2.0 * down
    run = physics.simulate(world, 0.5)
    normal = np.array([-0.5, math.cos(math.radians(30)), 0.0])
    slip = (run.velocities[:, 0] + np.cross(run.angular_velocities[:, 0],
                                            -scene.bodies[0].radius * normal)) @ down
    expected = 2.0 / (G * (3.5 * 0.5 * math.cos(math.radians(30)) - 0.5))
    assert expected == pytest.approx(0.2007, abs=1e-4)
    rolling = run.times[np.argmax(np.abs(slip) < 1e-9)]
    assert abs(rolling - expected) <= world.dt


def test_bowl_ball_swings_with_the_rolling_pendulum_period_within_2e_4():
    """The bundled bowl: T = 2 pi sqrt(7 (R - r) / (5 g)) = 2.2518 s for small swings,
    longer by theta0^2 / 16 at the release angle theta0 = 8 degrees (the pendulum's
    amplitude correction). Measured: the half-periods agree with that to 5e-5."""
    scene = marchlab.load_scene("bowl")
    run = physics.simulate(build_world(scene), 6.0)
    x = run.positions[:, 0, 0]
    crossing = np.flatnonzero(np.sign(x[:-1]) != np.sign(x[1:]))
    times = run.times[crossing] - x[crossing] * (run.times[crossing + 1] - run.times[crossing]) / (
        x[crossing + 1] - x[crossing])
    period = 2 * np.diff(times)
    small = 2 * math.pi * math.sqrt(7 * (1.0 - 0.1) / (5 * G))
    expected = small * (1 + math.radians(8) ** 2 / 16)
    assert len(period) >= 4
    np.testing.assert_allclose(period, expected, rtol=2e-4)
    # it keeps rolling on the hollow: its centre R - r from the sphere's centre
    radius = np.linalg.norm(run.positions[:, 0] - [0, 1.2, 0], axis=1)
    assert np.abs(radius - 0.9).max() < 2e-4


def test_table_break_keeps_every_ball_on_the_table_and_never_gains_energy():
    """The bundled table: 16 balls at up to 6 m/s against box cushions. Nothing passes a
    cushion or sinks into the bed, and the energy never rises above the start."""
    scene = marchlab.load_scene("table")
    run = physics.simulate(build_world(scene), 4.0, record_every=4)
    r = scene.bodies[0].radius
    assert np.abs(run.positions[..., 0]).max() <= 1.27 - r + 1e-4
    assert np.abs(run.positions[..., 2]).max() <= 0.635 - r + 1e-4
    assert run.positions[..., 1].min() >= 0.8 + r - 1e-4
    assert run.active.all()
    assert run.energy.max() <= run.energy[0] + 1e-9
    kinds = set(run.events["kind"])
    assert {"sphere-sphere", "sphere-shape"} <= kinds


def test_a_shapes_restitution_and_friction_come_from_the_material_at_the_contact():
    scene = Scene(materials={"default": Material(),
                             "rubber": Material(restitution=0.9, friction=1.5)},
                  objects=(box(2, 0.5, 2, material="rubber").at(0, -0.5, 0)
                           | box(2, 0.5, 2).at(4.5, -0.5, 0),),
                  physics=PhysicsSettings(plane_restitution=0.2, plane_friction=0.1),
                  bodies=(Body(position=(0, 0.1, 0), radius=0.1, restitution=0.0, friction=1.0),
                          Body(position=(4.5, 0.1, 0), radius=0.1, restitution=0.0,
                               friction=1.0)))
    world = build_world(scene)
    contacts = physics.contacts.find_contacts(world, world.slop)
    np.testing.assert_allclose(contacts.restitution, [0.9, 0.2])
    np.testing.assert_allclose(contacts.friction, [math.sqrt(1.5), math.sqrt(0.1)])


def test_a_repetition_whose_copies_cross_their_cells_warns_in_one_line():
    crowded = capped_cylinder(0.3, 1.0).repeat((0.5, 0, 0), count=(3, 0, 0))
    spaced = capped_cylinder(0.2, 1.0).repeat((0.5, 0, 0), count=(3, 0, 0))
    assert unsafe_distance(spaced) is None
    assert "past their cells' walls along x" in unsafe_distance(crowded)
    scene = Scene(materials={"default": Material()}, objects=(spaced, crowded))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene_shapes(scene, PhysicsSettings())
    assert len(caught) == 1
    message = str(caught[0].message)
    assert message.startswith("objects[1] (repeat) as a collider:") and "\n" not in message
