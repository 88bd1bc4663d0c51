"""Sphere tracing (Hart 1996, "Sphere tracing: a geometric method for the antialiased ray
tracing of implicit surfaces").

Along a ray o + t d, the SDF value at the current point is the radius of a sphere that holds no
surface, so the ray may safely advance by it. The rules, identical in every backend:

- step i (1-based) evaluates d_i = |sdf(o + t d)|; ``steps`` is the number of evaluations;
- if d_i < epsilon the ray hits at the current t;
- else t += d_i, and if t > max_distance the ray misses;
- after max_steps evaluations without a hit the ray misses.

Stepping by |d| (not d) lets a ray that starts inside a solid walk out to its surface.

Read `textbook_march` first: Hart's loop and nothing else. `march`, which the renderer calls,
gives the same t, steps and hit to the last bit (tests/test_march.py checks it on every bundled
scene) and adds what makes it fast: it drops finished rays from its arrays, and it takes two
render settings that change how far a step goes, never where a ray may stop
(`reference_cpu.relaxation` states their rules): over-relaxation steps omega d_i instead of
d_i and steps back when that may have skipped a surface, and bounding-sphere culling
(`reference_cpu.culling`) leaves out of each ray's SDF the objects it cannot reach.
"""

from __future__ import annotations

import numpy as np

from .relaxation import Relaxation


def textbook_march(origins, directions, sdf, max_steps, epsilon, max_distance, start=None):
    """Sphere tracing as Hart (1996) writes it: every ray steps by |sdf| until it hits or misses.

    All rays step together, as NumPy arrays; ``marching`` says which of them have neither hit
    nor missed yet, and only those move. `march` returns the same results, faster.

    Parameters
    ----------
    origins : (3,) or (N, 3) ndarray
        Ray origins (one shared origin, or one per ray).
    directions : (N, 3) ndarray
        Unit ray directions; their dtype (float32 or float64) is the precision of the march.
    sdf : callable
        ``sdf(p)`` for ``p : (M, 3)`` returns ``(distance (M,), ...)``, as built by
        `reference_cpu.scene_sdf.build_scene_sdf`.
    max_steps : int
        SDF evaluations allowed per ray.
    epsilon : float
        A ray hits where |sdf| < epsilon.
    max_distance : float or (N,) ndarray
        A ray misses once t > max_distance (one limit per ray for shadow rays).
    start : (N,) ndarray, optional
        Where each ray starts (default 0): a distance known to hold no surface within
        epsilon of the ray before it (`reference_cpu.cone_prepass`).

    Returns
    -------
    t : (N,) ndarray
        Distance to the hit along the ray; inf for a miss.
    steps : (N,) int32 ndarray
        SDF evaluations spent on each ray.
    hit : (N,) bool ndarray
    """
    n, dtype = len(directions), directions.dtype
    epsilon, max_distance = dtype.type(epsilon), np.asarray(max_distance, dtype)
    t = np.zeros(n, dtype) if start is None else np.array(start, dtype)
    t_hit = np.full(n, np.inf, dtype)
    steps = np.full(n, max_steps, np.int32)      # a ray that never stops uses every step
    hit = np.zeros(n, bool)
    marching = np.ones(n, bool)
    for step in range(1, max_steps + 1):
        d = np.abs(sdf(origins + t[:, None] * directions)[0])   # no surface within d,
        arrived = marching & (d < epsilon)
        hit[arrived], t_hit[arrived] = True, t[arrived]
        t = np.where(marching, t + d, t)                         # so a step of d is safe
        escaped = marching & ~arrived & (t > max_distance)
        steps[arrived | escaped] = step
        marching &= ~(arrived | escaped)
        if not marching.any():
            break
    return t_hit, steps, hit


def march(origins, directions, sdf, max_steps, epsilon, max_distance, observe=None, *,
          relaxation="none", omega=1.2, bounds=None, start=None, objects=None):
    """March every ray until it hits, escapes, or runs out of steps: `textbook_march`, fast.

    With ``relaxation="none"`` and no ``bounds`` the results are those of `textbook_march`,
    bit for bit. What is added is speed: the rays still marching are kept in a working set
    that finished rays leave, so each step costs in proportion to the rays left, and the two
    optional features below make the steps longer or the SDF cheaper.

    Parameters
    ----------
    origins : (3,) or (N, 3) ndarray
        Ray origins (one shared origin, or one per ray).
    directions : (N, 3) ndarray
        Unit ray directions.
    sdf : callable
        ``sdf(p)`` for ``p : (M, 3)`` returns ``(distance (M,), ...)``, as built by
        `reference_cpu.scene_sdf.build_scene_sdf`; with ``bounds``, it is called as
        ``sdf(p, objects)`` with the (M, objects) mask of the objects each ray may reach.
    max_steps : int
    epsilon : float
        Hit threshold on |distance|.
    max_distance : float or (N,) ndarray
        Distance beyond which a ray misses (per ray for shadow rays toward a light).
    observe : callable, optional
        Called every step as ``observe(index, t, distance, step)`` with the pixel index,
        current t and |SDF| of each ray still marching (soft shadows use it).
    relaxation : {"none", "fixed", "auto"}
        How far a step goes (`reference_cpu.relaxation`); ``omega`` is the fixed factor.
    bounds : reference_cpu.culling.BoundingSpheres, optional
        Bounding-sphere culling: each ray's SDF leaves out the objects it cannot reach.
    start : (N,) ndarray, optional
        Where each ray starts, as in `textbook_march` (the cone pre-pass's distances).
    objects : (N, K) bool ndarray, optional
        The objects each ray's SDF may keep at most (False: left out), K the scene's
        top-level objects; a shadow ray leaves out the convex object it starts on
        (`reference_cpu.shadows`). With ``bounds`` too, a ray keeps what both keep.

    Returns
    -------
    t, steps, hit : (N,) ndarray
        As `textbook_march` returns them: the distance to the hit (inf for a miss), the SDF
        evaluations spent (int32) and whether the ray hit.
    """
    n, dtype = len(directions), directions.dtype
    eps = dtype.type(epsilon)
    t_out = np.full(n, np.inf, dtype=dtype)
    steps = np.full(n, max_steps, dtype=np.int32)
    hit = np.zeros(n, dtype=bool)

    # The working set: pixel index, origin, direction, t and limit of each ray still in it,
    # and `live`, which of them are still marching. Dropping finished rays (compacting) costs
    # about as much as a step, so it is done once a quarter of the working set has finished;
    # until then finished rays ride along and their results are ignored.
    index = np.arange(n)
    o = columns(origins) if origins.ndim == 2 else origins
    d = columns(directions)
    t = np.zeros(n, dtype=dtype) if start is None else np.array(start, dtype=dtype)
    limit = np.asarray(max_distance, dtype=dtype)      # a scalar, or one limit per ray
    live = np.ones(n, dtype=bool)
    # Per-ray state of the optional features, compacted with the rest.
    extra = {}
    kept = objects
    if bounds is not None:
        met = bounds.objects_met(o, d)
        kept = met if objects is None else met & objects
    if kept is not None:
        extra["objects"] = kept
        scene_sdf = lambda p: sdf(p, extra["objects"])
    else:
        scene_sdf = sdf
    relax = None
    if relaxation != "none":
        relax = Relaxation(relaxation, omega, n, dtype)

    for step in range(1, max_steps + 1):
        signed = scene_sdf(o + t[:, None] * d)[0]
        dist = np.abs(signed)
        if observe is not None:
            observe(index[live], t[live], dist[live], step)
        if relax is None:
            t_next = t + dist
            arrived = live & (dist < eps)
            finished = arrived | (live & (t_next > limit))
        else:
            # A step that may have skipped a surface is taken back; that point decides nothing.
            t_next, valid = relax.step(t, signed)
            arrived = live & valid & (dist < eps)
            finished = arrived | (live & valid & (t + dist > limit))
        if finished.any():
            steps[index[finished]] = step
            hit[index[arrived]] = True
            t_out[index[arrived]] = t[arrived]
            live &= ~finished
            if not live.any():
                break
            if live.sum() < 0.75 * len(live):
                keep = live
                index, d, t_next, live = index[keep], columns(d[keep]), t_next[keep], live[keep]
                if o.ndim == 2:
                    o = columns(o[keep])
                if limit.ndim == 1:
                    limit = limit[keep]
                extra = {name: value[keep] for name, value in extra.items()}
                if relax is not None:
                    relax.keep(keep)
        if not live.all():
            # Finished rays that ride along stay where they stopped: stepping on, a ray
            # that escaped would double its t each step and overflow float32.
            np.copyto(t_next, t, where=~live)
        t = t_next
    return t_out, steps, hit


def columns(a: np.ndarray) -> np.ndarray:
    """The same (N, 3) array stored column by column (Fortran order).

    NumPy runs fastest along long contiguous runs; with rows of 3 its inner loops are 3 long.
    Storing x, y and z each contiguously makes the SDF arithmetic several times faster
    without changing any shape or value.
    """
    return np.asfortranarray(a)
