"""The swept test of boxes and capsules (physics/solid_sweeps.py): fast solids meet walls, the
floor and other bodies at their time of impact, never pass through them and never bounce
before reaching them."""

import numpy as np
import pytest
from test_shapes import box_shape
from test_solids import assert_resumes_bit_for_bit

import physics
from physics.box_contacts import box_corners, candidate_axes, largest_separation, separations
from physics.quaternions import (quaternion_from_rotation_vector, rotate_orientations,
                                 rotation_matrices, rotation_vector_between)
from physics.solid_sweeps import pair_gaps
from physics.solid_contacts import support_points
from physics.solids import BOX, CAPSULE, SPHERE, capsule_ends

G = 9.81
WALL = 1.0            # the wall's centre (m): a 1 cm slab, its near face at x = 0.995
HALF = 0.1            # the box's half size, the capsule's radius (m)


def thrown_at_the_wall(kind, speed, dtype="float64", spin=(0.0, 0.0, 0.0), dt=1 / 60):
    """A 1 cm wall (an SDF shape, e = 1) and a box or capsule at the origin thrown along +x at
    ``speed``, no gravity, dt = 1/60 s: 3.3 m a step at 200 m/s."""
    world = physics.World(gravity=(0, 0, 0), dt=dt, dtype=dtype)
    world.add_shape(box_shape((WALL, 0, 0), (0.005, 1, 1), restitution=1.0))
    if kind == "box":
        world.add_box((0, 0, 0), (HALF, HALF, HALF), velocity=(speed, 0, 0),
                      angular_velocity=spin, restitution=1.0)
    else:
        world.add_capsule((0, 0, 0), 0.1, HALF, velocity=(speed, 0, 0),
                          angular_velocity=spin, restitution=1.0)
    return world


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize("kind", ["box", "capsule"])
@pytest.mark.parametrize("speed", [20, 50, 200])
def test_a_fast_solid_bounces_off_a_1_cm_wall_on_the_reflected_path(kind, speed, dtype):
    """e = 1: at every step the centre is within 1e-3 m of the exact reflected path
    x(t) = x_touch - |V t - x_touch| (x_touch = 0.895, where its surface meets the wall's
    face). Tunnelling would leave it beyond the wall; a bounce a distance s short of the wall
    would put it 2 s behind the path, so it turns round within 5e-4 m of the wall. It never
    passes x_touch + 1e-3, leaves at 200 m/s (1e-6 relative) and the bounce is an event."""
    world = thrown_at_the_wall(kind, speed, dtype)
    run = physics.simulate(world, 0.3)
    touch = WALL - 0.005 - HALF
    x = run.positions[:, 0, 0].astype(np.float64)
    reflected = touch - np.abs(speed * run.times - touch)
    assert np.max(np.abs(x - reflected)) < 1e-3
    assert np.max(x) <= touch + 1e-3
    assert run.velocities[-1, 0, 0] == pytest.approx(-speed, rel=1e-6)
    assert np.all(run.events["kind"] == f"{kind}-shape")
    assert np.all(run.events["step"] == run.events["step"][0])
    assert run.events["speed"][0] == pytest.approx(speed, rel=1e-6)


@pytest.mark.parametrize("speed", [20, 200])
def test_a_box_spinning_at_50_rad_s_never_passes_into_a_thin_wall_and_bounces_as_at_dt_1_6000(
        speed):
    """Spinning about z, its corners sweep toward the wall as well: no corner is ever more
    than 1e-3 m into the wall at the end of a step, the energy never rises (e = 1 with
    friction: 1e-9 relative), and after 0.2 s it is where a run with steps 100 times shorter
    puts it (0.05 m), moving as fast (2% of its speed) and spinning as fast (5%): the short
    steps meet the wall over several steps, the long ones in one impact. A bounce short of
    the wall would put it up to 1.8 m away."""
    world = thrown_at_the_wall("box", speed, spin=(0, 0, 50))
    energy = world.energy()
    deepest = -np.inf
    for _ in range(12):
        world.step()
        corners = box_corners(world.position[0], rotation_matrices(world.orientation)[0],
                              world.extent[0])
        deepest = max(deepest, np.max(corners[:, 0]))
        assert world.energy() <= energy * (1 + 1e-9)
    assert deepest <= WALL - 0.005 + 1e-3
    fine = thrown_at_the_wall("box", speed, spin=(0, 0, 50), dt=1 / 6000)
    fine.step(1200)
    assert np.linalg.norm(world.position[0] - fine.position[0]) < 0.05
    speed_now = np.linalg.norm(fine.velocity[0])
    assert np.linalg.norm(world.velocity[0] - fine.velocity[0]) < 0.02 * speed_now
    spin_now = np.linalg.norm(fine.angular_velocity[0])
    assert np.linalg.norm(world.angular_velocity[0] - fine.angular_velocity[0]) < 0.05 * spin_now


def falling_box(restitution, dt=1 / 60):
    """A box thrown down at 30 m/s from 20 m onto the floor plane y = 0: it arrives at about
    36 m/s, 0.6 m a step at dt = 1/60 s."""
    world = physics.World(dt=dt)
    world.add_plane((0, 1, 0), 0.0, restitution=restitution)
    world.add_box((0, 20, 0), (0.2, 0.1, 0.15), velocity=(0, -30, 0),
                  restitution=restitution)
    return world


def lowest_corner(run, world):
    """The height (R,) of the lowest corner of box 0 at each record."""
    return np.array([np.min(box_corners(x, rotation_matrices(q[None])[0], world.extent[0])[:, 1])
                     for x, q in zip(run.positions[:, 0], run.orientations[:, 0])])


@pytest.mark.parametrize("dt", [1 / 60, 1 / 240])
def test_a_box_falling_fast_onto_the_floor_lands_without_sinking_or_bouncing(dt):
    """e = 0: no corner ever goes below the floor by more than the slop (1e-4 m); once it
    has landed (the first event) it never rises more than the slop, and it ends at rest."""
    world = falling_box(0.0, dt)
    run = physics.simulate(world, 2.0)
    assert np.min(lowest_corner(run, world)) >= -world.slop
    landed = int(np.searchsorted(run.times, run.events["time"][0]))
    assert np.max(run.positions[landed:, 0, 1]) <= 0.1 + world.slop
    assert np.abs(run.velocities[-1, 0]).max() < 1e-6


@pytest.mark.parametrize("dt", [1 / 60, 1 / 240])
def test_a_box_falling_fast_bounces_to_the_height_e_allows(dt):
    """e = 0.5: it leaves the floor at e times its arrival speed v (the event's), so it rises
    (e v)^2 / (2 g) above its resting height: never more than that plus the slop (the sweep
    meets the floor 0.5 to 1 slop above it), and at most 1e-3 relative less (the apex falls
    between two records). A bounce above the floor, before reaching it, would add that height
    to the rise."""
    world = falling_box(0.5, dt)
    run = physics.simulate(world, 2.5)
    assert np.min(lowest_corner(run, world)) >= -world.slop
    first = run.events[0]
    assert first["kind"] == "box-plane"
    after = int(np.searchsorted(run.times, first["time"]))
    rise = np.max(run.positions[after:, 0, 1]) - 0.1
    allowed = (0.5 * first["speed"]) ** 2 / (2 * G)
    assert allowed * (1 - 1e-3) <= rise <= allowed + world.slop


def test_a_box_at_200_m_s_neither_passes_through_nor_bounces_short_of_a_thin_box():
    """No gravity, e = 1, equal masses, a 1 kg box at 200 m/s at a resting 2 cm thick one:
    their centres are never closer than touching (0.2 m) less the slop nor, at the closest,
    farther than touching plus 1e-3 m, and they exchange velocities (the 1-D elastic answer,
    to 1e-5 relative: the solver's restitution passes over four corners)."""
    world = physics.World(gravity=(0, 0, 0), dt=1 / 60)
    world.add_box((0, 0, 0), (HALF, HALF, HALF), velocity=(200, 0, 0), restitution=1.0)
    world.add_box((1.0, 0, 0), (HALF, 0.01, HALF), mass=1.0, restitution=1.0)
    run = physics.simulate(world, 0.3)
    apart = run.positions[:, 1, 0] - run.positions[:, 0, 0]
    assert 0.2 - world.slop <= np.min(apart) <= 0.2 + 1e-3
    assert np.allclose(run.velocities[-1, :, 0], [0, 200], rtol=0, atol=1e-5 * 200)


def test_a_ball_at_200_m_s_neither_passes_through_nor_bounces_short_of_a_thin_capsule():
    """The same with a ball of radius 0.1 m and a capsule of radius 5 mm lying across its
    path: exact distances, so the exchange is exact to 1e-9 relative."""
    world = physics.World(gravity=(0, 0, 0), dt=1 / 60)
    world.add_sphere((0, 0, 0), velocity=(200, 0, 0), radius=HALF, mass=1.0, restitution=1.0)
    world.add_capsule((1.0, 0, 0), 0.1, 0.005, mass=1.0, restitution=1.0)
    run = physics.simulate(world, 0.3)
    apart = run.positions[:, 1, 0] - run.positions[:, 0, 0]
    assert 0.105 - world.slop <= np.min(apart) <= 0.105 + 1e-3
    assert np.allclose(run.velocities[-1, :, 0], [0, 200], rtol=0, atol=1e-9 * 200)
    assert run.events["kind"][0] == "sphere-capsule"


def test_a_resumed_run_with_fast_boxes_in_a_container_is_bit_identical(tmp_path):
    """Boxes and a capsule thrown about a container at up to 33 m/s (swept every step they
    fly): no sample of their surfaces ever ends a step more than 1e-3 m into its walls, and,
    saved and loaded mid-run, the run goes on bit for bit as the uninterrupted one."""
    def build():
        world = physics.World(dt=1 / 120)
        world.add_shape(box_shape((0, 0.5, 0), (1, 0.6, 1), restitution=0.8,
                                  hollow=((0, 1.2, 0), (0.9, 0.6, 0.9))))
        world.add_box((0, 0.8, 0), (0.1, 0.05, 0.08), velocity=(30, 5, 12),
                      angular_velocity=(3, 20, -7), restitution=0.8)
        world.add_box((0.4, 0.8, 0.3), (0.1, 0.1, 0.1), velocity=(-20, 2, 25), restitution=0.8)
        world.add_capsule((-0.4, 0.9, -0.3), 0.1, 0.05, velocity=(25, -10, -20),
                          restitution=0.8)
        return world
    straight = build()
    container = straight.shapes[0]
    for _ in range(120):
        straight.step()
        body, point, radius, _ = support_points(straight, np.arange(3), "surface")
        assert np.min(container.distance(point) - radius) >= -1e-3
    assert any(kind.endswith("-shape") for kind in straight.events["kind"])
    assert_resumes_bit_for_bit(build, straight, 60, tmp_path)


# --- the parts -------------------------------------------------------------------------------

def test_rotation_vector_between_undoes_rotate_orientations_within_1e_12():
    """Random orientations and turns up to (but short of) pi: exp(r) q turned back gives r."""
    rng = np.random.default_rng(3)
    q = quaternion_from_rotation_vector(rng.uniform(-3, 3, (200, 3)))
    turn = rng.normal(size=(200, 3))
    turn *= (rng.uniform(0, 3.1, 200) / np.linalg.norm(turn, axis=1))[:, None]
    turn[:3] = [[0, 0, 0], [1e-9, 0, 0], [0, 0, -1e-12]]
    found = rotation_vector_between(q, rotate_orientations(q, turn))
    assert np.allclose(found, turn, rtol=0, atol=1e-12)


def surface_samples(kind, x, q, extent, count=15):
    """Points (M, 3) on the surface of a body (a grid on each face of a box) or on its core
    (the segment of a capsule, the centre of a sphere: the distance to them less the radius is
    the surface's), and how far (m) any point of it can be from the nearest of them."""
    if kind == BOX:
        t = np.linspace(-1, 1, count)
        grid = np.stack(np.meshgrid(t, t, indexing="ij"), axis=-1).reshape(-1, 2)
        faces = [np.insert(grid, axis, side, axis=1) * extent
                 for axis in range(3) for side in (-1.0, 1.0)]
        spacing = 2 * extent / (count - 1)
        return (x + np.concatenate(faces) @ rotation_matrices(q[None])[0].T,
                0.5 * np.sqrt(spacing @ spacing))
    if kind == CAPSULE:
        start, end = capsule_ends(x[None], q[None], extent[None])
        return (start + np.linspace(0, 1, count)[:, None] * (end - start),
                extent[1] / (count - 1))
    return x[None], 0.0


@pytest.mark.parametrize("kinds", [(SPHERE, BOX), (SPHERE, CAPSULE), (CAPSULE, CAPSULE),
                                   (CAPSULE, BOX), (BOX, CAPSULE), (BOX, BOX)])
def test_pair_gaps_are_lower_bounds_of_the_distance_and_tight_where_exact(kinds):
    """50 random placements of two bodies apart: the gap never exceeds the distance D between
    points sampled densely on both surfaces (1e-9; the advancement needs a lower bound), and
    for every kind but box-box is no less than D less the samples' spacing (D overestimates
    the true distance by at most that). Box-box's separating-axis gap can be less than the
    distance, but is positive whenever the boxes are apart."""
    rng = np.random.default_rng(11)
    radius = {SPHERE: 0.1, CAPSULE: 0.05, BOX: 0.0}
    extent = {SPHERE: np.zeros(3), CAPSULE: np.array([0, 0.2, 0]),
              BOX: np.array([0.1, 0.2, 0.15])}
    world = physics.World()
    for kind in kinds:
        if kind == SPHERE:
            world.add_sphere((0, 0, 0), radius=radius[kind])
        elif kind == BOX:
            world.add_box((0, 0, 0), extent[kind])
        else:
            world.add_capsule((0, 0, 0), extent[kind][1], radius[kind])
    checked = 0
    while checked < 50:
        x = rng.uniform(-0.5, 0.5, (2, 3))
        q = quaternion_from_rotation_vector(rng.uniform(-3, 3, (2, 3)))
        (p0, e0), (p1, e1) = [surface_samples(k, x[i], q[i], extent[k])
                              for i, k in enumerate(kinds)]
        sampled = np.min(np.linalg.norm(p0[:, None] - p1[None], axis=2))
        sampled -= radius[kinds[0]] + radius[kinds[1]]
        if sampled <= e0 + e1:
            continue                 # touching or overlapping, as far as the samples tell
        checked += 1
        gap = pair_gaps(world, np.array([0]), np.array([1]), x[:1], q[:1], x[1:], q[1:])[0]
        assert gap <= sampled + 1e-9
        if kinds == (BOX, BOX):
            assert gap > 0
        else:
            assert gap >= sampled - (e0 + e1) - 1e-9


def test_largest_separation_of_k_pairs_at_once_is_that_of_each_pair_within_1e_12():
    """The stacked separating-axis gaps the sweep advances by are box_contacts' own, pair by
    pair (200 random pairs, some with parallel edges)."""
    rng = np.random.default_rng(5)
    k = 200
    centre_a, centre_b = rng.uniform(-1, 1, (k, 3)), rng.uniform(-1, 1, (k, 3))
    half_a, half_b = rng.uniform(0.05, 0.5, (k, 3)), rng.uniform(0.05, 0.5, (k, 3))
    turn_a = rng.uniform(-3, 3, (k, 3))
    turn_b = np.where(np.arange(k)[:, None] % 4 == 0, turn_a, rng.uniform(-3, 3, (k, 3)))
    rotation_a = rotation_matrices(quaternion_from_rotation_vector(turn_a))
    rotation_b = rotation_matrices(quaternion_from_rotation_vector(turn_b))
    stacked = largest_separation(centre_a, rotation_a, half_a, centre_b, rotation_b, half_b)
    for m in range(k):
        axes, usable = candidate_axes(rotation_a[m], rotation_b[m])
        each = separations(axes, centre_a[m], rotation_a[m], half_a[m], centre_b[m],
                           rotation_b[m], half_b[m])
        assert stacked[m] == pytest.approx(np.max(np.where(usable, each, -np.inf)), abs=1e-12)


@pytest.mark.parametrize("restitution", [0.0, 0.5])
def test_two_stacked_boxes_landing_fast_sink_into_neither_the_floor_nor_each_other(restitution):
    """A box riding on another, both thrown down at 30 m/s from 20 m (dt = 1/60 s): the lower
    meets the floor first, and the upper must then meet the lower, not pass through it to the
    floor. Over 3 s no corner goes below the floor by more than two slops (the resting stack's
    own depth under the solver), the boxes never overlap by more than 1e-3 m (their
    separating-axis gap), and the energy never rises (1e-9 relative)."""
    world = physics.World(dt=1 / 60)
    world.add_plane((0, 1, 0), 0.0, restitution=restitution)
    for height in (20.0, 20.2):
        world.add_box((0.1 * (height - 20), height, 0), (0.2, 0.1, 0.15),
                      velocity=(0, -30, 0), restitution=restitution)
    energy = world.energy()
    lowest, closest = np.inf, np.inf
    for _ in range(180):
        world.step()
        for body in range(2):
            corners = box_corners(world.position[body],
                                  rotation_matrices(world.orientation[body:body + 1])[0],
                                  world.extent[body])
            lowest = min(lowest, np.min(corners[:, 1]))
        closest = min(closest, pair_gaps(world, np.array([0]), np.array([1]),
                                         world.position[:1], world.orientation[:1],
                                         world.position[1:], world.orientation[1:])[0])
        assert world.energy() <= energy * (1 + 1e-9)
    assert lowest >= -2 * world.slop
    assert closest >= -1e-3
