"""Crowds: grid cells that hold more spheres than can fit in them without overlapping.

The grid of broadphase.py is linear only while each cell holds a few bodies. Spheres spawned at
one point (or pushed into each other) put everything into one cell, and then every pair really
does overlap: N(N-1)/2 contacts, 50 million for 10,000 spheres, whatever the broad phase. The
physics step therefore bounds the work: a cell holding more bodies than `cell_capacity` is
*crowded*, and the bodies in and next to crowded cells are paired only with their
``window`` successors along a Morton curve (`crowd_pairs`). That is a window of sort and sweep
(Ericson, Real-Time Collision Detection, 2005, ch. 7.5), sorted along a space-filling curve
instead of one axis, so it finds most of each body's near neighbours: enough for the push-out
to spread the crowd apart. Once no cell is crowded the pairs are exact again.
"""

from __future__ import annotations

import numpy as np

MORTON_BITS = 21    # bits per axis of a Morton code: 3 x 21 = 63 fit in an int64


def cell_capacity(cell_size, smallest):
    """The most bodies a cell can hold with no two bounding spheres touching (a volume count).

    Balls of the cell's smallest reach rho around each centre would then be disjoint, and they
    lie inside the cell grown by rho on every side, so there are at most
    (cell_size + 2 rho)^3 / (4/3 pi rho^3) of them: 15 for equal spheres (cell_size = 2 rho).
    A cell holding more has bodies that overlap, possibly many: a crowd.

    Parameters
    ----------
    cell_size : float
        Side of a cell (m).
    smallest : (C,) ndarray
        The smallest reach in each cell (m).

    Returns
    -------
    (C,) ndarray
        The capacities, whole numbers as floats.
    """
    return np.floor((cell_size + 2 * smallest) ** 3 / (4 / 3 * np.pi * smallest ** 3))


def crowd_pairs(centre, window: int):
    """Candidate pairs among M crowded bodies, each with its ``window`` successors in Morton
    order: about M x window pairs.

    Parameters
    ----------
    centre : (M, 3) ndarray
        The crowded bodies' centres (m).
    window : int
        How many successors each body is paired with.

    Returns
    -------
    i, j : int64 ndarrays
        Indices into ``centre``, i < j, each pair once.

    The Morton code interleaves the bits of the three coordinates, quantised to 2^21 steps over
    the crowd's bounding box; sorting by it lays the bodies along a space-filling curve that
    keeps most neighbours in space close in the order (Morton 1966; Ericson 2005, ch. 7.3.5).
    Equal codes keep the bodies' own order, so the pairs are the same on every run.
    """
    m = len(centre)
    low, high = centre.min(axis=0), centre.max(axis=0)
    steps = 2 ** MORTON_BITS - 1
    extent = np.where(high > low, high - low, 1.0)          # a flat crowd: that axis all 0
    quantised = np.minimum((centre - low) / extent * steps, steps).astype(np.int64)
    code = (_spread_bits(quantised[:, 0]) << 2) | (_spread_bits(quantised[:, 1]) << 1) \
        | _spread_bits(quantised[:, 2])
    order = np.argsort(code, kind="stable")
    shifts = range(1, min(window, m - 1) + 1)
    i = np.concatenate([order[:-s] for s in shifts] or [np.zeros(0, np.int64)])
    j = np.concatenate([order[s:] for s in shifts] or [np.zeros(0, np.int64)])
    return np.minimum(i, j), np.maximum(i, j)


def _spread_bits(v):
    """Bit k of each int64 in ``v`` moved to bit 3k, for its 21 low bits: the magic-number
    spreading of Ericson 2005, ch. 7.3.5 and F. Giesen, "Decoding Morton codes" (2009),
    widened from 10 bits to 21."""
    v = v & 0x1FFFFF
    v = (v | (v << 32)) & 0x1F00000000FFFF
    v = (v | (v << 16)) & 0x1F0000FF0000FF
    v = (v | (v << 8)) & 0x100F00F00F00F00F
    v = (v | (v << 4)) & 0x10C30C30C30C30C3
    v = (v | (v << 2)) & 0x1249249249249249
    return v
