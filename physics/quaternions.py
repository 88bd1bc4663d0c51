"""Unit quaternions (w, x, y, z) for the orientation of each body.

A sphere's orientation does not change how it collides, but a renderer needs it to draw a
rolling ball's texture turning, and a student can check that a rolling ball turns by
distance / radius radians.
"""

from __future__ import annotations

import numpy as np


def quaternion_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product p q for p, q : (N, 4) arrays of (w, x, y, z)."""
    pw, px, py, pz = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    qw, qx, qy, qz = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([pw * qw - px * qx - py * qy - pz * qz,
                     pw * qx + px * qw + py * qz - pz * qy,
                     pw * qy - px * qz + py * qw + pz * qx,
                     pw * qz + px * qy - py * qx + pz * qw], axis=1)


def quaternion_from_rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """The rotation by angle |r| about the axis r / |r|, for r : (N, 3) -> (N, 4).

    q = (cos(|r|/2), sin(|r|/2) r/|r|); sin(x/2)/x is written with np.sinc so that r = 0 gives
    the identity without a division by zero (np.sinc(u) = sin(pi u) / (pi u)).
    """
    angle = np.sqrt(np.sum(rotation * rotation, axis=1))
    half_sinc = 0.5 * np.sinc(angle / (2 * np.pi))          # sin(angle/2) / angle
    return np.concatenate([np.cos(0.5 * angle)[:, None], half_sinc[:, None] * rotation],
                          axis=1).astype(rotation.dtype, copy=False)


def rotate_orientations(orientation: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Turn each orientation (N, 4) by the world-frame rotation vector (N, 3) (radians).

    The new orientation is exp(r) q: the turn happens in the world frame, where angular
    velocity is measured. Renormalised so rounding cannot let |q| drift from 1 over many steps.
    """
    turned = quaternion_multiply(quaternion_from_rotation_vector(rotation), orientation)
    return turned / np.sqrt(np.sum(turned * turned, axis=1))[:, None]


def rotation_matrices(orientation: np.ndarray) -> np.ndarray:
    """3x3 rotation matrices (N, 3, 3) for unit quaternions (N, 4)."""
    w, x, y, z = orientation[:, 0], orientation[:, 1], orientation[:, 2], orientation[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1),
    ], axis=1)



def rotation_vector_between(start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """The world-frame rotation vector r (N, 3) with exp(r) start = end, the shorter way round,
    for unit quaternions start, end : (N, 4): the inverse of `rotate_orientations`.

    The turn end start^-1 = (cos(a/2), sin(a/2) k) gives the angle a = 2 atan2(|sin part|,
    cos part) (with the cos part made >= 0: q and -q are the same turn, and the shorter one
    has a <= pi) and r = a k; a / sin(a/2) tends to 2 for a small turn, which the formula
    below keeps without dividing by zero.
    """
    conjugate = start * np.array([1, -1, -1, -1], start.dtype)
    turn = quaternion_multiply(end, conjugate)
    turn = np.where(turn[:, :1] < 0, -turn, turn)
    sine = np.sqrt(np.sum(turn[:, 1:] * turn[:, 1:], axis=1))
    angle = 2 * np.arctan2(sine, turn[:, 0])
    scale = np.where(sine > 0, angle / np.where(sine > 0, sine, 1), 2.0)
    return (scale[:, None] * turn[:, 1:]).astype(start.dtype, copy=False)
