"""Where a convex body (convex.py) meets something: its contact patch, found from support points.

A convex body touches a plane, a shape or another body in a **patch**, found here
(`contact_patch`):

- **its nearest point.** Against a plane of normal n, the support point along -n
  (convex.support), exact. Against a shape or a body, the point an alternating search
  ends at: from the body's sample nearest the other, s <- support(-grad d_other(s)) a few
  times, the other's normal telling the direction in which the body reaches deepest toward
  it; its fixed point has the two surfaces' normals opposite, the condition for the nearest
  points of two convex solids. It is kept only where it comes nearer than where it started.
- **the rest of the patch.** The support points along directions tilted `PATCH_TILT` from
  the nearest one's in `PATCH_DIRECTIONS` azimuths (Bullet's "perturbation" of a convex
  against a plane, btConvexPlaneCollisionAlgorithm, does the same for its contact manifold):
  where the body rests on a face or an edge they are its corners and rims, which hold it up;
  on a curved surface they lie higher than the nearest point by about rho PATCH_TILT^2 / 2
  and are left out (they are kept only within ``within`` of the nearest gap).

So a cylinder rolls on its side as smoothly as a ball, with one contact, and stands on its
end on a ring of them. Surface samples (convex.py) away from the patch are left to the swept
test (solid_sweeps.py): a sample met by a turning body is not a contact (a speculative
contact at a sample approaching by rotation would push the body away from a surface it only
rolls on).
"""

from __future__ import annotations

import numpy as np

from physics.colliders import FALLBACK_NORMAL
from physics.convex import SAME_SAMPLE, support
from physics.point_solver import tangent_basis
from physics.quaternions import rotation_matrices
from physics.solids import (BOX, CAPSULE, CONVEX, box_distance, capsule_ends, segment_closest)

NEAREST_STEPS = 6        # moves of the alternating search for a convex body's nearest point
PATCH_TILT = 0.2         # rad: the patch's directions, tilted this far from the nearest one's
PATCH_DIRECTIONS = 8     # ... in this many azimuths, evenly spaced


def unit_or_fallback(vector) -> np.ndarray:
    """Unit vectors (K, 3) along ``vector`` (K, 3), FALLBACK_NORMAL where it is 0."""
    length = np.sqrt(np.sum(vector * vector, axis=1))
    zero = ~(length > 0)
    return np.where(zero[:, None], np.asarray(FALLBACK_NORMAL, vector.dtype),
                    vector / np.where(zero, 1, length)[:, None])


def body_distance(world, j: int, points, pose=None):
    """Signed distance (K,) from world points (K, 3) to body j, and its outward unit normal
    there (K, 3), in float64, with the body where ``pose`` = (positions (N, 3),
    orientations (N, 4)) puts it (default: where the world has it)."""
    position, orientation = (world.position, world.orientation) if pose is None else pose
    return placed_distance(world, j, position[j], orientation[j], points)


def placed_distance(world, j: int, x, q, points):
    """`body_distance` with body j centred at x (3,) and turned by q (4,)."""
    x = np.asarray(x, np.float64)
    q = np.asarray(q, np.float64)[None, :]
    p = np.asarray(points, np.float64)
    kind = int(world.kind[j])
    if kind == CAPSULE:
        start, end = capsule_ends(x[None, :], q, np.asarray(world.extent[j:j + 1], np.float64))
        start, end = np.repeat(start, len(p), 0), np.repeat(end, len(p), 0)
        nearest = start + segment_closest(start, end, p)[:, None] * (end - start)
        apart = p - nearest
        return (np.sqrt(np.sum(apart * apart, axis=1)) - float(world.radius[j]),
                unit_or_fallback(apart))
    if kind not in (BOX, CONVEX):                                  # a sphere
        apart = p - x
        return (np.sqrt(np.sum(apart * apart, axis=1)) - float(world.radius[j]),
                unit_or_fallback(apart))
    rotation = rotation_matrices(q)[0]
    local = (p - x) @ rotation
    if kind == BOX:
        half = np.broadcast_to(np.asarray(world.extent[j], np.float64), local.shape)
        distance, gradient = box_distance(local, half)
    else:
        solid = world.solids[world.solid_of[j]]
        distance, gradient = solid.distance(local), unit_or_fallback(solid.normal(local))
    return distance, gradient @ rotation.T


def convex_support(world, j: int, direction, pose=None) -> np.ndarray:
    """World points (K, 3) of convex body j farthest along world unit directions (K, 3)."""
    position, orientation = (world.position, world.orientation) if pose is None else pose
    rotation = rotation_matrices(np.asarray(orientation[j:j + 1], np.float64))[0]
    solid = world.solids[world.solid_of[j]]
    local = support(solid, np.asarray(direction, np.float64) @ rotation)
    return np.asarray(position[j], np.float64) + local @ rotation.T


def nearest_point(world, j: int, other_distance, start, pose=None):
    """The point (3,) of convex body j nearest another solid, and its distance from it, by
    the alternating search of the module docstring from the point ``start`` (3,) of j's
    surface; ``other_distance(points (K, 3)) -> (distance (K,), normal (K, 3))``."""
    best = np.asarray(start, np.float64)[None, :]
    distance, normal = other_distance(best)
    best_distance = float(distance[0])
    for _ in range(NEAREST_STEPS):
        s = convex_support(world, j, -normal, pose)
        distance, turned = other_distance(s)
        if not float(distance[0]) < best_distance:
            break
        best, best_distance = s, float(distance[0])
        if np.sum((turned - normal) ** 2) <= 1e-24:      # the same direction: a fixed point
            break
        normal = turned
    return best[0], best_distance


def patch_directions(direction) -> np.ndarray:
    """`PATCH_DIRECTIONS` unit directions (P, 3), each `PATCH_TILT` from ``direction`` (3,)."""
    u = np.asarray(direction, np.float64)[None, :]
    t1, t2 = tangent_basis(u)
    azimuth = 2 * np.pi * np.arange(PATCH_DIRECTIONS) / PATCH_DIRECTIONS
    across = np.cos(azimuth)[:, None] * t1 + np.sin(azimuth)[:, None] * t2
    return np.cos(PATCH_TILT) * u + np.sin(PATCH_TILT) * across


def contact_patch(world, j: int, other_distance, start, within: float, pose=None):
    """Where convex body j touches another solid (module docstring).

    Parameters
    ----------
    world : physics.World
    j : int
        The convex body.
    other_distance : callable
        ``other_distance(points (K, 3))`` -> (signed distance (K,), outward unit normal
        (K, 3)) of the other solid, float64.
    start : (3,)
        A point of j's surface to start the search from (its sample nearest the other).
    within : float
        The patch's points are those at most this much (m) farther than the nearest.
    pose : tuple, optional
        (positions (N, 3), orientations (N, 4)) where the bodies are; default: the world's.

    Returns
    -------
    points (M, 3), gaps (M,), normals (M, 3) (the other's, at each), patch (M,) int: 0 for
    the nearest point, 1 + k for the direction k; float64, M >= 1.
    """
    nearest, _ = nearest_point(world, j, other_distance, start, pose)
    _, normal = other_distance(nearest[None, :])
    tilted = convex_support(world, j, patch_directions(-normal[0]), pose)
    points = np.concatenate([nearest[None, :], tilted])
    gaps, normals = other_distance(points)
    keep = np.flatnonzero(gaps <= gaps[0] + within)
    size = SAME_SAMPLE * float(world.radius[j])
    unique = [k for k in keep if not any(np.sum((points[k] - points[m]) ** 2) <= size * size
                                         for m in keep if m < k)]
    return points[unique], gaps[unique], normals[unique], np.asarray(unique)
