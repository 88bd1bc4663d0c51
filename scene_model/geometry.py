"""Small vector helpers shared by the camera, the backends and the physics."""

from __future__ import annotations

import numpy as np


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product of 3-vectors along the last axis: (..., 3) with (..., 3) or (3,) -> (...).

    Written out term by term, (a.x b.x + a.y b.y) + a.z b.z, rather than with einsum, @ or
    linalg.norm: those may sum in an order that depends on the memory layout or the batch
    size, and a pixel's value must not depend on which other rays were traced with it.
    """
    products = a * b                # the three products at once: fewer NumPy calls, same sums
    return products[..., 0] + products[..., 1] + products[..., 2]


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


def quaternion_from_matrix(rotation: np.ndarray) -> np.ndarray:
    """The unit quaternion (4,) (w, x, y, z) of a rotation matrix (3, 3), with w >= 0.

    Shepperd's method ("Quaternion from rotation matrix", J. Guidance and Control 1, 1978):
    of 4w^2 = 1 + trace and 4x^2 = 1 + 2 R_xx - trace (and so on), take the root of the
    largest, which is never small, and the other three components from the off-diagonal
    sums and differences divided by it.
    """
    r = np.asarray(rotation, np.float64)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    squares = np.array([1 + trace, 1 + 2 * r[0, 0] - trace, 1 + 2 * r[1, 1] - trace,
                        1 + 2 * r[2, 2] - trace])
    largest = int(np.argmax(squares))
    s = 2 * np.sqrt(squares[largest])           # 4 times that component
    w_x_y_z = {
        0: (s / 4, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s),
        1: ((r[2, 1] - r[1, 2]) / s, s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s),
        2: ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s),
        3: ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4),
    }[largest]
    q = np.array(w_x_y_z)
    return q if q[0] >= 0 else -q


def axis_angle_matrix(rotation) -> np.ndarray:
    """The rotation (3, 3) by the angle |r| (radians) about the axis r / |r|, for a rotation
    vector r (3,); the identity for r = 0.

    Rodrigues' formula: R = I + sin(a) K + (1 - cos(a)) K^2, K the cross-product matrix of
    the unit axis.
    """
    r = np.asarray(rotation, np.float64)
    angle = float(np.sqrt(r @ r))
    if angle == 0:
        return np.eye(3)
    k = r / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def rotation_vector(rotation) -> np.ndarray:
    """The rotation vector r (3,) of a rotation matrix (3, 3): the axis times the angle, the
    angle in [0, pi] (the shorter way round), via its quaternion: |r| = 2 atan2(|v|, w)."""
    q = quaternion_from_matrix(rotation)
    length = float(np.sqrt(q[1:] @ q[1:]))
    if length == 0:
        return np.zeros(3)
    return 2 * np.arctan2(length, q[0]) * q[1:] / length
