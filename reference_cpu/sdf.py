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


def sdf_pyramid(p, base, height):
    """Square pyramid along y: base of side ``base`` on y = 0, apex at y = ``height``.

    Quilez's exact pyramid (sdPyramid, written for a base of side 1), here in true lengths for
    the half side s = base / 2 and height h, and with the base face, which sdPyramid leaves
    out (below y = 0, and inside next to the base, it is not the distance).

    Folded by symmetry onto 0 <= z <= x, the nearest side is the +x face. Measured from the
    base corner (s, 0, s), that face's plane has the outward unit normal (h, s) / L in (x, y),
    where L = sqrt(h^2 + s^2) is the slant height. In the plane, with coordinates (z, ``up``),
    the half face is the triangle (0, 0), (-s, 0), (-s, L). The distance is Pythagoras' sum of
    the height ``above`` the plane and the distance, in the plane, from the point's foot to
    that triangle: 0 if the foot is on it, else to the nearer of its base edge and its
    slanted edge. Below the base plane the nearest point is on the base square instead.
    """
    s, h = 0.5 * base, height
    ax, az = np.abs(p[:, 0]), np.abs(p[:, 2])
    x = np.maximum(ax, az) - s                  # the fold, from the corner (s, 0, s)
    z = np.minimum(ax, az) - s
    y = p[:, 1]
    slant = np.sqrt(h * h + s * s)
    above = (h * x + s * y) / slant             # height above the face's plane
    up = (h * y - s * x) / slant                # up the face, from the base edge
    # Squared distances to the base edge (up = 0, z <= 0) and, by clamped projection, to the
    # slanted edge from the corner (0, 0) to the apex (-s, L).
    edge = np.maximum(z, 0)
    edge2 = edge * edge + up * up
    t = np.clip((slant * up - s * z) / (s * s + slant * slant), 0, 1)
    ex, ey = z + s * t, up - slant * t
    # The foot is on the face where up > 0 and it is inside the slanted edge (L z + s up < 0).
    on_face = np.minimum(up, -(slant * z + s * up)) > 0
    d2 = np.where(on_face, 0, np.minimum(edge2, ex * ex + ey * ey))
    # Inside where below the face's plane and above the base plane; the base may be nearer.
    sides = np.sqrt(d2 + above * above) * np.sign(np.maximum(above, -y))
    # Below the base plane the solid lies above it and within the base square's outline, so
    # the nearest point is on the square, as for a flat box.
    bx, bz = np.maximum(x, 0), np.maximum(z, 0)
    below = np.sqrt(bx * bx + bz * bz + y * y)
    return np.where(y < 0, below, np.maximum(sides, -y))


def sdf_disk(p, radius, thickness):
    """Round disk in the xz-plane, ``radius`` wide and ``thickness`` thick, its rim rounded.

    The distance to the flat circle of radius a = radius - thickness / 2 in the plane y = 0
    (its nearest point is p's foot in the plane, pulled in to the circle's rim), minus the
    rounding thickness / 2: Quilez's rounding operator on an exact distance to a convex set,
    which is exact again (his rounded cylinder with height 0).
    """
    rounding = 0.5 * thickness
    rim = length2(p[:, 0], p[:, 2]) - (radius - rounding)
    return length2(np.maximum(rim, 0), p[:, 1]) - rounding


# cos 30 degrees and tan 30 degrees, the hexagon's constants in sdf_hex_prism.
COS_30 = 0.8660254037844386
TAN_30 = 0.5773502691896258


def sdf_hex_prism(p, apothem, half_length):
    """Hexagonal prism along z: a regular hexagon in the xy-plane with flat sides at
    y = +-``apothem`` (its corners on the x axis), from z = -``half_length`` to +``half_length``.

    Quilez's sdHexPrism. By symmetry p is folded into x, y >= 0, then mirrored across the
    line at 60 degrees (unit normal k = (-cos 30, 1/2)) that maps the slanted side onto the
    top one; the hexagon's signed distance is then the distance to the top side (y = apothem,
    |x| <= apothem tan 30), negative below it. The prism is that 2-D shape extruded along z,
    which combines like a 2-D box: outside, the length of the positive parts; inside, the
    larger (less negative) of the two.
    """
    x, y, z = np.abs(p[:, 0]), np.abs(p[:, 1]), np.abs(p[:, 2])
    fold = 2.0 * np.minimum(-COS_30 * x + 0.5 * y, 0)
    x = x + fold * COS_30
    y = y - fold * 0.5
    half_side = TAN_30 * apothem
    dy = y - apothem
    hexagon = length2(x - np.clip(x, -half_side, half_side), dy) * np.sign(dy)
    along = z - half_length
    outside = length2(np.maximum(hexagon, 0), np.maximum(along, 0))
    inside = np.minimum(np.maximum(hexagon, along), 0)
    return inside + outside


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


def op_morph(d1, d2, t):
    """Shape 1 turning into shape 2 as ``t`` goes from 0 to 1: (1 - t) d1 + t d2.

    A linear interpolation of two distances (GLSL's ``mix``). For t in [0, 1] it is
    1-Lipschitz when d1 and d2 are, and so a distance bound in Hart's sense (J. C. Hart,
    "Sphere tracing", The Visual Computer 12(10), 1996): safe to march, but not an exact
    distance. Written as two products and a sum (not d1 + t (d2 - d1)) so that t = 0 gives
    d1 and t = 1 gives d2 exactly.
    """
    return (1 - t) * d1 + t * d2


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
