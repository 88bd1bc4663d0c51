"""Building a world, its bookkeeping, bad arguments, precision and determinism."""

import hashlib

import numpy as np
import pytest

import physics
from physics.contacts import find_contacts
from physics.quaternions import rotation_matrices

RADIUS = 0.1


@pytest.mark.parametrize("make, name", [
    (lambda: physics.World(dt=0), "dt"),
    (lambda: physics.World(dt=float("nan")), "dt"),
    (lambda: physics.World(integrator="rk4"), "integrator"),
    (lambda: physics.World(solver="magic"), "solver"),
    (lambda: physics.World(dtype="float16"), "dtype"),
    (lambda: physics.World(gravity=(0, -9.81)), "gravity"),
    (lambda: physics.World(bounds=((0, 0, 0), (1, -1, 1))), "bounds"),
    (lambda: physics.World(iterations=0), "iterations"),
    (lambda: physics.World(seed=1.5), "seed"),
    (lambda: physics.World(restitution_threshold=-1), "restitution_threshold"),
    (lambda: physics.World().add_sphere((0, 0, 0), radius=-1.0), "radius"),
    (lambda: physics.World().add_sphere((0, 0, 0), radius=0), "radius"),
    (lambda: physics.World().add_sphere((0, 0, 0), mass=1, density=1000), "mass or density"),
    (lambda: physics.World().add_sphere((0, 0, 0), mass=-2), "mass"),
    (lambda: physics.World().add_sphere((0, 0, 0), density=0), "density"),
    (lambda: physics.World().add_sphere((0, 0, 0), restitution=1.5), "restitution"),
    (lambda: physics.World().add_sphere((0, 0, 0), friction=-0.1), "friction"),
    (lambda: physics.World().add_sphere((0, float("inf"), 0)), "position"),
    (lambda: physics.World().add_sphere((0, 0, 0), velocity="fast"), "velocity"),
    (lambda: physics.World().add_plane((0, 0, 0), 0), "normal"),
    (lambda: physics.World().add_plane((0, 1, 0), "low"), "offset"),
    (lambda: physics.World().step(-1), "n"),
    (lambda: physics.simulate(physics.World(), -1.0), "seconds"),
    (lambda: physics.simulate(physics.World(), 1.0, record_every=0), "record_every"),
])
def test_bad_argument_raises_a_one_line_value_error_naming_it(make, name):
    with pytest.raises(ValueError) as error:
        make()
    assert isinstance(error.value, physics.PhysicsError)
    message = str(error.value)
    assert name in message and "\n" not in message


def test_mass_from_density_is_four_thirds_pi_r_cubed_rho_within_1e_15():
    world = physics.World()
    world.add_sphere((0, 0, 0), radius=0.2, density=7800)       # a steel ball
    assert world.mass[0] == pytest.approx(4 / 3 * np.pi * 0.2 ** 3 * 7800, rel=1e-15)
    world.add_sphere((1, 0, 0))
    assert world.mass[1] == 1.0, "neither mass nor density: 1 kg"


def test_pair_coefficients_are_max_restitution_and_geometric_mean_friction():
    world = physics.World()
    world.add_plane((0, 1, 0), 0, restitution=0.2, friction=0.9)
    world.add_sphere((0, RADIUS, 0), radius=RADIUS, restitution=0.7, friction=0.4)
    world.add_sphere((0, 3 * RADIUS, 0), radius=RADIUS, restitution=0.1, friction=0.1)
    contacts = find_contacts(world, world.slop)
    assert list(contacts.kind()) == ["sphere-plane", "sphere-sphere"]
    assert contacts.restitution == pytest.approx([0.7, 0.7])
    assert contacts.friction == pytest.approx([np.sqrt(0.4 * 0.9), np.sqrt(0.4 * 0.1)])


def coincident_pair(seed):
    world = physics.World(gravity=(0, 0, 0), seed=seed)
    world.add_sphere((1, 2, 3), radius=RADIUS)
    world.add_sphere((1, 2, 3), radius=RADIUS)
    return world


def test_coincident_spawn_separates_without_nan_and_without_gaining_speed():
    world = coincident_pair(seed=1)
    assert not np.array_equal(world.position[0], world.position[1]), "spawn offset applied"
    world.step(240)
    assert np.all(np.isfinite(world.position)) and np.all(np.isfinite(world.velocity))
    distance = np.linalg.norm(world.position[1] - world.position[0])
    assert distance >= 2 * RADIUS - 2 * world.slop, "pushed apart to (almost) touching"
    assert np.all(world.velocity == 0), "moved apart by position only: no kinetic energy"


def test_coincident_spawn_direction_is_the_same_for_a_seed_and_differs_between_seeds():
    def direction(seed):
        world = coincident_pair(seed)
        world.step(240)
        d = world.position[1] - world.position[0]
        return d / np.linalg.norm(d)
    assert np.array_equal(direction(1), direction(1))
    assert np.dot(direction(1), direction(2)) < 0.99


def test_centres_made_to_coincide_later_separate_along_the_fallback_normal_plus_y():
    world = physics.World(gravity=(0, 0, 0))
    world.add_sphere((0, 0, 0), radius=RADIUS)
    world.add_sphere((1, 0, 0), radius=RADIUS)
    world.position[1] = world.position[0]           # bypasses the spawn offset
    world.step(240)
    assert np.all(np.isfinite(world.position))
    d = world.position[0] - world.position[1]       # the normal points from b = 1 to a = 0
    assert d / np.linalg.norm(d) == pytest.approx([0, 1, 0], abs=1e-12)


def test_sphere_leaving_the_bounds_is_removed_with_an_event():
    world = physics.World(bounds=((-5, -5, -5), (5, 5, 5)))
    world.add_sphere((0, 0, 0), velocity=(20, 0, 0), radius=RADIUS)
    world.add_sphere((0, 1, 0), radius=RADIUS, mass=3.0)
    trajectory = physics.simulate(world, 1.0)
    (event,) = trajectory.events
    assert event["kind"] == "left-bounds" and event["body"] == 0 and event["other"] == -1
    assert event["time"] == pytest.approx(5 / 20, abs=2 / 240)
    assert not world.active[0] and world.active[1]
    after = trajectory.steps > event["step"]
    assert np.all(trajectory.positions[after, 0] == trajectory.positions[-1, 0]), "frozen"
    # Energy and momentum count the remaining ball only (3 kg, falling).
    assert trajectory.momentum[-1] == pytest.approx(3.0 * world.velocity[1])


def test_trajectory_has_the_documented_shapes_and_records_every_kth_step():
    world = physics.World()
    world.add_plane((0, 1, 0), 0)
    world.add_spheres([(0, 1, 0), (1, 2, 0), (2, 3, 0)], radius=RADIUS)
    trajectory = physics.simulate(world, 1.0, record_every=10)
    t = len(trajectory.times)
    assert trajectory.steps.tolist() == list(range(0, 240, 10)) + [240]
    assert trajectory.times == pytest.approx(trajectory.steps / 240, abs=1e-15)
    for name in ("positions", "velocities", "angular_velocities"):
        assert getattr(trajectory, name).shape == (t, 3, 3)
    assert trajectory.orientations.shape == (t, 3, 4)
    assert trajectory.energy.shape == (t,) and trajectory.momentum.shape == (t, 3)
    assert trajectory.energy[-1] == world.energy()
    assert trajectory.momentum[-1] == pytest.approx(world.momentum(), abs=0)


def test_trajectory_csv_has_one_row_per_record_and_sphere(tmp_path):
    world = physics.World()
    world.add_sphere((0, 1, 0), velocity=(1, 0, 0), radius=RADIUS)
    trajectory = physics.simulate(world, 0.1, record_every=12)
    path = tmp_path / "run.csv"
    trajectory.to_csv(path)
    lines = path.read_text().splitlines()
    assert lines[0].startswith("time,body,x,y,z")
    assert len(lines) == 1 + len(trajectory.times)
    last = [float(v) for v in lines[-1].split(",")]
    assert last[2:5] == trajectory.positions[-1, 0].tolist()
    assert last[11:15] == trajectory.orientations[-1, 0].tolist()      # qw, qx, qy, qz


def test_spinning_ball_orientation_turns_by_omega_t_within_1e_12():
    world = physics.World(gravity=(0, 0, 0))
    world.add_sphere((0, 0, 0), radius=RADIUS, angular_velocity=(0, 0, 2.0))
    world.step(240)                                 # 1 s at 2 rad/s
    expected = np.array([[np.cos(2), -np.sin(2), 0], [np.sin(2), np.cos(2), 0], [0, 0, 1]])
    assert np.abs(rotation_matrices(world.orientation)[0] - expected).max() <= 1e-12


def box_of_balls(solver, dtype=np.float64, count=12, seconds=1.5):
    """Balls of different restitution dropped into a box (floor and four walls), seeded."""
    world = physics.World(solver=solver, dtype=dtype)
    world.add_plane((0, 1, 0), 0, friction=0.4)
    for normal in [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]:
        world.add_plane(normal, -1.0)
    rng = np.random.default_rng(2024)
    world.add_spheres(rng.uniform((-0.8, 0.3, -0.8), (0.8, 2.0, 0.8), size=(count, 3)),
                      velocities=rng.normal(0, 1, size=(count, 3)), radius=RADIUS,
                      restitution=rng.uniform(0.2, 0.9, count), friction=0.4)
    return world, physics.simulate(world, seconds)


def trajectory_digest(trajectory) -> str:
    """sha256 of the positions, velocities and angular velocities, as little-endian bytes."""
    digest = hashlib.sha256()
    for name in ("positions", "velocities", "angular_velocities"):
        digest.update(np.ascontiguousarray(getattr(trajectory, name), "<f8").tobytes())
    return digest.hexdigest()


# The digests of box_of_balls(solver). Any change to the physics changes them; after an
# intentional change, regenerate with
#   .venv/bin/python -c "import tests.physics.test_world as t; print({s: \
#       t.trajectory_digest(t.box_of_balls(s)[1]) for s in ('sequential', 'simultaneous')})"
# and say in the commit message why the trajectories changed.
PINNED_DIGESTS = {
    "sequential": "1d02d1304a4e5cd2bef276bf912162f2ea5006ff25e1d27ddff924484ebc6ef5",
    "simultaneous": "4e3e66206c5bc3f8b74cf9d879b9398d8066a5ee29a84d9c11851e949ea3e715",
}


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_same_scene_stepped_twice_is_bit_identical_and_matches_the_pinned_digest(solver):
    first = trajectory_digest(box_of_balls(solver)[1])
    second = trajectory_digest(box_of_balls(solver)[1])
    assert first == second
    assert first == PINNED_DIGESTS[solver]


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_float32_box_of_balls_runs_in_float32_and_keeps_balls_inside_the_box(solver):
    world, trajectory = box_of_balls(solver, np.float32)
    assert trajectory.positions.dtype == np.float32 and world.velocity.dtype == np.float32
    assert np.all(np.isfinite(trajectory.positions))
    inside = np.abs(trajectory.positions[:, :, [0, 2]]) <= 1.0 - RADIUS + 1e-4
    assert np.all(inside) and np.all(trajectory.positions[:, :, 1] >= RADIUS - 1e-3)
    assert trajectory.energy[-1] < trajectory.energy[0]


def test_float32_single_bounce_tracks_float64_within_1e_4_m():
    def bounce(dtype):
        world = physics.World(dtype=dtype)
        world.add_plane((0, 1, 0), 0)
        world.add_sphere((0, 1.1, 0), velocity=(0.5, 0, 0), radius=RADIUS, restitution=0.6)
        return physics.simulate(world, 2.0).positions
    assert np.abs(bounce(np.float32) - bounce(np.float64)).max() <= 1e-4


@pytest.mark.parametrize("radius, mass", [(1e200, None), (1e-200, None), (1.0, 1e-320)])
def test_a_mass_or_inertia_beyond_the_precision_is_refused_in_one_line(radius, mass):
    """m, I = 2/5 m r^2 and their inverses must be finite, or the solver makes NaNs."""
    world = physics.World()
    with pytest.raises(physics.PhysicsError) as caught:
        world.add_sphere((0, 0, 0), radius=radius, mass=mass, density=None if mass else 1000.0)
    assert "out of range" in str(caught.value) and "\n" not in str(caught.value)
    assert world.count == 0
