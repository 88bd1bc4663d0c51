"""The broad phase finds exactly the pairs that checking every pair finds, and contacts come out
in the same fixed order whichever way the pairs were found, and a neighbour list kept from
step to step finds them too."""

from collections import Counter

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import physics
from physics.broadphase import NeighbourList, brute_force_pairs, find_pairs, grid_pairs
from physics.contacts import find_contacts


@st.composite
def sphere_clouds(draw):
    """Up to 80 spheres in a box whose size, crowding and size spread vary (seeded RNG)."""
    n = draw(st.integers(0, 80))
    seed = draw(st.integers(0, 2**32 - 1))
    side = draw(st.floats(0.05, 20.0))
    smallest = draw(st.floats(1e-3, 1.0))
    spread = draw(st.sampled_from([1.0, 2.0, 10.0, 100.0]))     # 100: a few boulders
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-side, side, size=(n, 3))
    reach = smallest * rng.uniform(1.0, spread, size=n)
    if n >= 2 and draw(st.booleans()):
        centre[1] = centre[0]                                     # a coincident pair
    return centre, reach


@given(sphere_clouds())
def test_grid_pairs_equal_brute_force_pairs_exactly(cloud):
    centre, reach = cloud
    i, j = grid_pairs(centre, reach)
    expected_i, expected_j = brute_force_pairs(centre, reach)
    assert np.array_equal(i, expected_i) and np.array_equal(j, expected_j)
    found_i, found_j = find_pairs(centre, reach)
    assert np.array_equal(found_i, expected_i) and np.array_equal(found_j, expected_j)


def test_grid_pairs_equal_brute_force_for_2000_packed_spheres():
    rng = np.random.default_rng(7)
    centre = rng.uniform(0, 3, size=(2000, 3))
    reach = rng.uniform(0.05, 0.12, size=2000)
    i, j = grid_pairs(centre, reach)
    expected_i, expected_j = brute_force_pairs(centre, reach)
    assert len(i) > 1000
    assert np.array_equal(i, expected_i) and np.array_equal(j, expected_j)


def test_contacts_of_200_spheres_match_an_all_pairs_check_in_the_same_order():
    world = physics.World()
    world.add_plane((0, 1, 0), 0)
    rng = np.random.default_rng(3)
    world.add_spheres(rng.uniform(0, 1.5, size=(200, 3)), radius=rng.uniform(0.05, 0.1, 200))
    contacts = find_contacts(world, world.slop)
    pairs = contacts.plane < 0
    x, r = world.position, world.radius
    i, j = np.triu_indices(200, k=1)
    gap = np.sqrt(np.sum((x[i] - x[j]) ** 2, axis=1)) - r[i] - r[j]
    close = gap <= world.slop
    assert np.array_equal(contacts.a[pairs], i[close])
    assert np.array_equal(contacts.b[pairs], j[close])
    below = np.flatnonzero(x[:, 1] - r <= world.slop)
    assert np.array_equal(contacts.a[~pairs], below)


def test_half_the_spheres_ten_times_larger_are_paired_exactly_from_a_linear_count_of_candidates():
    """Many large spheres among small ones: each size class has its own grid (a hierarchical
    grid), so 4,000 spheres, half of them 10x larger, need a few hundred candidates, not
    the 6 million that testing each large one against everyone took."""
    rng = np.random.default_rng(11)
    centre = rng.uniform(0, 60, size=(4000, 3))
    reach = np.where(rng.permutation(4000) < 2001, 0.05, 0.5)
    counter = Counter()
    i, j = grid_pairs(centre, reach, counter=counter)
    expected_i, expected_j = brute_force_pairs(centre, reach)
    assert len(i) > 10
    assert np.array_equal(i, expected_i) and np.array_equal(j, expected_j)
    assert counter["pairs examined"] <= len(centre)


@given(st.integers(2, 120), st.integers(0, 2**32 - 1), st.sampled_from(["float64", "float32"]),
       st.floats(1e-3, 1e3))
def test_a_kept_neighbour_list_finds_the_brute_force_pairs_exactly_at_every_step(n, seed, dtype,
                                                                                 scale):
    """A crowd (each body within reach of a few others) of any size and scale that moves a
    little each step (the list is kept), sometimes jumps (it is made again), loses a body,
    grows its reaches and meets a NaN centre and an infinite reach: every answer is brute
    force's, pair for pair and in order."""
    rng = np.random.default_rng(seed)
    side = scale * (n / 4) ** (1 / 3) * 2.5          # about 4 neighbours within 2 reaches
    centre = rng.uniform(0, side, (n, 3)).astype(dtype)
    reach = (scale * rng.uniform(0.5, 1.0, n)).astype(dtype)
    neighbours = NeighbourList()
    bodies = np.arange(n)
    kept = 0
    for step in range(24):
        if step == 12:
            bodies, centre, reach = bodies[1:], centre[1:], reach[1:]      # one body gone
        if step == 20:
            centre[0, 0] = np.nan
        if step == 22:
            reach = reach.copy()
            reach[-1] = np.inf
        before = neighbours._pairs
        found = neighbours.pairs(centre, reach, bodies=bodies)
        kept += before is not None and neighbours._pairs is before
        expected = brute_force_pairs(centre, reach)
        assert all(np.array_equal(f, e) for f, e in zip(found, expected)), step
        jump = 2.0 if step % 8 == 7 else 0.15         # in reaches a step
        centre = (centre + rng.normal(0, jump * scale / 1.7, centre.shape)).astype(dtype)
        reach = (reach * rng.uniform(1.0, 1.02, len(reach))).astype(dtype)
    assert kept > 0         # the list was used again, not made afresh every time


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_a_neighbour_list_is_made_again_before_two_bodies_closing_head_on_can_touch(dtype):
    """Two bodies of reach 1 start 4.01 apart, just beyond the list's lengthened reaches
    (1 + 1 each), and close head on by 0.36 each a step. After three steps each has moved
    1.08, more than the skin of 1, and they touch (1.85 apart): the list must have been made
    again, or the pair is missed. A check looser by 0.08 of a reach misses it."""
    centre = np.array([[0.0, 0, 0], [4.01, 0, 0], [50.0, 0, 0]], dtype)
    reach = np.ones(3, dtype)
    neighbours = NeighbourList()
    for step in range(4):
        found = neighbours.pairs(centre, reach)
        expected = brute_force_pairs(centre, reach)
        assert all(np.array_equal(f, e) for f, e in zip(found, expected)), step
        centre[0, 0] += 0.36
        centre[1, 0] -= 0.36
    assert [part.tolist() for part in found] == [[0], [1]]


def test_a_pile_of_100_steps_the_same_with_and_without_the_neighbour_list():
    """The world keeps a neighbour list for its contacts and swept test: the trajectory is
    the very one the brute-force broad phase gives, to the bit."""
    def pile():
        rng = np.random.default_rng(5)
        world = physics.World(dtype="float32")
        world.add_plane((0, 1, 0), 0)
        for normal in [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]:
            world.add_plane(normal, -0.3)
        world.add_spheres(rng.uniform((-0.25, 0.05, -0.25), (0.25, 0.8, 0.25), (100, 3)),
                          velocities=rng.normal(0, 2, (100, 3)), radius=0.04, restitution=0.5)
        return world
    kept, fresh = pile(), pile()
    examined = Counter()
    for _ in range(90):
        kept.step()
        fresh._neighbours = NeighbourList()         # made afresh: brute force every step
        fresh.step()
        examined["kept"] += kept.work["pairs examined"]
        examined["fresh"] += fresh.work["pairs examined"]
    assert examined["kept"] < 0.5 * examined["fresh"]
    for a, b in [(kept.position, fresh.position), (kept.velocity, fresh.velocity),
                 (kept.angular_velocity, fresh.angular_velocity)]:
        np.testing.assert_array_equal(a, b)
