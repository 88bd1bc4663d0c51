"""Exact ray intersections (float64) with unions of spheres, boxes and planes.

Each primitive gives, for every ray o + t d, the interval [t_in, t_out] of t where the ray is
inside its solid, and the outward normals where it enters and leaves. The scene is the union of
the primitives, so the surface a ray meets first is

- for a ray that starts outside every solid: the nearest entry t_in >= 0;
- for a ray that starts inside some solid: where it leaves the union of the intervals that
  overlap the one it is in (marching by |sdf| walks out to that surface too; see march.py).

Everything is computed in the primitive's own frame (`reference_cpu.truth.parts`): the ray is
moved there by the inverse similarity, keeping its parameter t, and the normals are turned back.
"""

from __future__ import annotations

import numpy as np

from scene_model.errors import SceneError
from scene_model.geometry import dot
from scene_model.shapes import Box, Plane, Sphere

from .parts import Part

ANALYTIC_KINDS = (Sphere, Box, Plane)


def check_analytic(parts: list[Part]) -> None:
    """Raise `SceneError` naming the first part that is not a sphere, box or plane."""
    for part in parts:
        if not isinstance(part.leaf, ANALYTIC_KINDS):
            raise SceneError(f"{part.leaf.kind!r} has no analytic intersection (the analytic "
                             "method takes unions of spheres, boxes and planes); use "
                             "--method embree", part.path)


# --- One primitive: the interval where the ray is inside -------------------------------------
# Each function takes local ray origins o (N, 3) and directions d (N, 3), d not necessarily
# unit length, and returns t_in (N,), t_out (N,), n_in (N, 3), n_out (N, 3). A ray that misses
# gets t_in = inf, t_out = -inf (an empty interval).

def interval_sphere(o, d, radius):
    """Ray inside the sphere |x| <= radius.

    Solving |o + t d|^2 = r^2 as a d.d t^2 + 2 (o.d) t + (o.o - r^2) = 0 by the school formula
    loses precision twice (Haines et al., "Precision improvements for ray/sphere
    intersection", Ray Tracing Gems, ch. 7, 2019):

    - the discriminant b^2 - a c cancels when the ray passes far from the centre; written as
      r^2 - |l|^2, with l the vector from the centre to the closest point of the line, it
      does not;
    - -b + sqrt(disc) cancels for the far root when b is large; the other root is c / q with
      q = -(b + sign(b) sqrt(disc)) (Press et al., Numerical Recipes, 3rd ed., section 5.6).

    The roots are found along the unit direction u = d / |d| and divided by |d| to give t.
    """
    length = np.sqrt(dot(d, d))
    u = d / length[:, None]
    b = dot(o, u)                                   # the "half b" of the quadratic in s
    closest = o - b[:, None] * u                    # centre-to-line vector l
    disc = radius * radius - dot(closest, closest)
    c = dot(o, o) - radius * radius
    root = np.sqrt(np.maximum(disc, 0.0))
    q = -(b + np.copysign(root, b))                 # s1 = q (a = 1), s2 = c / q
    with np.errstate(divide="ignore", invalid="ignore"):
        s1, s2 = q, np.where(q != 0, c / q, 0.0)    # q = 0 only for b = disc = 0: s = 0
    hits = disc >= 0
    t_in = np.where(hits, np.minimum(s1, s2) / length, np.inf)
    t_out = np.where(hits, np.maximum(s1, s2) / length, -np.inf)
    # The normal is the radial direction at the hit; |x| = r there, so x / r is unit.
    n_in = (o + np.where(hits, t_in, 0.0)[:, None] * d) / radius
    n_out = (o + np.where(hits, t_out, 0.0)[:, None] * d) / radius
    return t_in, t_out, _unit(n_in), _unit(n_out)


def interval_box(o, d, half_size):
    """Ray inside the box |x_k| <= h_k: Kay and Kajiya's slab test (SIGGRAPH 1986).

    The ray is inside the slab |x_k| <= h_k for t between (-h_k - o_k) / d_k and
    (h_k - o_k) / d_k; inside the box where it is inside all three slabs: from the latest
    entry to the earliest exit. The axis of the latest entry names the face entered, whose
    outward normal points against d; likewise the earliest exit's. A ray parallel to a slab
    (d_k = 0) is inside it for all t or for none, decided by o_k (Williams et al., "An
    efficient and robust ray-box intersection algorithm", JGT 2005, discuss the IEEE cases).
    """
    h = np.asarray(half_size, dtype=np.float64)
    parallel = d == 0
    with np.errstate(divide="ignore", invalid="ignore"):
        t_lo = (-h - o) / d
        t_hi = (h - o) / d
    near = np.minimum(t_lo, t_hi)
    far = np.maximum(t_lo, t_hi)
    inside_slab = np.abs(o) <= h
    near = np.where(parallel, np.where(inside_slab, -np.inf, np.inf), near)
    far = np.where(parallel, np.where(inside_slab, np.inf, -np.inf), far)

    entry_axis = np.argmax(near, axis=1)
    exit_axis = np.argmin(far, axis=1)
    rows = np.arange(len(o))
    t_in = near[rows, entry_axis]
    t_out = far[rows, exit_axis]
    hits = t_in <= t_out
    n_in = np.zeros_like(o)
    n_out = np.zeros_like(o)
    n_in[rows, entry_axis] = -np.sign(d[rows, entry_axis])
    n_out[rows, exit_axis] = np.sign(d[rows, exit_axis])
    return (np.where(hits, t_in, np.inf), np.where(hits, t_out, -np.inf), n_in, n_out)


def interval_plane(o, d, normal, offset):
    """Ray inside the half-space n . x <= offset, with n the unit outward normal.

    n . (o + t d) <= offset holds for t >= (offset - n.o) / (n.d) when the ray goes down
    (n.d < 0), for t <= that when it goes up, and for all t or none when it runs parallel.
    """
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.sqrt(dot(n, n))
    height = offset - dot(o, n)                     # >= 0 where the origin is inside
    rate = dot(d, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = height / rate
    down, up, inside = rate < 0, rate > 0, height >= 0
    t_in = np.where(down, t, np.where(up | inside, -np.inf, np.inf))
    t_out = np.where(up, t, np.where(down | inside, np.inf, -np.inf))
    normals = np.broadcast_to(n, o.shape)
    return t_in, t_out, normals.copy(), normals.copy()


def interval_part(part: Part, origin, directions):
    """The interval of one part along world rays: the primitive's, in world t and normals."""
    o = part.to_local(np.broadcast_to(origin, directions.shape))
    d = part.direction_to_local(directions)
    leaf = part.leaf
    if isinstance(leaf, Sphere):
        t_in, t_out, n_in, n_out = interval_sphere(o, d, leaf.radius)
    elif isinstance(leaf, Box):
        t_in, t_out, n_in, n_out = interval_box(o, d, leaf.half_size)
    else:
        t_in, t_out, n_in, n_out = interval_plane(o, d, leaf.normal, leaf.offset)
    return t_in, t_out, part.normal_to_world(n_in), part.normal_to_world(n_out)


# --- The union --------------------------------------------------------------------------------

def first_surface(t_in, t_out, n_in, n_out):
    """Where each ray first crosses the boundary of the union of the intervals.

    Parameters
    ----------
    t_in, t_out : (P, N) ndarray
        Interval of each of P parts along each of N rays (t_in > t_out: empty).
    n_in, n_out : (P, N, 3) ndarray
        Outward normals at the entries and exits.

    Returns
    -------
    t : (N,) ndarray
        Distance to the surface, inf where there is none at t >= 0.
    normal : (N, 3) ndarray
        Unit outward normal there, 0 on a miss.
    part : (N,) int ndarray
        Index of the part whose surface it is, -1 on a miss.
    """
    n_rays = t_in.shape[1]
    rays = np.arange(n_rays)
    inside = (t_in < 0) & (t_out > 0)

    # Outside every solid: the nearest entry ahead.
    ahead = np.where(t_in >= 0, t_in, np.inf)
    part = np.argmin(ahead, axis=0)
    t = ahead[part, rays]
    normal = n_in[part, rays]

    # Inside one: leave it, then keep extending through every interval that overlaps (closed
    # intervals: touching solids are one solid). Each pass adds at least one interval, so P
    # passes are enough.
    started_inside = inside.any(axis=0)
    if started_inside.any():
        exits = np.where(inside, t_out, -np.inf)
        leave = np.argmax(exits, axis=0)
        reach = exits[leave, rays]
        for _ in range(t_in.shape[0]):
            overlaps = (t_in <= reach) & (t_out > reach) & started_inside
            if not overlaps.any():
                break
            longer = np.where(overlaps, t_out, -np.inf)
            best = np.argmax(longer, axis=0)
            grow = overlaps.any(axis=0)
            leave = np.where(grow, best, leave)
            reach = np.where(grow, longer[best, rays], reach)
        t = np.where(started_inside, reach, t)
        part = np.where(started_inside, leave, part)
        normal = np.where(started_inside[:, None], n_out[leave, rays], normal)

    missed = ~np.isfinite(t)
    t = np.where(missed, np.inf, t)
    normal = np.where(missed[:, None], 0.0, normal)
    part = np.where(missed, -1, part)
    return t, normal, part


def trace_analytic(parts: list[Part], origin, directions):
    """First hit of world rays with the union of analytic parts.

    Parameters
    ----------
    parts : list of Part
        Spheres, boxes and planes (see `check_analytic`).
    origin : (3,) ndarray
    directions : (N, 3) float64 ndarray
        Unit ray directions.

    Returns
    -------
    t : (N,) ndarray
        Depth along the ray (inf on a miss).
    normal : (N, 3) ndarray
        Unit outward normal (0 on a miss).
    object_id : (N,) int32 ndarray
        Object id of the primitive hit (-1 on a miss).
    """
    check_analytic(parts)
    n = len(directions)
    if not parts:
        return np.full(n, np.inf), np.zeros((n, 3)), np.full(n, -1, np.int32)
    intervals = [interval_part(part, origin, directions) for part in parts]
    t_in, t_out, n_in, n_out = (np.stack(column) for column in zip(*intervals))
    t, normal, index = first_surface(t_in, t_out, n_in, n_out)
    ids = np.array([part.first_id for part in parts], dtype=np.int32)
    object_id = np.where(index >= 0, ids[np.maximum(index, 0)], -1).astype(np.int32)
    return t, normal, object_id


def _unit(v):
    """v / |v| along the last axis, leaving zero vectors zero."""
    length = np.sqrt(dot(v, v))
    return v / np.where(length > 0, length, 1.0)[..., None]
