"""Boxes and capsules: their inertia, free tumbling, sliding, rolling, landing and stacking,
each against a closed form (physics/solids.py, solid_contacts.py, point_solver.py)."""

import numpy as np
import pytest

import physics
from physics.quaternions import quaternion_from_rotation_vector, rotation_matrices
from physics.solids import BOX, CAPSULE, principal_inertia, volume

G = 9.81


def turned(vector):
    """The quaternion (4,) of the rotation vector ``vector`` (radians)."""
    return quaternion_from_rotation_vector(np.array([vector], float))[0]


def incline(degrees, friction):
    """A world whose only static is the plane through the origin tilted ``degrees`` about z
    (downhill is +x), and the unit vectors (down the slope, normal). A body turned by
    -``degrees`` about z has its own y axis along the normal."""
    theta = np.radians(degrees)
    normal = np.array([np.sin(theta), np.cos(theta), 0.0])
    down = np.array([np.cos(theta), -np.sin(theta), 0.0])
    world = physics.World(gravity=(0, -G, 0))
    world.add_plane(normal, 0.0, restitution=0.0, friction=friction)
    return world, down, normal


# --- mass and inertia ------------------------------------------------------------------------

@pytest.mark.parametrize("kind, radius, extent", [(BOX, 0.0, (0.3, 0.2, 0.1)),
                                                  (CAPSULE, 0.15, (0.0, 0.4, 0.0))])
def test_moments_of_inertia_match_a_monte_carlo_integral(kind, radius, extent):
    """I = integral of rho (|p|^2 - p_i^2) over the solid, sampled at 2 million uniform
    points: within 1% (the sampling error is about 0.2%)."""
    rng = np.random.default_rng(7)
    extent = np.array(extent)
    bound = extent + radius
    p = rng.uniform(-bound, bound, size=(2_000_000, 3))
    if kind == BOX:
        inside = np.all(np.abs(p) <= extent, axis=1)
    else:
        along = np.clip(p[:, 1], -extent[1], extent[1])
        inside = (p[:, 0] ** 2 + (p[:, 1] - along) ** 2 + p[:, 2] ** 2) <= radius ** 2
    q = p[inside]
    mass = 2.0
    sampled = mass * np.mean(np.sum(q * q, axis=1)[:, None] - q * q, axis=0)
    exact = principal_inertia(np.array([kind]), np.array([mass]), np.array([radius]),
                              extent[None])[0]
    assert np.allclose(exact, sampled, rtol=0.01)
    box_volume = np.prod(2 * bound)
    assert np.isclose(volume(np.array([kind]), np.array([radius]), extent[None])[0],
                      box_volume * inside.mean(), rtol=0.01)


# --- free flight ------------------------------------------------------------------------------

def free_box(spin, half=(0.3, 0.2, 0.1), dt=1 / 240):
    world = physics.World(gravity=(0, 0, 0), dt=dt)
    world.add_box((0, 0, 0), half, orientation=turned((0.3, -0.2, 0.5)),
                  angular_velocity=spin, mass=2.0)
    return world


def test_a_tumbling_box_keeps_its_angular_momentum_and_energy():
    """Torque-free: L exactly (1e-12 relative, the splitting turns L's body-frame image, never
    L), the energy within 1e-5 relative over 10 s: the splitting's error is O((h w)^2), here
    (4.6 / 240)^2 = 4e-4 times a small factor, and it oscillates instead of drifting."""
    world = free_box((1.0, 4.0, -2.0))
    momentum, energy = world.angular_momentum(), world.energy()
    for _ in range(10):
        world.step(240)
        assert np.allclose(world.angular_momentum(), momentum, rtol=0, atol=1e-12 * np.sqrt(
            momentum @ momentum))
        assert abs(world.energy() - energy) <= 1e-5 * energy


def euler_equations_spin(principal, spin_body, seconds):
    """Body-frame w after ``seconds`` from Euler's equations I w' = (I w) x w, by classical
    Runge-Kutta with 20,000 steps a second (error far below 1e-9 here)."""
    def rate(w):
        return np.cross(principal * w, w) / principal
    w, h = np.array(spin_body, float), 1 / 20000
    for _ in range(int(round(seconds / h))):
        k1 = rate(w)
        k2 = rate(w + h / 2 * k1)
        k3 = rate(w + h / 2 * k2)
        k4 = rate(w + h * k3)
        w = w + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return w


def test_free_tumbling_follows_eulers_equations():
    """The body-frame angular velocity after 1 s matches Euler's equations within 1e-3 rad/s
    (|w| about 4.6 rad/s; the splitting's error with h = 1/1000 s is O(h^2))."""
    world = free_box((1.0, 4.0, -2.0), dt=1 / 1000)
    start = rotation_matrices(world.orientation)[0].T @ world.angular_velocity[0]
    world.step(1000)
    body = rotation_matrices(world.orientation)[0].T @ world.angular_velocity[0]
    expected = euler_equations_spin(world.principal_inertia[0], start, 1.0)
    assert np.allclose(body, expected, rtol=0, atol=1e-3)


def test_spin_about_the_middle_axis_flips_and_about_the_others_is_stable():
    """The tennis-racket theorem: spun about its largest or smallest principal axis (with a
    1% wobble) a box keeps spinning that way (the component stays above 98% of its start);
    about the middle axis the wobble grows and the spin turns over (the component changes
    sign) within 5 s."""
    half = (0.3, 0.2, 0.1)               # moments: x smallest, y middle, z largest
    for axis, flips in ((0, False), (1, True), (2, False)):
        spin = np.full(3, 0.05)
        spin[axis] = 5.0
        world = physics.World(gravity=(0, 0, 0))
        world.add_box((0, 0, 0), half, angular_velocity=spin, mass=1.0)
        lowest = np.inf
        for _ in range(5 * 24):
            world.step(10)
            body = rotation_matrices(world.orientation)[0].T @ world.angular_velocity[0]
            lowest = min(lowest, body[axis])
        assert (lowest < 0) == flips
        if not flips:
            assert lowest > 0.98 * 5.0


# --- on the floor and on slopes ----------------------------------------------------------------

def test_a_box_dropped_flat_comes_to_rest_on_the_floor():
    """e = 0: at rest with its bottom face on y = 0 (within the 1e-4 m slop), no sideways
    drift (1e-6 m) and no spin over 4 s."""
    world = physics.World()
    world.add_plane((0, 1, 0), 0.0, restitution=0.0)
    world.add_box((0.5, 0.6, -0.2), (0.2, 0.1, 0.3), restitution=0.0)
    world.step(240)
    assert abs(world.position[0, 1] - 0.1) <= 1e-4
    rest = world.position.copy()
    world.step(3 * 240)
    assert np.allclose(world.position, rest, rtol=0, atol=1e-6)
    assert np.abs(world.angular_velocity).max() < 1e-6


def test_a_box_slides_down_an_incline_at_g_sin_minus_mu_cos():
    """30 degrees, mu = 0.3 < tan 30: a = g (sin 30 - mu cos 30) = 2.357 m/s^2; after 1 s it
    has slid a / 2 (within 1%), without turning (1e-6 rad/s)."""
    world, down, normal = incline(30, 0.3)
    half = np.array([0.2, 0.05, 0.2])
    world.add_box(0.05 * normal, half, orientation=turned((0, 0, -np.radians(30))),
                  restitution=0.0, friction=0.3)
    start = world.position[0].copy()
    world.step(240)
    travelled = (world.position[0] - start) @ down
    expected = 0.5 * G * (np.sin(np.radians(30)) - 0.3 * np.cos(np.radians(30)))
    assert travelled == pytest.approx(expected, rel=0.01)
    assert np.abs(world.angular_velocity[0]).max() < 1e-6


def test_a_box_holds_on_an_incline_where_friction_is_enough():
    """mu = 0.7 > tan 30 = 0.577: static friction holds it (moves less than 1e-4 m in 2 s)."""
    world, down, normal = incline(30, 0.7)
    world.add_box(0.05 * normal, (0.2, 0.05, 0.2), orientation=turned((0, 0, -np.radians(30))),
                  restitution=0.0, friction=0.7)
    start = world.position[0].copy()
    world.step(480)
    assert np.linalg.norm(world.position[0] - start) < 1e-4


def test_a_capsule_rolls_down_an_incline_at_g_sin_over_one_plus_i_over_m_r_squared():
    """A capsule lying across the slope rolls on its two end caps without slipping:
    a = g sin 30 / (1 + I_axis / (m r^2)) (within 1%) after 1 s."""
    world, down, normal = incline(30, 1.0)
    r, l, m = 0.1, 0.3, 1.0
    # Its axis along z: across the slope, which runs in x.
    world.add_capsule(r * normal, l, r, orientation=turned((np.pi / 2, 0, 0)), mass=m,
                      restitution=0.0, friction=1.0)
    start = world.position[0].copy()
    world.step(240)
    axis_moment = principal_inertia(np.array([CAPSULE]), np.array([m]), np.array([r]),
                                    np.array([[0, l, 0]]))[0, 1]
    expected = 0.5 * G * np.sin(np.radians(30)) / (1 + axis_moment / (m * r * r))
    assert (world.position[0] - start) @ down == pytest.approx(expected, rel=0.01)


def test_a_box_landing_on_a_corner_never_gains_energy():
    """Dropped tilted with e = 0.5: it bounces and topples flat; the energy (kinetic +
    rotational + potential) never rises above the start (1e-9 relative), and it ends at rest
    on a face."""
    world = physics.World()
    world.add_plane((0, 1, 0), 0.0, restitution=0.5)
    world.add_box((0, 1.0, 0), (0.2, 0.2, 0.2), orientation=turned((0.5, 0.2, 0.3)),
                  restitution=0.5)
    start = world.energy()
    for _ in range(3 * 240):
        world.step()
        assert world.energy() <= start * (1 + 1e-9)
    assert world.kinetic_energy() < 1e-8
    assert abs(world.position[0, 1] - 0.2) < 2e-4


# --- bodies against bodies ----------------------------------------------------------------------

def test_a_ball_striking_a_box_head_on_exchanges_momentum_elastically():
    """No gravity, e = 1, a 1 kg ball at 2 m/s along x into the middle of a 3 kg box's face:
    the 1-D elastic answer v_ball = (m1 - m2) / (m1 + m2) v = -1, v_box = 2 m1 / (m1 + m2) v = 1
    (1e-9), no spin, momentum kept exactly (1e-12)."""
    world = physics.World(gravity=(0, 0, 0))
    world.add_sphere((-1.0, 0, 0), velocity=(2.0, 0, 0), radius=0.1, mass=1.0, restitution=1.0)
    world.add_box((0.3, 0, 0), (0.2, 0.2, 0.2), mass=3.0, restitution=1.0)
    momentum = world.momentum()
    world.step(240)
    assert np.allclose(world.velocity[:, 0], [-1.0, 1.0], rtol=0, atol=1e-9)
    assert np.allclose(world.momentum(), momentum, rtol=0, atol=1e-12)
    assert np.abs(world.angular_velocity).max() < 1e-9


def test_a_stack_of_five_boxes_stands_for_ten_seconds():
    """Five boxes stacked on the floor (mu 0.6, e 0): once settled (after 1 s) no box moves
    more than 1e-5 m over the next 10 s, nor turns; the stack's total drift from where it was
    built is below 1e-3 m (the slop times the contacts, and the warm start's settling)."""
    world = physics.World()
    world.add_plane((0, 1, 0), 0.0, restitution=0.0, friction=0.6)
    for level in range(5):
        world.add_box((0.01 * level, 0.1 + 0.2 * level, 0), (0.2, 0.1, 0.15), restitution=0.0,
                      friction=0.6, density=500)
    built = world.position.copy()
    world.step(240)
    settled, turned_by = world.position.copy(), world.orientation.copy()
    world.step(10 * 240)
    assert np.abs(world.position - settled).max() < 1e-5
    assert np.abs(world.orientation - turned_by).max() < 1e-5
    assert np.abs(world.position - built).max() < 1e-3


def test_a_box_turned_on_another_rests_on_its_eight_point_overlap():
    """A box turned 45 degrees about y on an equal box: the overlap is an octagon; it rests
    (1e-6 m over 2 s) without turning."""
    world = physics.World()
    world.add_plane((0, 1, 0), 0.0, restitution=0.0)
    world.add_box((0, 0.2, 0), (0.2, 0.2, 0.2), restitution=0.0)
    world.add_box((0, 0.6, 0), (0.2, 0.2, 0.2), orientation=turned((0, np.pi / 4, 0)),
                  restitution=0.0)
    world.step(240)
    rest = world.position.copy()
    world.step(480)
    assert np.abs(world.position - rest).max() < 1e-6
    assert world.work["contacts"] >= 4 + 8     # the floor's 4 corners and the octagon's 8


def test_capsules_rest_side_by_side_on_the_floor_and_across_a_box():
    """Two capsules lying side by side, touching, and a third laid across a box: all at rest
    (1e-5 m over 2 s once settled), each lying on its two end caps, or on the box's top face
    at its ends and middle."""
    world = physics.World()
    world.add_plane((0, 1, 0), 0.0, restitution=0.0, friction=0.8)
    lying = turned((np.pi / 2, 0, 0))            # axis along z
    across = turned((0, 0, np.pi / 2))           # axis along x
    for x in (-0.1, 0.1):
        world.add_capsule((x, 0.1, 0), 0.4, 0.1, orientation=lying, restitution=0.0,
                          friction=0.8)
    world.add_box((1.0, 0.15, 0), (0.6, 0.15, 0.3), restitution=0.0, friction=0.8)
    world.add_capsule((1.0, 0.4, 0), 0.4, 0.1, orientation=across, restitution=0.0,
                      friction=0.8)
    world.step(480)
    rest = world.position.copy()
    world.step(480)
    assert np.abs(world.position - rest).max() < 1e-5
    assert world.position[3, 1] == pytest.approx(0.4, abs=2e-4)


# --- the rules ---------------------------------------------------------------------------------

@pytest.mark.parametrize("call, message", [
    (lambda w: w.add_box((0, 0, 0), (0.1, -0.1, 0.1)), "half_size y must be positive"),
    (lambda w: w.add_capsule((0, 0, 0), 0.0, 0.1), "half_length must be positive"),
    (lambda w: w.add_box((0, 0, 0), (1, 1, 1), orientation=(0, 0, 0, 0)), "orientation"),
    (lambda w: w.add_box((0, 0, 0), (1, 1, 1), mass=1, density=1), "not both"),
])
def test_bad_solids_are_refused_in_one_line(call, message):
    with pytest.raises(physics.PhysicsError, match=message) as error:
        call(physics.World())
    assert "\n" not in str(error.value)


def test_solids_need_the_sequential_solver():
    world = physics.World(solver="simultaneous")
    world.add_plane((0, 1, 0), 0.0)
    world.add_box((0, 0.1, 0), (0.1, 0.1, 0.1))
    with pytest.raises(physics.PhysicsError, match="sequential solver"):
        world.step()


def test_a_resumed_run_with_boxes_is_bit_identical(tmp_path):
    """Saving and loading mid-run (physics/state.py) carries the boxes' kinds, sizes and the
    warm start of their contacts: the resumed run equals the uninterrupted one bit for bit."""
    def build():
        world = physics.World()
        world.add_plane((0, 1, 0), 0.0)
        world.add_box((0, 0.5, 0), (0.2, 0.1, 0.15), orientation=turned((0.3, 0.1, 0.2)))
        world.add_capsule((0.6, 0.5, 0), 0.2, 0.1)
        world.add_sphere((0.0, 1.2, 0.05), radius=0.1)
        return world
    straight = build()
    straight.step(300)
    assert_resumes_bit_for_bit(build, straight, 150, tmp_path)


def assert_resumes_bit_for_bit(build, straight, first, tmp_path):
    """A world from ``build()`` stepped ``first`` steps, saved, loaded into another and stepped
    on to ``straight.steps`` equals ``straight`` (stepped straight through) bit for bit."""
    resumed = build()
    resumed.step(first)
    physics.save_state(resumed, tmp_path / "state.npz")
    fresh = build()
    physics.load_state(fresh, tmp_path / "state.npz")
    fresh.step(straight.steps - first)
    for name in ("position", "velocity", "angular_velocity", "orientation"):
        assert np.array_equal(getattr(fresh, name), getattr(straight, name)), name


def test_a_saved_box_world_refuses_a_world_with_another_shape(tmp_path):
    world = physics.World()
    world.add_box((0, 0.5, 0), (0.2, 0.1, 0.15))
    physics.save_state(world, tmp_path / "state.npz")
    other = physics.World()
    other.add_sphere((0, 0.5, 0))
    with pytest.raises(physics.PhysicsError, match="shape .* of body 0 is 1 in the file"):
        physics.load_state(other, tmp_path / "state.npz")
