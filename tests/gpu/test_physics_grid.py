"""The GPU step's broad phase (gpu_shader/glsl/physics_grid.glsl) finds exactly the pairs that
testing every pair finds, and the contact limit still stops a crowd.

The pair tests step the same float32 world twice, once through the grid and once with
``GpuStepper(all_pairs=True)``, the textbook loop over every other sphere, and compare what
the step found: each sphere's contact list (`GpuStepper.contact_lists`) and the positions
after the sweep test. (tests/equivalence/test_physics_grid_equivalence.py compares whole steps
of a pile.) The clouds mix sizes (radii 1.5 cm to 16 cm), straddle the origin, and put
centres exactly on cell boundaries and pairs exactly at the edge of a contact, where a
rounding in the grid would lose a neighbour. The contact lists are also checked against a
NumPy brute force in float32, away from that edge (gap within 1e-6 m of the slop), where a
GPU may round the other way.
"""

from __future__ import annotations

import numpy as np
import pytest

import physics
from physics.errors import PhysicsError

RADII = (0.015, 0.16)                   # m: a factor of ten between the smallest and largest
EDGE = 1e-6                             # m: pairs this near the slop are left to the GPU
SLOP = physics.World().slop
CELL = float(np.float32(2 * RADII[1] + SLOP))    # the GPU grid's cell (physics.cell_size)


@pytest.fixture(autouse=True)
def _needs_gpu(gpu):
    pass


def stepper(world, all_pairs=False):
    from gpu_shader.physics import GpuStepper            # needs moderngl
    return GpuStepper(world, all_pairs=all_pairs)


def cloud(rng, count: int, side: float):
    """Centres (count, 3) in a cube of ``side`` around (-0.4, -0.3, -0.2) m and log-uniform radii
    (count,), a tenth of the centres moved onto a cell boundary of the GPU's grid in x, y or z
    (negative coordinates too)."""
    radius = np.exp(rng.uniform(*np.log(RADII), count))
    centre = rng.uniform(-side / 2, side / 2, (count, 3)) + (-0.4, -0.3, -0.2)
    for k in range(0, count, 10):
        axis = rng.integers(3)
        centre[k, axis] = CELL * np.round(centre[k, axis] / CELL)
    return centre, radius


def world_of(centre, radius, velocity=None, dt=1 / 240) -> physics.World:
    world = physics.World(dt=dt, gravity=(0, 0, 0), solver="simultaneous", dtype="float32")
    world.add_spheres(centre, velocities=velocity, radius=radius, restitution=0.5,
                      friction=0.3)
    return world


def mixed_cloud(seed: int, count: int = 700) -> physics.World:
    """A resting `cloud` (no gravity, no planes), about 2 contacts a sphere (7 for the
    largest). A third of the spheres are placed next to another, half of them touching (gap 0)
    and half exactly at the slop (gap = slop: the edge of a contact), some across a cell
    boundary."""
    rng = np.random.default_rng(seed)
    centre, radius = cloud(rng, count, 0.19 * count ** (1 / 3))
    for k in range(0, count // 3, 2):
        direction = rng.normal(size=3)
        if k % 10 == 0:                           # across the cell boundary that k is on
            on_boundary = np.argmin(np.abs(centre[k] / CELL - np.round(centre[k] / CELL)))
            direction = np.eye(3)[on_boundary] * rng.choice([-1.0, 1.0])
        distance = radius[k] + radius[k + 1] + (SLOP if k % 4 == 0 else 0.0)
        centre[k + 1] = centre[k] + distance * direction / np.linalg.norm(direction)
    return world_of(centre, radius)


def flying_cloud(seed: int, count: int = 600, speed: float = 6.0) -> physics.World:
    """A `cloud` with no two spheres within 1 mm (no contacts), flying in random directions
    (``speed`` m/s per axis) at dt = 1/60 s: many pairs would pass into each other within the
    step, and only the sweep test stops them."""
    rng = np.random.default_rng(seed)
    centre, radius = cloud(rng, count, 0.19 * count ** (1 / 3))
    keep = []
    for k in range(count):
        gap = np.linalg.norm(centre[keep] - centre[k], axis=1) - radius[keep] - radius[k]
        if np.all(gap > 1e-3):
            keep.append(k)
    velocity = rng.normal(size=(len(keep), 3)) * speed
    return world_of(centre[keep], radius[keep], velocity, dt=1 / 60)


def numpy_contact_lists(position, radius, slop):
    """For each sphere, the others with |x_a - x_b| - (r_a + r_b) <= slop, in float32 and in
    the shader's order of operations; and for each, those within EDGE of the slop."""
    x, r = position.astype(np.float32), radius.astype(np.float32)
    d = x[:, None, :] - x[None, :, :]
    distance = np.sqrt((d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) + d[..., 2] * d[..., 2])
    gap = distance - (r[:, None] + r[None, :])
    np.fill_diagonal(gap, np.inf)
    near = gap <= np.float32(slop)
    edge = np.abs(gap.astype(np.float64) - slop) <= EDGE
    return ([np.flatnonzero(row) for row in near], [np.flatnonzero(row) for row in edge])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_grid_contact_lists_equal_every_pair_and_numpy_brute_force(seed):
    world = mixed_cloud(seed)
    start = world.position.copy()
    lists = {}
    for all_pairs in (False, True):
        gpu = stepper(world.copy(), all_pairs)
        gpu(1)
        lists[all_pairs] = gpu.contact_lists()
    grid, every = lists[False], lists[True]
    assert sum(map(len, grid)) > len(grid), "the cloud must have contacts to compare"
    for i in range(len(grid)):
        np.testing.assert_array_equal(grid[i], every[i], err_msg=f"sphere {i}")
        # the order of the sums: the spheres of higher index, then those of lower, by index
        summed = np.concatenate([np.sort(grid[i][grid[i] > i]), np.sort(grid[i][grid[i] < i])])
        np.testing.assert_array_equal(grid[i], summed, err_msg=f"sphere {i}: list order")
    expected, edge = numpy_contact_lists(start, world.radius, world.slop)
    for i in range(len(grid)):
        differ = np.setxor1d(grid[i], expected[i])
        assert np.isin(differ, edge[i]).all(), (f"sphere {i}: the GPU and NumPy disagree on "
                                                f"{differ} away from the slop")


def test_grid_meets_fewer_than_a_tenth_of_the_candidates_of_every_pair():
    # the property the grid exists for; also shows the walks did use the grid (a walk that
    # falls back to every body would make the equality tests above trivially true)
    world = mixed_cloud(0)
    counts = {}
    for all_pairs in (False, True):
        gpu = stepper(world.copy(), all_pairs)
        gpu(1)
        counts[all_pairs] = gpu.candidates()
    n = world.count
    assert counts[True] == 2 * n * n                     # contacts and sweeps: N each
    assert counts[False] < 0.1 * counts[True]


@pytest.mark.parametrize("bullet", [False, True], ids=["fast", "fast_and_a_bullet"])
def test_grid_sweep_test_stops_the_same_spheres_as_every_pair(bullet):
    # At about 10 m/s and dt = 1/60 s spheres move 17 cm a step, more than most radii: many
    # would pass into each other. A bullet at 1 km/s (17 m a step) widens every walk past N
    # cells, so every sphere falls back to the loop over all of them: the same answer again.
    world = flying_cloud(3)
    if bullet:
        world.velocity[0] = (1000.0, 0.0, 0.0)
    free = world.position + world.dt * world.velocity     # where no sweep stopped them
    ends = {}
    for all_pairs in (False, True):
        copy = world.copy()
        stepper(copy, all_pairs)(1)
        ends[all_pairs] = copy.position
    np.testing.assert_array_equal(ends[False], ends[True])
    stopped = np.abs(ends[False] - free).max(axis=1) > 1e-6
    assert stopped.sum() >= 20, "the sweep test must stop spheres for this test to mean much"
    cpu = world.copy()
    cpu.step(1)
    assert np.abs(ends[False] - cpu.position).max() <= 1e-5      # the CPU's sweeps, too


def fibonacci_directions(count: int) -> np.ndarray:
    """``count`` unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    polar = np.arccos(1 - 2 * k / count)
    azimuth = np.pi * (1 + 5 ** 0.5) * k
    return np.stack([np.cos(azimuth) * np.sin(polar), np.cos(polar),
                     np.sin(azimuth) * np.sin(polar)], axis=1)


@pytest.mark.parametrize("small", [24, 25])
def test_contact_limit_refuses_the_25th_contact_of_a_sphere_not_the_24th(small):
    from gpu_shader.physics import MAX_CONTACTS
    world = physics.World(gravity=(0, 0, 0), solver="simultaneous", dtype="float32")
    world.add_sphere((-3.0, 2.0, 1.0), radius=1.0)
    # small balls resting on the big one, none touching another
    world.add_spheres((-3.0, 2.0, 1.0) + 1.02 * fibonacci_directions(small), radius=0.02)
    gpu = stepper(world)
    if small <= MAX_CONTACTS:
        gpu(2)
        assert len(gpu.contact_lists()[0]) == small
    else:
        with pytest.raises(PhysicsError, match=f"more than {MAX_CONTACTS} contacts"):
            gpu(2)


def test_a_crowd_spawned_at_one_point_is_refused_in_one_line():
    world = physics.World(solver="simultaneous", dtype="float32")
    world.add_plane((0, 1, 0), 0)
    world.add_spheres(np.zeros((200, 3)) + (0, 1, 0), radius=0.05)
    with pytest.raises(PhysicsError, match="more than 24 contacts") as error:
        stepper(world)(1)
    assert "\n" not in str(error.value)


def grid_slot(cell, table_size: int) -> int:
    """The slot of ``cell`` (3 ints) in the GPU grid's hash table, as glsl/physics_grid.glsl's
    grid_slot computes it in uint32: x plus a hash of y and z."""
    x, y, z = (int(c) & 0xFFFFFFFF for c in cell)
    row = ((y * 19349663) & 0xFFFFFFFF) ^ ((z * 83492791) & 0xFFFFFFFF)
    return (x + row) & (table_size - 1)


def test_a_row_of_cells_whose_slots_wrap_past_the_table_end_still_meets_its_neighbour():
    # A row of cells fills consecutive slots, so a walk reads one run of entries per row; where
    # the run passes the table's last slot it goes on from slot 0. Two touching spheres in
    # neighbouring cells of the row y = z = 0, one in the table's last slot and the other in
    # slot 0: each is met only through that second part of the run.
    from gpu_shader.physics import cell_size, grid_sizes
    radius = 0.05
    far = [(0.0, 1.0 + 0.2 * k, 0.0) for k in range(38)]       # a column, none touching
    world = world_of(np.array(far + [(0.0, 0.0, 0.0)] * 2), np.full(40, radius))
    table, _ = grid_sizes(world.count)
    cell = np.float32(cell_size(world))
    x_a = float(table * cell) - 0.02                  # in cell table - 1: the last slot
    world.position[38] = (x_a, float(cell) / 2, float(cell) / 2)
    world.position[39] = (x_a + 2 * radius, float(cell) / 2, float(cell) / 2)   # touching
    cells = np.floor(world.position[38:].astype(np.float32) / cell).astype(int)
    assert [grid_slot(c, table) for c in cells] == [table - 1, 0]
    assert world.count >= 27        # so that the walks use the grid, not every body
    lists = {}
    for all_pairs in (False, True):
        gpu = stepper(world.copy(), all_pairs)
        gpu(1)
        lists[all_pairs] = gpu.contact_lists()
    assert list(lists[False][38]) == [39] and list(lists[False][39]) == [38]
    for grid, every in zip(lists[False], lists[True]):
        np.testing.assert_array_equal(grid, every)


def test_a_row_longer_than_the_table_keeps_its_far_cells_apart():
    # Along x the slots repeat every table-size cells, so in a row longer than that, cells far
    # apart share slots: a walk must keep only the cells of its own stretch. 300 touching pairs
    # 2 m apart on one row span about 6,000 cells, with a table of 2,048 slots.
    from gpu_shader.physics import cell_size, grid_sizes
    radius = 0.05
    x = np.repeat(np.arange(300) * 2.0, 2) + np.tile([0.0, 2 * radius], 300)
    centre = np.stack([x, np.full(600, 0.02), np.full(600, 0.02)], axis=1)
    world = world_of(centre, np.full(600, radius))
    table, _ = grid_sizes(world.count)
    span = (x.max() - x.min()) / float(np.float32(cell_size(world)))
    assert span > 2 * table
    lists, met = {}, {}
    for all_pairs in (False, True):
        gpu = stepper(world.copy(), all_pairs)
        gpu(1)
        lists[all_pairs], met[all_pairs] = gpu.contact_lists(), gpu.candidates()
    for i, (grid, every) in enumerate(zip(lists[False], lists[True])):
        np.testing.assert_array_equal(grid, every)
        assert list(grid) == [i ^ 1], f"sphere {i} touches its partner only"
    # Each of a sphere's two walks (contacts, sweep test) meets itself and its partner, and
    # none of the bodies whose cells share the slots of its stretch 2,048 cells away: those
    # the exact tests would turn down too, so only the count of bodies met tells.
    assert met[False] == 4 * world.count
