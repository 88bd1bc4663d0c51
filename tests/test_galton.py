"""The bundled Galton board fills its bins with binomial counts.

galton.toml runs 120 balls out of a hopper through 10 rows of pins into 11 bins. A ball that
passes right of k of the 10 pins it meets lands in bin k, so if each pin sends it either way
with probability 1/2, whatever it did before, the counts follow Binomial(10, 1/2): bin k
expects 120 C(10, k) / 2^10 balls (Galton, "Natural Inheritance", 1889). The simulation is
run once for the whole module (`board`); it is deterministic, since the scene fixes every
start position and the physics draws no random numbers for balls that do not coincide.

Measured here (float64, dt = 1/120 s, 7 s simulated; the module takes 40 to 53 s of CPU time
on a shared two-core machine, nearly all of it in `board`):
counts 0 3 5 11 22 30 25 17 7 0 0 against expected 0.1 1.2 5.3 14.1 24.6 29.5 24.6 14.1 5.3
1.2 0.1, chi-square 1.91 with 6 degrees of freedom after pooling the tails, p = 0.93; the
variance of the bin index 2.62 (binomial 2.5), its mean 5.07. The same board from five other
seeds of the starting jitter gave p = 0.41, 0.86, 0.09, 0.45 and 0.88 and variances 2.3 to
3.1: a pass is not a lucky draw.
"""

import numpy as np
import pytest
from scipy import stats

import marchlab
import physics
from marchlab.simulation import build_world

# The board as galton.toml builds it.
ROWS = 10
PIN_SPACING = 0.1            # m: bin k is centred at x = (k - ROWS / 2) PIN_SPACING
DIVIDER_TOP = 0.8            # m: a ball whose centre is lower is in a bin
WALL = 0.55                  # m: the side walls' inner faces are at x = +-WALL
SECONDS = 7.0                # simulated; every ball is in a bin after about 6 s
SIGNIFICANCE = 0.01
LEAST_EXPECTED = 5           # Pearson's rule of thumb for each cell of a chi-square test


@pytest.fixture(scope="module")
def board():
    """The scene and its trajectory over SECONDS, ten frames a second."""
    scene = marchlab.load_scene("galton")
    world = build_world(scene)
    run = physics.simulate(world, SECONDS, record_every=round(0.1 / world.dt))
    return scene, run


def bin_of(position: np.ndarray) -> np.ndarray:
    """Bin index (N,) of each ball centre (N, 3): nearest bin centre, -1 for a ball not in a bin
    (above the dividers or outside the walls)."""
    k = np.rint(position[:, 0] / PIN_SPACING).astype(int) + ROWS // 2
    inside = (position[:, 1] < DIVIDER_TOP) & (np.abs(position[:, 0]) < WALL)
    return np.where(inside, k, -1)


def pooled(observed: np.ndarray, expected: np.ndarray, least: float):
    """Merge the cells at each end into their neighbour until every expected count is at least
    ``least`` (the tails of a binomial are the small cells). Returns both arrays, pooled."""
    observed, expected = np.array(observed, float), np.array(expected, float)
    low, high = 0, len(expected)
    while expected[low] < least:
        expected[low + 1] += expected[low]
        observed[low + 1] += observed[low]
        low += 1
    while expected[high - 1] < least:
        expected[high - 2] += expected[high - 1]
        observed[high - 2] += observed[high - 1]
        high -= 1
    return observed[low:high], expected[low:high]


def test_pooling_merges_each_tail_until_every_cell_expects_five():
    observed, expected = pooled(np.array([1, 1, 1, 9, 1]), np.array([1.0, 2.0, 3.0, 9.0, 4.0]), 5)
    np.testing.assert_array_equal(observed, [3, 10])
    np.testing.assert_allclose(expected, [6.0, 13.0])


def test_galton_bin_counts_fit_binomial_10_half_by_chi_square_at_1_percent(board):
    """Pearson's chi-square goodness of fit of the bin counts to Binomial(ROWS, 1/2), the tails
    pooled so that every cell expects at least five balls, must not reject at the 1% level."""
    _, run = board
    k = bin_of(run.positions[-1])
    counts = np.bincount(k[k >= 0], minlength=ROWS + 1)
    expected = stats.binom.pmf(np.arange(ROWS + 1), ROWS, 0.5) * counts.sum()
    observed, expected = pooled(counts, expected, LEAST_EXPECTED)
    assert len(observed) >= 5                 # the test has degrees of freedom to speak of
    result = stats.chisquare(observed, expected)
    assert result.pvalue > SIGNIFICANCE, (counts, result)


def test_galton_at_least_98_percent_of_the_balls_end_in_bins_and_none_leave_the_board(board):
    """Every ball stays between the walls, on the floor and in the plane z = 0 all along, none
    is removed for leaving the world, and by the end 98% or more lie in a bin (not still in the
    hopper or wedged among the pins). "On the floor" allows half a radius of sinking in: the
    Jacobi solver lets the bottom ball of a full bin, under some 15 others, press 5 mm in.
    "Between the walls" allows a quarter of a radius: a ball squeezed between a pin and a
    wall by the balls above it pressed 1.9 mm into the wall for one recorded frame (at 1.3 s,
    with NumPy 2.4's rounding), before the solver pushed it out."""
    scene, run = board
    radius = scene.bodies[0].radius
    assert run.active.all()
    assert np.abs(run.positions[..., 0]).max() <= WALL - radius + radius / 4
    assert run.positions[..., 1].min() >= radius / 2
    assert np.all(run.positions[..., 2] == 0.0)
    in_bins = np.count_nonzero(bin_of(run.positions[-1]) >= 0)
    assert in_bins >= 0.98 * len(scene.bodies)


def test_galton_mean_bin_is_within_half_a_bin_of_the_centre(board):
    """The board is symmetric, so the mean bin index is ROWS / 2 = 5 up to sampling: its
    standard error is sqrt(ROWS / 4 / 120) = 0.14, and 0.5 is 3.5 of those."""
    _, run = board
    k = bin_of(run.positions[-1])
    assert abs(k[k >= 0].mean() - ROWS / 2) < 0.5
