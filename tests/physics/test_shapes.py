"""Static shapes given by an SDF (physics/colliders.py), against exact answers.

The shapes here are written out in NumPy (an exact box SDF, Quilez's formula), so these tests
check the physics alone; tests/test_scene_colliders.py checks the scene's shapes, built from
the renderer's SDF, on the bundled ramp, bowl and table.
"""

import numpy as np
import pytest

import physics
from physics.colliders import (FALLBACK_NORMAL, MAX_SHAPE_CONTACTS, Shape, shape_contacts,
                               surface_near)
from physics.contacts import find_contacts

G = 9.81
STEP = 1e-6          # central-difference step of the normals below (m)


def box_shape(centre, half_size, name="box", restitution=0.0, friction=0.5, hollow=None):
    """An exact box SDF (Quilez, "Distance functions"); with ``hollow`` = (centre, half size)
    a second box is subtracted from it (a container)."""
    def box(p, c, h):
        q = np.abs(p - np.asarray(c, p.dtype)) - np.asarray(h, p.dtype)
        outside = np.sqrt(np.sum(np.maximum(q, 0) ** 2, axis=1))
        return outside + np.minimum(np.max(q, axis=1), 0)

    def distance(p):
        d = box(p, centre, half_size)
        return d if hollow is None else np.maximum(d, -box(p, *hollow))

    def normal(p):
        axes = np.eye(3, dtype=p.dtype)
        g = np.stack([distance(p + STEP * k) - distance(p - STEP * k) for k in axes], axis=1)
        size = np.sqrt(np.sum(g * g, axis=1))[:, None]
        return np.divide(g, size, out=np.zeros_like(g), where=size > 0)

    return Shape(name, distance, normal, restitution, friction, normal_step=STEP)


# A container: a 2 x 1.2 x 2 m block with a 1.8 m wide hollow; its inside floor is y = 0.6
# and its inside walls x, z = +-0.9.
CONTAINER = dict(centre=(0, 0.5, 0), half_size=(1, 0.6, 1),
                 hollow=((0, 1.2, 0), (0.9, 0.6, 0.9)))


def test_a_ball_in_a_box_corner_gets_one_contact_per_face_with_the_faces_normals_to_1e_9():
    """Centre equidistant from the floor and two walls: the SDF's gradient there is a blend of
    the three normals; the contacts must be the three faces' own."""
    shape = box_shape(**CONTAINER)
    x = np.array([[0.8, 0.7, 0.8]])
    found = shape_contacts(shape, x, np.array([0.1]), np.array([0]), reach=1e-4)
    assert len(found.body) == MAX_SHAPE_CONTACTS == 3
    normals = sorted(map(tuple, np.round(found.normal, 9)))
    assert normals == [(-1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)]
    np.testing.assert_allclose(found.gap, 0, atol=1e-9)


def test_a_ball_on_one_face_gets_one_contact_not_three():
    shape = box_shape(**CONTAINER)
    found = shape_contacts(shape, np.array([[0.0, 0.7, 0.3]]), np.array([0.1]), np.array([0]),
                           reach=1e-4)
    assert len(found.body) == 1
    np.testing.assert_allclose(found.normal, [[0, 1, 0]], atol=1e-9)


def test_where_the_gradient_vanishes_the_normal_is_the_fallback_not_nan():
    """The centre of a sphere: every direction is as near as every other."""
    def distance(p):
        return 1 - np.sqrt(np.sum(p * p, axis=1))        # the inside of a hollow sphere

    def normal(p):
        return np.zeros_like(p)                           # the gradient at the centre
    shape = Shape("hollow", distance, normal, normal_step=STEP)
    d, n = surface_near(shape, np.zeros((1, 3)), distance(np.zeros((1, 3))))
    assert np.all(np.isfinite(n)) and np.isfinite(d).all()
    np.testing.assert_array_equal(shape_contacts(shape, np.zeros((1, 3)), np.array([1.0]),
                                                 np.array([0]), 1e-4).normal[0],
                                  FALLBACK_NORMAL)


def test_a_ball_at_rest_in_a_concave_corner_stays_within_1e_9_m_for_10_s():
    """Pressed into the corner by gravity with horizontal parts too, it touches three faces."""
    for gravity in [(0, -G, 0), (4.0, -G, 3.0)]:
        world = physics.World(gravity=gravity, dt=1 / 240)
        world.add_shape(box_shape(**CONTAINER))
        world.add_sphere((0.8, 0.7, 0.8), radius=0.1, restitution=0.0)
        run = physics.simulate(world, 10.0, record_every=60)
        drift = np.max(np.abs(run.positions[:, 0] - run.positions[0, 0]))
        assert drift < 1e-9, (gravity, drift)
        assert len(run.events) == 0


def test_a_ball_dropped_on_a_box_bounces_like_on_the_plane_of_its_top_within_2e_4_m():
    """e = 0.5: the plane's time of impact is exact, the box's is found by conservative
    advancement within half the slop (5e-5 m); the paths differ by less than 2e-4 m."""
    runs = []
    for kind in ("plane", "box"):
        world = physics.World(dt=1 / 240)
        if kind == "plane":
            world.add_plane((0, 1, 0), 1.0, restitution=0.5)
        else:
            world.add_shape(box_shape((0, 0.5, 0), (2, 0.5, 2), restitution=0.5))
        world.add_sphere((0.3, 2.0, -0.2), radius=0.1, restitution=0.5)
        runs.append(physics.simulate(world, 2.0))
    plane, box = runs
    assert np.max(np.abs(plane.positions - box.positions)) < 2e-4
    bounces = box.events[box.events["kind"] == "sphere-shape"]
    assert len(bounces) >= 3 and set(bounces["other"]) == {0}


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_a_ball_at_200_m_s_bounces_off_a_1_cm_wall_at_dt_1_60(dtype):
    """3.3 m a step against a wall 1 cm thick: conservative advancement stops it at the wall,
    and at e = 1 it leaves at 200 m/s the way it came."""
    world = physics.World(gravity=(0, 0, 0), dt=1 / 60, dtype=dtype)
    world.add_shape(box_shape((1.0, 0, 0), (0.005, 1, 1), restitution=1.0))
    world.add_sphere((0, 0, 0), velocity=(200, 0, 0), radius=0.1, restitution=1.0)
    run = physics.simulate(world, 0.2)
    assert np.max(run.positions[:, 0, 0]) <= 0.995 - 0.1 + 1e-4
    assert run.velocities[-1, 0, 0] == pytest.approx(-200, rel=1e-6)
    assert run.events["kind"][0] == "sphere-shape"


def test_a_ball_rolling_on_a_box_floor_still_meets_the_wall():
    """Touching the container's floor must not hide its wall from the continuous test: the
    ball never passes into the wall by more than half the slop."""
    world = physics.World(dt=1 / 240)
    world.add_shape(box_shape(**CONTAINER, restitution=0.5))
    world.add_sphere((0, 0.7, 0), velocity=(6, 0, 4), radius=0.1, restitution=0.5)
    run = physics.simulate(world, 3.0)
    inside = 0.9 - 0.1 + 0.5 * world.slop
    assert np.max(np.abs(run.positions[:, 0, [0, 2]])) <= inside


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_energy_never_rises_above_the_start_bouncing_in_a_box_with_e_up_to_1(solver):
    """Two balls thrown into a container, e = 0, 0.5 and 1, friction 0.5, 4 s. Velocity
    Verlet puts each step's end exactly on the parabola, so the energy at step ends is the
    true one in flight and any rise is the contacts' doing: it never exceeds the start by
    1e-9 J, and no step adds more than 1e-4 J (the largest, 2.7e-5 J of 134 J, at e = 0.5,
    is the push-out of a ball pressed into the floor by the other)."""
    for e in (0.0, 0.5, 1.0):
        world = physics.World(dt=1 / 240, solver=solver, integrator="verlet")
        world.add_shape(box_shape(**CONTAINER, restitution=e))
        world.add_sphere((0, 0.9, 0), velocity=(3, 1, 2), radius=0.1, density=1000,
                         restitution=e)
        world.add_sphere((0.4, 0.75, 0.3), velocity=(-2, 0, 1), radius=0.15, density=1000,
                         restitution=e)
        run = physics.simulate(world, 4.0)
        assert np.max(run.energy) <= run.energy[0] + 1e-9, e
        assert np.max(np.diff(run.energy)) < 1e-4, e
        assert len(run.events) > 10


def test_shape_contacts_take_restitution_and_friction_from_the_surface_where_given():
    base = box_shape((0, -1, 0), (5, 1, 5))
    shape = Shape("two materials", base.distance, base.normal, 0.0, 0.5,
                  surface=lambda p: (np.where(p[:, 0] < 0, 0.9, 0.1),
                                     np.where(p[:, 0] < 0, 0.25, 1.0)),
                  normal_step=STEP)
    world = physics.World()
    world.add_shape(shape)
    world.add_sphere((-1, 0.1, 0), radius=0.1, restitution=0.0, friction=1.0)
    world.add_sphere((1, 0.1, 0), radius=0.1, restitution=0.0, friction=1.0)
    contacts = find_contacts(world, world.slop)
    np.testing.assert_array_equal(contacts.shape, [0, 0])
    np.testing.assert_allclose(contacts.restitution, [0.9, 0.1])
    np.testing.assert_allclose(contacts.friction, [0.5, 1.0])


def test_add_shape_refuses_what_is_not_a_shape_and_bad_coefficients_in_one_line():
    world = physics.World()
    with pytest.raises(physics.PhysicsError, match="must be a physics.colliders.Shape"):
        world.add_shape(lambda p: p)
    shape = box_shape((0, 0, 0), (1, 1, 1))
    for field, value in (("restitution", 1.5), ("friction", -1.0), ("lipschitz", 0.5)):
        bad = Shape(shape.name, shape.distance, shape.normal,
                    **{"restitution": 0.0, "friction": 0.5, "lipschitz": 1.0, field: value})
        with pytest.raises(physics.PhysicsError, match=field) as caught:
            world.add_shape(bad)
        assert "\n" not in str(caught.value)
