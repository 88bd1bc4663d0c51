"""Crowds: spheres spawned at one point, or piled into each other, cost bounded work per step.

N spheres at one point all overlap one another: N(N-1)/2 true contacts, 499,500 for 1,000.
The step bounds its work instead (physics/broadphase.py): a grid cell holding more bodies than
can fit in it without touching is crowded, and inside a crowd each sphere is paired with its
CROWD_WINDOW successors along a Morton curve, so a find_pairs call examines at most
CROWD_WINDOW pairs per sphere there. The work is checked by counting it (``world.work``), never
by timing. Outside crowds the pairs stay exactly the brute-force ones.
"""

from collections import Counter

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import physics
from physics.broadphase import CROWD_WINDOW, brute_force_pairs, grid_pairs
from physics.crowds import cell_capacity

RADIUS = 0.05


def spawned_at_one_point(count, solver="sequential", gravity=(0.0, -9.81, 0.0)):
    world = physics.World(solver=solver, gravity=gravity)
    world.add_plane((0, 1, 0), 0)
    world.add_spheres(np.zeros((count, 3)) + (0, 1, 0), radius=RADIUS)
    return world


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_1000_spheres_spawned_at_one_point_step_in_bounded_work(solver):
    world = spawned_at_one_point(1000, solver)
    world.step(1)
    work = world.work
    # Two broad-phase calls a step (contacts, swept test), each at most W pairs per sphere:
    # 24,000 pairs instead of the 999,000 that testing every pair twice would take.
    assert 0 < work["pairs examined"] <= 2 * CROWD_WINDOW * 1000
    assert work["contacts"] <= CROWD_WINDOW * 1000 + 1000          # + one floor each
    assert work["collision sweeps"] <= world.iterations
    assert work["resting passes"] <= world.iterations
    assert work["push-out passes"] == 1
    assert work["solver levels"] <= work["contacts"]
    assert np.all(np.isfinite(world.position)) and np.all(np.isfinite(world.velocity))


def test_10000_spheres_spawned_at_one_point_examine_about_ten_times_the_pairs_of_1000():
    """Linear, not quadratic: 10x the spheres, 10x the pairs (all pairs would be 100x)."""
    examined = {}
    for count in (1000, 10000):
        world = spawned_at_one_point(count, "simultaneous")
        world.step(1)
        examined[count] = world.work["pairs examined"]
        assert examined[count] <= 2 * CROWD_WINDOW * count
        assert world.work["contacts"] <= (CROWD_WINDOW + 1) * count
    assert examined[10000] / examined[1000] == pytest.approx(10, rel=0.01)


def test_a_crowd_in_zero_gravity_spreads_by_position_only_and_deterministically():
    """200 spheres at one point, no gravity: push-out moves them apart, never giving them speed,
    the deepest overlap shrinks from nearly a diameter, and two runs agree bit for bit."""
    def spread(steps):
        world = spawned_at_one_point(200, "simultaneous", gravity=(0, 0, 0))
        world.step(steps)
        return world
    assert spread(1).work["pairs examined"] <= 2 * CROWD_WINDOW * 200   # not 2 x 19,900
    world = spread(200)
    assert np.all(world.velocity == 0) and np.all(world.angular_velocity == 0)
    i, j = brute_force_pairs(world.position, world.radius)
    deepest = np.max(2 * RADIUS - np.linalg.norm(world.position[i] - world.position[j], axis=1))
    assert deepest < 0.7 * 2 * RADIUS, f"deepest overlap {deepest:.4f} m after 200 steps"
    assert np.array_equal(spread(200).position, world.position)


def test_cell_capacity_is_15_for_equal_spheres_and_grows_for_smaller_ones():
    """(2 rho + 2 rho)^3 / (4/3 pi rho^3) = 48 / pi = 15.3: no 16 equal spheres fit in a cell."""
    assert cell_capacity(2.0, np.array([1.0]))[0] == 15
    assert cell_capacity(2.0, np.array([0.5]))[0] == np.floor(27 / (np.pi / 6))


def test_grid_pairs_with_a_crowd_window_are_exact_where_no_cell_is_crowded():
    rng = np.random.default_rng(7)
    centre = rng.uniform(0, 3, size=(2000, 3))
    reach = rng.uniform(0.05, 0.12, size=2000)
    i, j = grid_pairs(centre, reach, crowd_window=CROWD_WINDOW)
    expected_i, expected_j = brute_force_pairs(centre, reach)
    assert len(i) > 1000
    assert np.array_equal(i, expected_i) and np.array_equal(j, expected_j)


@st.composite
def crowds(draw):
    """A cloud (up to 300 spheres) with a crowd of up to 200 at one point or in a small ball."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    sparse = draw(st.integers(0, 100))
    crowd = draw(st.integers(20, 200))
    spread = draw(st.sampled_from([0.0, 0.02, 0.1]))
    centre = np.concatenate([rng.uniform(-2, 2, size=(sparse, 3)),
                             rng.normal(0, spread, size=(crowd, 3)) + rng.uniform(-1, 1, 3)])
    reach = RADIUS * rng.uniform(1.0, draw(st.sampled_from([1.0, 2.0])), size=len(centre))
    return centre[rng.permutation(len(centre))], reach


@given(crowds())
def test_pairs_in_a_crowd_are_true_pairs_and_at_most_the_window_per_sphere(cloud):
    centre, reach = cloud
    counter = Counter()
    i, j = grid_pairs(centre, reach, crowd_window=CROWD_WINDOW, counter=counter)
    key = set(zip(i.tolist(), j.tolist()))
    expected = set(zip(*(part.tolist() for part in brute_force_pairs(centre, reach))))
    assert key <= expected, "every pair found really touches"
    assert np.all(i < j) and len(key) == len(i), "each pair once, i < j"
    # W pairs per crowded sphere; outside crowds a cell holds at most cell_capacity bodies (15
    # equal spheres, 51 when the smallest is half the largest) and the grid pairs a sphere
    # with the bodies of 14 cells (the other 13 neighbours pair with it from their side).
    largest_capacity = cell_capacity(2 * reach.max(), np.array([reach.min()]))[0]
    assert counter["pairs examined"] <= len(centre) * (CROWD_WINDOW + 14 * largest_capacity)
