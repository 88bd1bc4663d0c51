"""Broad phase: which pairs of spheres are close enough to be worth a closer look.

Testing every pair costs N(N-1)/2 checks, 50 million for 10,000 spheres. A uniform grid with
cells as wide as the largest reach needs only the 27 cells around each sphere, so the cost
grows like N when the spheres are of similar size (a box of marbles, a break of pool balls).

Cells are found by sorting a hash of their integer coordinates (Teschner et al. 2003,
"Optimized spatial hashing for collision detection of deformable objects"), so there is no
table as large as the scene. Two different cells may share a hash: that only adds candidates,
which the exact distance test then drops, so the answer is always exactly the brute-force one.
A few bodies much larger than the rest (a boulder among marbles) would make every cell huge;
they are tested against everyone directly instead.
"""

from __future__ import annotations

import numpy as np

# Three large primes from Teschner et al. 2003; the hash mixes the cell coordinates with them.
_PRIMES = np.array([73856093, 19349663, 83492791], dtype=np.int64)
# The cell itself and 13 of its 26 neighbours: the other 13 are the opposites of these, so every
# pair of neighbouring cells is visited once (from the cell with the smaller offset).
_OFFSETS = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                     if (i, j, k) >= (0, 0, 0)], dtype=np.int64)
SMALL_SCENE = 64    # below this many bodies, checking every pair is faster than the grid
_LARGE = 4.0        # a body whose reach is over 4x the median is checked against all others


def find_pairs(centre: np.ndarray, reach: np.ndarray):
    """Pairs (i < j) whose bounding spheres touch: brute force for a few bodies (less overhead),
    the grid from SMALL_SCENE bodies on. Same answer either way; see `brute_force_pairs`."""
    if len(centre) < SMALL_SCENE:
        return brute_force_pairs(centre, reach)
    return grid_pairs(centre, reach)


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
    i, j = np.triu_indices(len(centre), k=1)
    return _close(centre, reach, i.astype(np.int64), j.astype(np.int64))


def grid_pairs(centre: np.ndarray, reach: np.ndarray):
    """The same pairs as `brute_force_pairs`, found with a hashed uniform grid in ~O(N)."""
    n = len(centre)
    if n < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    large = reach > _LARGE * np.median(reach)
    small = np.flatnonzero(~large)
    i_small, j_small = (_grid_candidates(centre[small], reach[small]) if len(small) > 1
                        else (np.zeros(0, np.int64), np.zeros(0, np.int64)))
    i = [small[i_small]]
    j = [small[j_small]]
    for body in np.flatnonzero(large):       # few: each against every other body
        others = np.arange(n, dtype=np.int64)
        others = others[(others != body) & (~large | (others > body))]
        i.append(np.full(len(others), body, np.int64))
        j.append(others)
    i, j = np.concatenate(i), np.concatenate(j)
    i, j = np.minimum(i, j), np.maximum(i, j)
    i, j = _close(centre, reach, i, j)
    key = np.unique(i * n + j)                          # sorted, and each pair once
    return key // n, key % n


def _grid_candidates(centre, reach):
    """Candidate pairs (i < j) from neighbouring cells of a grid of cell size 2 max(reach)."""
    n = len(centre)
    cell_size = 2.0 * float(np.max(reach))
    cell = np.floor(centre / cell_size).astype(np.int64)
    key = _hash(cell)
    order = np.argsort(key, kind="stable")               # bodies grouped by cell
    cell_keys, cell_start, cell_count = np.unique(key[order], return_index=True,
                                                  return_counts=True)
    i_parts, j_parts = [], []
    for offset in _OFFSETS:
        neighbour = _hash(cell + offset)
        slot = np.minimum(np.searchsorted(cell_keys, neighbour), len(cell_keys) - 1)
        found = cell_keys[slot] == neighbour
        start = cell_start[slot]
        count = np.where(found, cell_count[slot], 0)
        i = np.repeat(np.arange(n, dtype=np.int64), count)
        # the positions start[k], ..., start[k] + count[k] - 1 for every body k, in one array
        first = np.repeat(start - np.concatenate([[0], np.cumsum(count)[:-1]]), count)
        j = order[first + np.arange(len(i))]
        keep = (i < j) if not offset.any() else (i != j)
        i_parts.append(np.minimum(i[keep], j[keep]))
        j_parts.append(np.maximum(i[keep], j[keep]))
    return np.concatenate(i_parts), np.concatenate(j_parts)


def _hash(cell):
    """One int64 per integer cell (kx, ky, kz): (kx p1) xor (ky p2) xor (kz p3)."""
    mixed = cell * _PRIMES
    return mixed[:, 0] ^ mixed[:, 1] ^ mixed[:, 2]


def _close(centre, reach, i, j):
    """The pairs (i, j) whose bounding spheres touch or overlap."""
    d = centre[i] - centre[j]
    distance_squared = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2]
    limit = reach[i] + reach[j]
    keep = distance_squared <= limit * limit
    return i[keep], j[keep]
