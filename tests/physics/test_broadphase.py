"""The broad phase finds exactly the pairs that checking every pair finds, and contacts come out
in the same fixed order whichever way the pairs were found."""

from collections import Counter

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import physics
from physics.broadphase import brute_force_pairs, find_pairs, grid_pairs
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
