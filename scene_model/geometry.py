"""Small vector helpers shared by the camera, the backends and the physics."""

from __future__ import annotations

import numpy as np


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product of 3-vectors along the last axis: (..., 3) with (..., 3) or (3,) -> (...).

    Written out term by term, (a.x b.x + a.y b.y) + a.z b.z, rather than with einsum, @ or
    linalg.norm: those may sum in an order that depends on the memory layout or the batch
    size, and a pixel's value must not depend on which other rays were traced with it.
    """
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def normalize(v: np.ndarray) -> np.ndarray:
    """Unit vectors along the last axis. v : (..., 3) ndarray."""
    return v / np.sqrt(dot(v, v))[..., None]


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles in radians between vectors a and b, (..., 3) each: (...,).

    atan2(|a x b|, a . b) is accurate for small angles, where arccos(a . b) is not (near 1
    its slope is infinite); neither vector need be of unit length.
    """
    c = np.cross(a, b)
    return np.arctan2(np.sqrt(dot(c, c)), dot(a, b))


def rotation_matrix(degrees) -> np.ndarray:
    """R = Rz(z) Ry(y) Rx(x) for Euler angles in degrees, as a float64 (3, 3): turn about x first,
    then y, then z, all about the fixed axes.

    A rotated shape is evaluated at R^T p: turning the query point back into the shape's frame.
    """
    ax, ay, az = np.radians(np.asarray(degrees, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx
