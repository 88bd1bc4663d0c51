"""Inputs for the packet tests: seeded random rows, with the hard cases mixed in.

`mix` picks, row by row (or packet by packet), one of several arrays; `per_packet` repeats a
parameter for the LANES rows of a packet (what a scene fixes is the same in every lane);
`pick`, `units`, `normalised` and `near` (just beside a value) draw the rest. Each test file
keeps its own seed and sizes (tests/opencl/packet_twins.py runs the kernels).
"""

from __future__ import annotations

import numpy as np

from gpu_shader.dialects import PACKET_LANES

LANES = PACKET_LANES


def mix(rng, *options) -> np.ndarray:
    """Entry by entry along the first axis, one of ``options`` at random.

    Parameters
    ----------
    rng : numpy.random.Generator
    *options : array_like
        Broadcast to one shape (n, ...): rows of inputs, or (blocks, ...) values of a
        parameter to choose packet by packet. At least one must have that shape.

    Returns
    -------
    (n, ...) ndarray
    """
    shape = np.broadcast_shapes(*map(np.shape, options))
    stacked = np.stack([np.broadcast_to(o, shape) for o in options])
    return stacked[rng.integers(len(options), size=shape[0]), np.arange(shape[0])]


def per_packet(values) -> np.ndarray:
    """One value (or row of k values) per packet, repeated for the LANES rows of its packet.

    Parameters
    ----------
    values : (blocks,) or (blocks, k) array_like

    Returns
    -------
    (blocks * LANES, k) ndarray
    """
    values = np.asarray(values, float)
    return np.repeat(values.reshape(len(values), -1), LANES, axis=0)


def pick(rng, choices, shape) -> np.ndarray:
    """An array of ``shape`` values drawn from ``choices``, each equally likely."""
    return np.asarray(choices, float)[rng.integers(len(choices), size=shape)]


def units(rng, n: int) -> np.ndarray:
    """(n, 3) random unit vectors, uniform over the sphere."""
    return normalised(rng.normal(size=(n, 3)))


def normalised(v) -> np.ndarray:
    """``v`` divided by its length along the last axis."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def near(rng, values, exponents: tuple) -> np.ndarray:
    """``values`` a relative 10**e off, either way, for e uniform in ``exponents``.

    Parameters
    ----------
    rng : numpy.random.Generator
    values : (n, ...) ndarray
    exponents : (low, high)
        E.g. (-7, -2): from 1e-7 to 1e-2 off, just inside to well outside a surface.

    Returns
    -------
    (n, ...) ndarray
        One offset per entry along the first axis (per row).
    """
    shape = (len(values),) + (1,) * (np.ndim(values) - 1)
    offset = rng.choice([-1.0, 1.0], size=shape) * 10.0 ** rng.uniform(*exponents, size=shape)
    return values * (1.0 + offset)
