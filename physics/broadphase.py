"""Broad phase: which pairs of spheres are close enough to be worth a closer look.

Testing every pair costs N(N-1)/2 checks, 50 million for 10,000 spheres. A uniform grid with
cells as wide as the largest reach needs only the 27 cells around each sphere, so the cost
grows like N when the spheres are of similar size (a box of marbles, a break of pool balls).

Cells are found by sorting a hash of their integer coordinates (Teschner et al. 2003,
"Optimized spatial hashing for collision detection of deformable objects"), so there is no
table as large as the scene. Two different cells may share a hash: that only adds candidates,
which the exact distance test then drops, so the answer is always exactly the brute-force one.

Spheres of very different sizes (boulders among marbles) would make every cell huge, so they
are sorted into size classes a factor of 4 apart (`size_classes`), each with its own grid: a
hierarchical grid (Ericson, Real-Time Collision Detection, 2005, ch. 7.2). Two spheres of one
class meet in their class's grid; a sphere meets those of a larger class by looking up the 27
cells around it in that class's grid, whose cells are wide enough for any such pair.

Where spheres pile into each other (spawned at one point), every pair really overlaps and no
grid helps; with ``crowd_window`` the work stays bounded there instead (crowds.py).
"""

from __future__ import annotations

import functools

import numpy as np

from physics.crowds import cell_capacity, crowd_pairs

# Three large primes from Teschner et al. 2003; the hash mixes the cell coordinates with them.
_PRIMES = np.array([73856093, 19349663, 83492791], dtype=np.int64)
# All 27 cells around a cell, itself included, and the cell with the 13 of its neighbours that
# come after it: the other 13 are their opposites, so every pair of neighbouring cells is
# visited once (from the cell with the smaller offset).
_ALL = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)],
                dtype=np.int64)
_OFFSETS = _ALL[[tuple(offset) >= (0, 0, 0) for offset in _ALL.tolist()]]
# Below this many bodies, checking every pair (one (N, N) table, `brute_force_pairs`) is
# faster than the grid: measured 0.25 against 0.9 ms at 100 spheres, about even at 192-256.
SMALL_SCENE = 192
CLASS_RATIO = 4.0   # the reaches of a size class span a factor of 4 (16 around the median)
CROWD_WINDOW = 12   # in a crowd, each body is paired with its next 12 along a Morton curve


def find_pairs(centre: np.ndarray, reach: np.ndarray, crowd_window=None, counter=None,
               neighbours=None, bodies=None):
    """Pairs (i < j) whose bounding spheres touch: brute force for a few bodies (less overhead),
    the grid from SMALL_SCENE bodies on. Same answer either way; see `brute_force_pairs`.

    ``crowd_window`` (an int) bounds the work where bodies crowd into a cell, and ``counter``
    (a collections.Counter) gets the number of candidate pairs tested added to its
    ``"pairs examined"``; see `grid_pairs`. ``neighbours``, a `NeighbourList` kept from step
    to step, does the brute force's work with fewer tests; ``bodies`` (N,) int names the bodies
    the rows of ``centre`` are, so that a list made for others is not used.
    """
    if len(centre) < SMALL_SCENE:
        if neighbours is not None:
            return neighbours.pairs(centre, reach, counter, bodies)
        if counter is not None:
            counter["pairs examined"] += len(centre) * (len(centre) - 1) // 2
        return brute_force_pairs(centre, reach)
    return grid_pairs(centre, reach, crowd_window, counter)


def brute_force_pairs(centre: np.ndarray, reach: np.ndarray):
    """All pairs (i < j) with |c_i - c_j| <= reach_i + reach_j, by checking every pair.

    Parameters
    ----------
    centre : (N, 3) ndarray
        Centres of the bounding spheres (m).
    reach : (N,) ndarray
        Their radii (m).

    Returns
    -------
    i, j : (M,) int64 ndarrays
        The pairs, sorted by i then j. O(N^2): the reference the grid is tested against.
    """
    return _close(centre, reach, *_upper_pairs(len(centre)))    # row by row: sorted


@functools.lru_cache(maxsize=8)
def _upper_pairs(n: int):
    """Every pair i < j of n bodies, sorted by i then j: (n (n - 1) / 2,) int64 each, kept
    for the next step (a world's count seldom changes)."""
    i, j = np.triu_indices(n, k=1)
    i, j = i.astype(np.int64), j.astype(np.int64)
    i.flags.writeable = j.flags.writeable = False
    return i, j


class NeighbourList:
    """`find_pairs` that remembers: candidate pairs found with room to spare, kept for the
    steps after while no body has used the room up (a Verlet list, Verlet 1967; the
    neighbour list of molecular dynamics, Allen and Tildesley, "Computer Simulation of
    Liquids", 2nd ed. 2017, ch. 5.3).

    When the list is made, every reach is lengthened by a skin s (the largest reach), and
    the pairs within the lengthened reaches are kept. A later call with centres c and
    reaches R may use them while every body k has |c_k - c0_k| + R_k <= R0_k + s (c0, R0:
    when made): then |c_i - c_j| <= R_i + R_j gives |c0_i - c0_j| <= (R0_i + s) + (R0_j + s)
    by the triangle inequality, so no touching pair is missing from the kept ones. The kept
    pairs are tested with the same arithmetic as `brute_force_pairs` (`_close`), so the
    answer is the same pairs in the same order, to the bit; only the number tested changes
    (about 1,000 of 4,950 for a pile of 100 balls). A check that fails, or a different set
    of bodies, makes the list afresh.

    A world steps its contacts and its swept test through one list (both ask about spheres
    near each other, the swept test about their paths), given to `find_pairs`: from
    SMALL_SCENE bodies on that uses the grid instead, which finds pairs in ~O(N) anyway.
    """

    def __init__(self):
        self._bodies = None      # (N,) int: which bodies the list was made for
        self._centre = None      # (N, 3) float64: c0
        self._bound = None       # (N,) float64: R0 + s, less a margin for rounding
        self._pairs = None       # (i, j): every pair within the lengthened reaches

    def pairs(self, centre, reach, counter=None, bodies=None):
        """The same pairs as `brute_force_pairs` (i < j, sorted by i then j).

        ``bodies`` (N,) int names the bodies the rows of ``centre`` are (the world's alive
        spheres): a list made for other bodies is not used. ``counter``: see `find_pairs`.
        """
        n = len(centre)
        bodies = np.arange(n) if bodies is None else bodies
        if not self._still_holds(centre, reach, bodies):
            if counter is not None:
                counter["pairs examined"] += n * (n - 1) // 2
            if not self._make(centre, reach, bodies):      # a reach that is not finite
                return brute_force_pairs(centre, reach)
        i, j = self._pairs
        if counter is not None:
            counter["pairs examined"] += len(i)
        return _close(centre, reach, i, j)

    def _still_holds(self, centre, reach, bodies) -> bool:
        if self._bodies is None or not np.array_equal(bodies, self._bodies):
            return False
        moved = centre - self._centre                   # in float64: c0 is
        moved *= moved
        distance = np.sqrt(moved[:, 0] + moved[:, 1] + moved[:, 2])
        # NaN (a body gone astray) fails the test, and the list is made again.
        return bool((distance + reach <= self._bound).all())

    def _make(self, centre, reach, bodies) -> bool:
        """Make the list for these bodies; False (and no list) where a reach is not finite,
        as no skin then bounds how far the bodies may go."""
        skin = float(np.max(reach, initial=0))
        if not np.isfinite(skin):
            self._bodies = None
            return False
        self._pairs = _close(centre, reach + skin, *_upper_pairs(len(centre)))
        self._bodies = np.array(bodies)
        self._centre = centre.astype(np.float64)
        # The margin covers the rounding of the float32 tests (|c| and R of the scene's size,
        # a few units in the last place) and of the check itself.
        size = float(np.max(np.abs(self._centre), initial=0)) + skin
        margin = 0.01 * skin + 64 * np.finfo(centre.dtype).eps * size
        self._bound = reach.astype(np.float64) + (skin - margin)
        return True


def grid_pairs(centre: np.ndarray, reach: np.ndarray, crowd_window=None, counter=None):
    """The same pairs as `brute_force_pairs`, found with hashed uniform grids in ~O(N).

    Parameters
    ----------
    centre, reach : (N, 3) and (N,) ndarrays
        As for `brute_force_pairs`: the bounding spheres' centres and radii (m).
    crowd_window : int, optional
        None (default): exactly the brute-force pairs, whatever it costs. An int W: bounded
        work where a cell is crowded (`crowds.cell_capacity`): its bodies and those of the
        cells around it are paired with their W successors in Morton order
        (`crowds.crowd_pairs`), and a smaller sphere looking into a crowded cell of a larger
        class meets only W of its bodies. Some touching pairs inside a crowd are then missed.
    counter : collections.Counter, optional
        ``counter["pairs examined"]`` grows by the number of candidate pairs tested.

    Returns
    -------
    i, j : (M,) int64 ndarrays
        The pairs, sorted by i then j.
    """
    n = len(centre)
    if n < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    size_class = size_classes(reach)
    classes = np.unique(size_class)
    members = [np.flatnonzero(size_class == this) for this in classes]
    grids = [_Grid(centre[m], reach[m], crowd_window) for m in members]   # one per class
    i, j = [], []
    for index, own in enumerate(members):
        if len(own) > 1:
            i_class, j_class = _grid_candidates(grids[index], centre[own], crowd_window)
            i.append(own[i_class])
            j.append(own[j_class])
        for big, grid in zip(members[index + 1:], grids[index + 1:]):
            i_small, j_big = _larger_candidates(centre[own], grid, crowd_window)
            i.append(own[i_small])
            j.append(big[j_big])
    i, j = np.concatenate(i), np.concatenate(j)
    if counter is not None:
        counter["pairs examined"] += len(i)
    i, j = np.minimum(i, j), np.maximum(i, j)
    i, j = _close(centre, reach, i, j)
    key = np.unique(i * n + j)                          # sorted, and each pair once
    return key // n, key % n


def size_classes(reach: np.ndarray) -> np.ndarray:
    """The size class (N,) int of each reach: 0 within a factor CLASS_RATIO of the median, then
    1, 2, ... for each further factor above it and -1, -2, ... below."""
    scale = np.log(reach / np.median(reach)) / np.log(CLASS_RATIO)
    return np.where(scale > 1, np.ceil(scale) - 1,
                    np.where(scale < -1, np.floor(scale) + 1, 0)).astype(np.int64)


def _grid_candidates(grid, centre, crowd_window=None):
    """Candidate pairs (i < j) of the bodies at ``centre`` from neighbouring cells of their
    `_Grid` (cell size 2 max(reach)).

    With ``crowd_window``, the bodies of crowded cells are paired only by `crowd_pairs`, and
    those of the cells around them both by it and by the grid (with each other).
    """
    i_parts, j_parts = [], []
    count = grid.count
    if grid.crowded.any():
        # The crowd: the bodies of crowded cells and of the cells around them.
        around = grid.lookup((grid.cells[grid.crowded][:, None, :] + _ALL).reshape(-1, 3))
        near = grid.crowded.copy()
        near[around[around >= 0]] = True
        crowd = np.sort(grid.order[near[grid.cell_of_order]])
        i_crowd, j_crowd = crowd_pairs(centre[crowd], crowd_window)
        i_parts.append(crowd[i_crowd])
        j_parts.append(crowd[j_crowd])
        count = np.where(grid.crowded, 0, count)       # the grid pairs only uncrowded cells
    uncrowded = ~grid.crowded[grid.lookup(grid.cell)]     # each body's own cell
    for offset in _OFFSETS:
        slot = grid.lookup(grid.cell + offset)
        i, j = grid.members(slot, np.where((slot >= 0) & uncrowded, count[slot], 0))
        keep = (i < j) if not offset.any() else (i != j)
        i_parts.append(np.minimum(i[keep], j[keep]))
        j_parts.append(np.maximum(i[keep], j[keep]))
    return np.concatenate(i_parts), np.concatenate(j_parts)


def _larger_candidates(small_centre, grid, crowd_window=None):
    """Candidate pairs (i into small_centre, j into the larger class) between bodies of a
    smaller size class and those of a larger one, from the 27 cells around each smaller body
    in the larger class's `_Grid`. A pair that touches has |c_i - c_j| <= 2 max(reach), one
    cell, so none is missed."""
    count = grid.count
    if crowd_window is not None:
        count = np.where(grid.crowded, np.minimum(count, crowd_window), count)
    cell = np.floor(small_centre / grid.cell_size).astype(np.int64)
    i_parts, j_parts = [], []
    for offset in _ALL:
        slot = grid.lookup(cell + offset)
        i, j = grid.members(slot, np.where(slot >= 0, count[slot], 0))
        i_parts.append(i)
        j_parts.append(j)
    return np.concatenate(i_parts), np.concatenate(j_parts)


class _Grid:
    """M bodies hashed into cubic cells of side 2 max(reach), grouped by cell.

    ``order`` lists the bodies cell by cell; cell k (in ``keys`` order) holds
    order[start[k] : start[k] + count[k]] and has integer coordinates cells[k]. With a
    ``crowd_window``, ``crowded`` marks the cells holding more than `crowds.cell_capacity`.
    """

    def __init__(self, centre, reach, crowd_window=None):
        self.cell_size = 2.0 * float(np.max(reach))
        self.cell = np.floor(centre / self.cell_size).astype(np.int64)
        key = _hash(self.cell)
        self.order = np.argsort(key, kind="stable")
        self.keys, self.start, self.count = np.unique(key[self.order], return_index=True,
                                                      return_counts=True)
        self.cells = self.cell[self.order][self.start]
        self.cell_of_order = np.repeat(np.arange(len(self.keys)), self.count)
        self.crowded = np.zeros(len(self.keys), bool)
        if crowd_window is not None:
            smallest = np.minimum.reduceat(reach[self.order], self.start)
            self.crowded = self.count > cell_capacity(self.cell_size, smallest)

    def lookup(self, cells):
        """The slot of each of the integer cells (K, 3) in ``keys``, -1 where it is empty."""
        keys = _hash(cells)
        slot = np.minimum(np.searchsorted(self.keys, keys), len(self.keys) - 1)
        return np.where(self.keys[slot] == keys, slot, -1)

    def members(self, slot, count):
        """Pairs (k, body) for the first count[k] bodies of cell slot[k], for every k."""
        i = np.repeat(np.arange(len(slot), dtype=np.int64), count)
        # the positions start[k], ..., start[k] + count[k] - 1 for every k, in one array
        first = np.repeat(self.start[slot] - np.concatenate([[0], np.cumsum(count)[:-1]]),
                          count)
        return i, self.order[first + np.arange(len(i))]


def _hash(cell):
    """One int64 per integer cell (kx, ky, kz): (kx p1) xor (ky p2) xor (kz p3)."""
    mixed = cell * _PRIMES
    return mixed[:, 0] ^ mixed[:, 1] ^ mixed[:, 2]


def _close(centre, reach, i, j):
    """The pairs (i, j) (M,) whose bounding spheres touch or overlap: |c_i - c_j| <=
    reach_i + reach_j, term by term (d_x d_x + d_y d_y + d_z d_z).

    Gathered with `take`, x, y and z each into one contiguous row of d (3, M), and products
    made in place: 70 against 170 microseconds for the 4,950 pairs of 100 bodies.
    """
    d = centre.T.take(i, axis=1)
    d -= centre.T.take(j, axis=1)
    d *= d
    distance_squared = d[0] + d[1] + d[2]
    limit = reach.take(i)
    limit += reach.take(j)
    limit *= limit
    keep = np.flatnonzero(distance_squared <= limit)
    return i.take(keep), j.take(keep)
