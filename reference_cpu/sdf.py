"""Signed distance functions and the operators that combine them, over arrays of points.

Every function takes points ``p : (N, 3) ndarray`` and returns distances ``(N,)``. Results are
in the dtype of ``p`` when the parameters are Python numbers or arrays of that dtype
(`reference_cpu.scene_sdf` converts them so). Primitives are centred on the origin; transforms
move the query point instead of the shape. Formulas from Inigo Quilez, "Distance functions"
(https://iquilezles.org/articles/distfunctions/); the GLSL and OpenCL versions use the same
names.
"""

from __future__ import annotations

import numpy as np

from scene_model.geometry import dot


def length(v: np.ndarray) -> np.ndarray:
    """Euclidean length of 3-vectors along the last axis: (N, 3) -> (N,)."""
    return np.sqrt(dot(v, v))


def length2(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Length of the 2-D vectors (x, y), given as two (N,) arrays."""
    return np.sqrt(x * x + y * y)


# --- Primitives --------------------------------------------------------------------------------

def sdf_sphere(p, radius):
    """Sphere: distance to the centre minus the radius."""
    return length(p) - radius


def sdf_box(p, half_size):
    """Box with half-extents ``half_size`` (3,).

    q is p folded into the positive octant relative to the corner: outside, the distance is
    the length of q's positive part; inside, the largest (least negative) component.
    """
    q = np.abs(p) - half_size
    outside = length(np.maximum(q, 0))
    inside = np.minimum(q.max(axis=-1), 0)
    return outside + inside


def sdf_round_box(p, half_size, radius):
    """Box of outer half-extents ``half_size`` whose edges are rounded by ``radius``.

    It is the box shrunk by ``radius`` on every side, then inflated by ``radius``.
    """
    return sdf_box(p, np.asarray(half_size) - radius) - radius


def sdf_plane(p, normal, offset):
    """Half-space ``normal . x <= offset`` (``normal`` (3,) need not be unit length)."""
    n = normal / np.sqrt(dot(normal, normal))
    return dot(p, n) - offset


def sdf_torus(p, major_radius, minor_radius):
    """Torus around the y axis: distance to the ring's centre circle, minus the tube radius."""
    ring = length2(p[:, 0], p[:, 2]) - major_radius
    return length2(ring, p[:, 1]) - minor_radius


def sdf_capped_cylinder(p, radius, half_height):
    """Cylinder along y: a 2-D box in the (distance from axis, height) plane."""
    dx = length2(p[:, 0], p[:, 2]) - radius
    dy = np.abs(p[:, 1]) - half_height
    outside = length2(np.maximum(dx, 0), np.maximum(dy, 0))
    inside = np.minimum(np.maximum(dx, dy), 0)
    return outside + inside


def sdf_capsule(p, a, b, radius):
    """Distance to the segment a-b (closest point by clamped projection), minus the radius."""
    pa, ba = p - a, b - a
    h = np.clip(dot(pa, ba) / dot(ba, ba), 0, 1)
    # h ba, the closest point of the segment; built column by column like p (order="F"),
    # which NumPy does ten times faster here than row by row.
    closest = np.multiply(h[:, None], ba, order="F")
    return length(pa - closest) - radius


def sdf_cone(p, radius, height):
    """Solid cone along y with its base disc (``radius``) at y = 0 and apex at y = ``height``.

    Quilez's exact cone, which has its apex at the origin, evaluated at p - (0, height, 0).
    In the (distance from axis, y) half-plane the cone is a triangle; q is the base rim
    seen from the apex. The distance is to the nearer of the slanted side (segment a) and
    the base (segment b); the sign says which side of both the point lies on.
    """
    wx = length2(p[:, 0], p[:, 2])
    wy = p[:, 1] - height
    qx, qy = radius, -height
    # Closest point on the slanted side, from the apex (0, 0) to the rim (qx, qy).
    s = np.clip((wx * qx + wy * qy) / (qx * qx + qy * qy), 0, 1)
    ax, ay = wx - qx * s, wy - qy * s
    # Closest point on the base, from the axis (0, qy) to the rim (qx, qy).
    bx, by = wx - qx * np.clip(wx / qx, 0, 1), wy - qy
    d2 = np.minimum(ax * ax + ay * ay, bx * bx + by * by)
    # Inside when below the slant and above the base (k = sign(qy) = -1).
    sign = np.sign(np.maximum(-(wx * qy - wy * qx), -(wy - qy)))
    return np.sqrt(d2) * sign


# --- Combining distances (CSG) --------------------------------------------------------------

def op_union(d1, d2):
    """Points inside either shape."""
    return np.minimum(d1, d2)


def op_intersection(d1, d2):
    """Points inside both shapes."""
    return np.maximum(d1, d2)


def op_subtraction(d1, d2):
    """Shape 1 minus shape 2: inside 1 and outside 2."""
    return np.maximum(d1, -d2)


def _mix(a, b, h):
    return a + (b - a) * h


def op_smooth_union(d1, d2, k):
    """Union whose seam is rounded over a width ``k`` (Quilez's polynomial smooth minimum).

    h blends from shape 2 (h = 0) to shape 1 (h = 1); k h (1 - h) digs the fillet. The result
    is a bound, not an exact distance, inside the blend region.
    """
    h = np.clip(0.5 + 0.5 * (d2 - d1) / k, 0, 1)
    return _mix(d2, d1, h) - k * h * (1 - h)


def op_smooth_subtraction(d1, d2, k):
    """Shape 1 minus shape 2 with a rounded edge of width ``k``."""
    h = np.clip(0.5 - 0.5 * (d1 + d2) / k, 0, 1)
    return _mix(d1, -d2, h) + k * h * (1 - h)


def op_smooth_intersection(d1, d2, k):
    """Intersection with a rounded edge of width ``k``."""
    h = np.clip(0.5 - 0.5 * (d2 - d1) / k, 0, 1)
    return _mix(d2, d1, h) + k * h * (1 - h)


# --- Moving the query point (transforms) ---------------------------------------------------------

def op_translate(p, offset):
    """Query point for a shape moved by ``offset``."""
    return p - offset


def op_rotate(p, matrix):
    """Query point for a shape rotated by ``matrix`` R (3, 3): R^T p for every point.

    Component j of R^T p is p . (column j of R). Stacked as rows and transposed, the result
    is stored column by column like ``p`` (see `reference_cpu.march.columns`).
    """
    return np.stack([dot(p, matrix[:, j]) for j in range(3)]).T


def op_scale(p, factor):
    """Query point for a shape scaled by ``factor``; multiply its distance back by ``factor``."""
    return p / factor


def op_repeat(p, period):
    """Fold space into one cell of size ``period`` (3,), centred on the origin.

    Axes whose period is 0 are left alone. floor(x + 0.5) rounds halves up the same way in
    every backend (GLSL's round() leaves them to the implementation).
    """
    cell = np.floor(p / np.where(period > 0, period, 1) + 0.5)
    return p - np.where(period > 0, period * cell, 0)


def op_repeat_limited(p, period, count):
    """Like `op_repeat`, but only cells -count..count (3,) along each axis hold a copy."""
    cell = np.clip(np.floor(p / np.where(period > 0, period, 1) + 0.5), -count, count)
    return p - np.where(period > 0, period * cell, 0)
