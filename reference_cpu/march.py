"""Sphere tracing (Hart 1996, "Sphere tracing: a geometric method for the antialiased ray
tracing of implicit surfaces").

Along a ray o + t d, the SDF value at the current point is the radius of a sphere that holds no
surface, so the ray may safely advance by it. The rules, identical in every backend:

- step i (1-based) evaluates d_i = |sdf(o + t d)|; ``steps`` is the number of evaluations;
- if d_i < epsilon the ray hits at the current t;
- else t += d_i, and if t > max_distance the ray misses;
- after max_steps evaluations without a hit the ray misses.

Stepping by |d| (not d) lets a ray that starts inside a solid walk out to its surface.
"""

from __future__ import annotations

import numpy as np


def march(origins, directions, sdf, max_steps, epsilon, max_distance):
    """March every ray until it hits, escapes, or runs out of steps.

    Parameters
    ----------
    origins : (3,) or (N, 3) ndarray
        Ray origins (one shared origin, or one per ray).
    directions : (N, 3) ndarray
        Unit ray directions.
    sdf : callable
        ``sdf(p)`` for ``p : (M, 3)`` returns ``(distance (M,), ...)``, as built by
        `reference_cpu.scene_sdf.build_scene_sdf`.
    max_steps : int
    epsilon : float
        Hit threshold on |distance|.
    max_distance : float or (N,) ndarray
        Distance beyond which a ray misses (per ray for shadow rays toward a light).

    Returns
    -------
    t : (N,) ndarray
        Distance to the hit along the ray; inf for a miss.
    steps : (N,) int32 ndarray
        SDF evaluations spent on each ray.
    hit : (N,) bool ndarray
    """
    n, dtype = len(directions), directions.dtype
    eps = dtype.type(epsilon)
    t_out = np.full(n, np.inf, dtype=dtype)
    steps = np.full(n, max_steps, dtype=np.int32)
    hit = np.zeros(n, dtype=bool)

    # The rays still marching, compacted: their index, origin, direction, t and limit.
    index = np.arange(n)
    o = origins
    d = directions
    t = np.zeros(n, dtype=dtype)
    limit = np.broadcast_to(np.asarray(max_distance, dtype=dtype), (n,))

    for step in range(1, max_steps + 1):
        dist = np.abs(sdf(o + t[:, None] * d)[0])
        arrived = dist < eps
        t_next = np.where(arrived, t, t + dist)
        escaped = t_next > limit
        finished = arrived | escaped
        if finished.any():
            done = index[finished]
            steps[done] = step
            hit[done] = arrived[finished]
            t_out[done[arrived[finished]]] = t[finished & arrived]
            keep = ~finished
            index, d, t_next, limit = index[keep], d[keep], t_next[keep], limit[keep]
            if o.ndim == 2:
                o = o[keep]
            if index.size == 0:
                break
        t = t_next
    return t_out, steps, hit
