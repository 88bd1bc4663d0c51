"""Bodies that are not spheres: boxes and capsules, their mass, inertia and distance functions.

Every body of a `World` has a kind (`SPHERE`, `BOX`, `CAPSULE`, `CONVEX`) and, besides its
radius, an ``extent`` (3,) in its own frame::

    sphere    radius r                      extent (0, 0, 0)
    box       half sizes (a, b, c)          extent (a, b, c); radius = |(a, b, c)|, the
                                            bounding sphere's
    capsule   radius r around the segment   extent (0, l, 0): the segment runs from
              from -l to +l along local y   (0, -l, 0) to (0, +l, 0)
    convex    any convex SDF (convex.py)    extent: half sizes of the box holding its
                                            samples; radius: a sphere's holding it all

A body's orientation q (a unit quaternion) turns its own frame into the world's: a point p of
the body is at x + R(q) p. Its inertia is a tensor, diagonal in its own frame with the
principal moments `principal_inertia`, and R diag(I) R^T in the world's, which changes as the
body turns. What stays constant in free flight is the angular momentum L = I_world w, not w:
a tumbling box's w wanders (a book thrown about its middle axis flips over, the
"Dzhanibekov effect"), and `World.step` advances L, not w (docs/physics.md).

The moments (solid, uniform density rho; any mechanics text, e.g. Goldstein, Classical
Mechanics, 3rd ed., ch. 5)::

    sphere    I = 2/5 m r^2 about every axis
    box       I_x = m (b^2 + c^2) / 3, and so on (m/12 of the full sizes squared)
    capsule   a cylinder (mass m_c = rho pi r^2 2l) and two hemispheres (together a sphere,
              m_s = rho 4/3 pi r^3):
                I_y = m_c r^2 / 2 + 2/5 m_s r^2                            (about the axis)
                I_x = I_z = m_c (l^2 / 3 + r^2 / 4) + m_s (2/5 r^2 + l^2 + 3/4 l r)
              the last term is each hemisphere's 83/320 m r^2 about its own centre of mass,
              moved by Steiner's theorem to the capsule's centre, l + 3/8 r away.
"""

from __future__ import annotations

import numpy as np

from physics.quaternions import (quaternion_from_rotation_vector, quaternion_multiply,
                                 rotation_matrices)

SPHERE, BOX, CAPSULE, CONVEX = 0, 1, 2, 3
KIND_NAMES = ("sphere", "box", "capsule", "convex")
CAPSULE_SAMPLES = 5       # points along a capsule's segment tested against an SDF shape


def volume(kind, radius, extent) -> np.ndarray:
    """Volume (N,) in m^3 of bodies of ``kind`` (N,) with radius (N,) and extent (N, 3)."""
    sphere = 4 / 3 * np.pi * radius ** 3
    box = 8 * extent[:, 0] * extent[:, 1] * extent[:, 2]
    capsule = sphere + np.pi * radius ** 2 * 2 * extent[:, 1]
    return np.select([kind == BOX, kind == CAPSULE], [box, capsule], sphere)


def principal_inertia(kind, mass, radius, extent, gyration=None) -> np.ndarray:
    """Principal moments of inertia (N, 3) in kg m^2, about the body's own x, y, z axes.

    Parameters
    ----------
    kind : (N,) int
    mass, radius : (N,)
    extent : (N, 3)
        See the module docstring.
    gyration : (N, 3), optional
        A convex body's moments per unit mass, I / m (m^2, convex.py); needed where ``kind``
        has one.
    """
    sphere = 0.4 * mass * radius * radius
    a, b, c = extent[:, 0], extent[:, 1], extent[:, 2]
    box = mass[:, None] / 3 * np.stack([b * b + c * c, a * a + c * c, a * a + b * b], axis=1)
    # The capsule's mass split between its cylinder and its two end caps by their volumes.
    r, l = radius, extent[:, 1]
    cylinder_share = 2 * l / (2 * l + 4 / 3 * r)          # pi r^2 2l / (pi r^2 (2l + 4/3 r))
    m_c, m_s = mass * cylinder_share, mass * (1 - cylinder_share)
    along = m_c * r * r / 2 + 0.4 * m_s * r * r
    across = m_c * (l * l / 3 + r * r / 4) + m_s * (0.4 * r * r + l * l + 0.75 * l * r)
    capsule = np.stack([across, along, across], axis=1)
    convex = mass[:, None] * (np.zeros_like(box) if gyration is None else gyration)
    return np.select([(kind == BOX)[:, None], (kind == CAPSULE)[:, None],
                      (kind == CONVEX)[:, None]], [box, capsule, convex],
                     np.repeat(sphere[:, None], 3, axis=1))


def bounding_radius(kind, radius, extent) -> np.ndarray:
    """Radius (N,) of the smallest sphere about the centre that holds each body (m); a convex
    body's radius is already one that holds it."""
    corner = np.sqrt(np.sum(extent * extent, axis=1))
    return np.select([kind == BOX, kind == CAPSULE], [corner, extent[:, 1] + radius], radius)


def world_inverse_inertia(orientation, principal) -> np.ndarray:
    """I_world^-1 = R diag(1 / I) R^T, (N, 3, 3), for orientations (N, 4) and moments (N, 3)."""
    rotation = rotation_matrices(orientation)
    return np.einsum("nij,nj,nkj->nik", rotation, 1 / principal, rotation)


def world_inertia(orientation, principal) -> np.ndarray:
    """I_world = R diag(I) R^T, (N, 3, 3)."""
    rotation = rotation_matrices(orientation)
    return np.einsum("nij,nj,nkj->nik", rotation, principal, rotation)


def box_distance(p, half):
    """Exact signed distance from local points p (K, 3) to boxes of half sizes ``half`` (K, 3),
    and its gradient (K, 3), a unit vector.

    Outside, the nearest point is p clamped to the box: distance |max(q, 0)| with
    q = |p| - half, gradient sign(p) max(q, 0) / distance. Inside, the nearest face is the one
    of the largest q (the least negative), and the gradient is its normal. (Quilez,
    "distance functions", the same box SDF the renderer marches.) A point exactly on a middle
    plane counts as on the + side (sign(0) taken as +1), so the gradient is never 0.
    """
    side = np.where(p < 0, -1.0, 1.0).astype(p.dtype)
    q = np.abs(p) - half
    outside = np.maximum(q, 0)
    length = np.sqrt(np.sum(outside * outside, axis=1))
    inside = np.max(q, axis=1)
    nearest = np.argmax(q, axis=1)
    face = np.zeros_like(p)
    face[np.arange(len(p)), nearest] = 1
    is_out = length > 0
    distance = np.where(is_out, length, inside)
    gradient = side * np.where(is_out[:, None], outside / np.where(is_out, length, 1)[:, None],
                               face)
    return distance, gradient


def segment_closest(start, end, point) -> np.ndarray:
    """Parameter t in [0, 1] (K,) of the point of each segment start + t (end - start) nearest
    to ``point`` (K, 3) (Ericson, Real-Time Collision Detection, 2005, 5.1.2)."""
    d = end - start
    length2 = np.sum(d * d, axis=1)
    t = np.sum((point - start) * d, axis=1) / np.where(length2 > 0, length2, 1)
    return np.clip(t, 0, 1)


def segments_closest(p1, q1, p2, q2):
    """Parameters s, t in [0, 1] (K,) of the closest points p1 + s (q1 - p1) and
    p2 + t (q2 - p2) of two segments (Ericson, 2005, 5.1.9, with its parallel case: s = 0)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.sum(d1 * d1, axis=1)
    e = np.sum(d2 * d2, axis=1)
    f = np.sum(d2 * r, axis=1)
    c = np.sum(d1 * r, axis=1)
    b = np.sum(d1 * d2, axis=1)
    denominator = a * e - b * b
    parallel = denominator <= 1e-12 * a * e
    s = np.where(parallel, 0, np.clip((b * f - c * e) / np.where(parallel, 1, denominator),
                                      0, 1))
    t = (b * s + f) / e
    # t outside [0, 1]: clamp it and recompute s for the clamped t.
    s = np.where(t < 0, np.clip(-c / a, 0, 1), np.where(t > 1, np.clip((b - c) / a, 0, 1), s))
    t = np.clip(t, 0, 1)
    return s, t


def capsule_ends(position, orientation, extent):
    """The segment ends (K, 3), (K, 3) of capsules at ``position`` (K, 3)."""
    axis = rotation_matrices(orientation)[:, :, 1] * extent[:, 1:2]
    return position - axis, position + axis


def box_points(extent, which: str = "corners") -> np.ndarray:
    """Points of boxes in their own frames, (K, P, 3) for half sizes (K, 3).

    ``"corners"``: the 8 corners (P = 8), ordered by the signs (-,-,-), (-,-,+), ... as binary
    digits x, y, z. ``"surface"``: the 26 points of the 3 x 3 x 3 grid on the surface (corners,
    edge midpoints, face centres), what a box tests against an SDF shape.
    """
    steps = (-1.0, 1.0) if which == "corners" else (-1.0, 0.0, 1.0)
    grid = np.array([(i, j, k) for i in steps for j in steps for k in steps
                     if which == "corners" or max(abs(i), abs(j), abs(k)) == 1])
    return grid[None, :, :] * extent[:, None, :]


# The splitting of `free_rotation`: (body axis, fraction of the step), symmetric so that the
# method is second order and time-reversible.
SPLITTING = ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5))


def free_rotation(orientation, principal, momentum, h):
    """Turn bodies for a time h in free flight: new orientations (N, 4) and angular velocities
    (N, 3), keeping their world-frame angular momentum ``momentum`` (N, 3) exactly.

    The free rigid body's energy is the sum of three parts P_i^2 / (2 I_i), P the angular
    momentum in the body's own frame. The motion under one part alone is exact and simple: a
    turn about body axis i by the angle h P_i / I_i, while P, seen from the body, turns back
    by the same angle (so the world-frame L does not change). Composing the three in the
    symmetric order x, y, z, y, x (half, half, whole, half, half steps) is the splitting of
    Dullweber, Leimkuhler and McLachlan ("Symplectic splitting methods for rigid body
    molecular dynamics", J. Chem. Phys. 107, 1997): explicit, second order, symplectic. It
    keeps L exactly and the energy within O(h^2) of its start for as long as one runs, where
    turning by h w and then re-deriving w from L lets the energy drift away (a box spun
    about its middle axis gained 11% in 10 s).

    Parameters
    ----------
    orientation : (N, 4)
        Unit quaternions (w, x, y, z) at the start.
    principal : (N, 3)
        Principal moments (kg m^2).
    momentum : (N, 3)
        Angular momentum in the world frame (kg m^2 / s).
    h : float
        Time (s).
    """
    rotation = rotation_matrices(orientation)
    body_momentum = np.einsum("nji,nj->ni", rotation, momentum)     # P = R^T L
    q = orientation
    for axis, fraction in SPLITTING:
        angle = fraction * h * body_momentum[:, axis] / principal[:, axis]
        turn = np.zeros((len(q), 3), q.dtype)
        turn[:, axis] = angle
        # A turn about the body's own axis multiplies on the right: q <- q exp(angle e_i).
        q = quaternion_multiply(q, quaternion_from_rotation_vector(turn))
        cos, sin = np.cos(angle), np.sin(angle)
        j, k = (axis + 1) % 3, (axis + 2) % 3
        pj, pk = body_momentum[:, j].copy(), body_momentum[:, k].copy()
        body_momentum[:, j] = cos * pj + sin * pk
        body_momentum[:, k] = -sin * pj + cos * pk
    q = q / np.sqrt(np.sum(q * q, axis=1))[:, None]
    spin = np.einsum("nij,nj->ni", rotation_matrices(q), body_momentum / principal)
    return q.astype(orientation.dtype), spin.astype(orientation.dtype)
