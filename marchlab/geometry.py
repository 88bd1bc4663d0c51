"""Small vector helpers shared by the camera, the backends and the physics."""

from __future__ import annotations

import numpy as np


def normalize(v: np.ndarray) -> np.ndarray:
    """Unit vectors along the last axis. v : (..., 3) ndarray."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def rotation_matrix(degrees) -> np.ndarray:
    """R = Rz(z) Ry(y) Rx(x) for Euler angles in degrees (source 000), as a float64 (3, 3).

    A rotated shape is evaluated at R^T p: turning the query point back into the shape's frame.
    """
    ax, ay, az = np.radians(np.asarray(degrees, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx
