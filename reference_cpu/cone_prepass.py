"""Cone marching: a safe distance to start each pixel's ray, found once per tile of pixels.

Neighbouring primary rays cross the same empty space: a floor pixel's ray spends most of its
steps in the air above the floor, as do the 63 rays around it. The pre-pass marches one cone
per tile of T x T pixels (the cone from the eye that holds every ray of the tile) and hands
each ray of the tile the distance the cone got to as its start. After the "cone marching" of
the demoscene (Aaltonen, "GPU-based clay simulation and ray-tracing tech in Claybook", GDC
2018) and the enhanced sphere tracing of Keinert et al. 2014.

Why a start is safe. Let the cone have apex o (the eye), unit axis a and half-angle theta.
At axial distance t its cross-section is a disc of radius t tan(theta) around c(t) = o + t a.
The SDF at c(t) is a distance d with no surface inside the sphere of radius d about c(t)
(|sdf| is a lower bound on the distance to the nearest surface: the same property every
sphere-tracing step relies on). That sphere holds every point of the cone with axial
distance in [t, t + delta] if the farthest such point, on the rim at t + delta, is within d:
its distance from c(t) is at most delta + (t + delta) tan(theta), so

    delta = (d - margin - t tan(theta)) / (1 + tan(theta))

keeps the cone between t and t + delta at least ``margin`` away from every surface. The
march takes these steps until delta is small (the cone has come close to a surface: see
`MIN_PROGRESS`) and ends at t_cone; every point of the cone nearer than t_cone along the axis is
at least ``margin`` from every surface. A ray of the tile, o + s u with u inside the cone,
has axial distance s (u . a) <= s, so its points with s <= t_cone lie in that part of the
cone: none is within ``margin`` of a surface. With ``margin`` = epsilon, the hit threshold,
plain sphere tracing of that ray could not have stopped before t_cone either: starting it
there skips only empty space. It does change where the ray samples the SDF afterwards, so a
ray that grazes a silhouette (passing within epsilon of a surface without meeting it) may
stop at the graze in one march and fly on in the other, as it may between float32 and
float64; the equivalence gates excuse exactly those pixels (docs/equivalence.md).

`tile_cones` gives each tile's axis and half-angle, `cone_march` marches them, and `start_distances`
spreads the result over the tile's pixels; `reference_cpu.march.march` takes it as ``start``.
"""

from __future__ import annotations

import math

import numpy as np

from scene_model.camera import camera_basis
from scene_model.scene import Camera

# A cone stops once a step would carry it less than this fraction of its own width
# (margin + t tan(theta)) further. Near a surface the steps shrink geometrically toward the
# point where the cone touches it (delta -> 0), so without this rule a cone spends most of
# its steps there: 163 evaluations per 8 x 8 tile of the classroom instead of about 20, for
# a start a fraction of a tile's width further on. Stopping sooner is always safe.
MIN_PROGRESS = 0.1


def tile_cones(camera: Camera, width: int, height: int, tile: int):
    """The cone of each tile of ``tile`` x ``tile`` pixels (tiles at the right and bottom
    edges may be smaller): the axis through the tile's centre and the half-angle that holds
    the rays through all four corners of the tile, so every pixel's ray.

    Returns
    -------
    axes : (TH, TW, 3) float64 ndarray
        Unit axis of each tile's cone, TH = ceil(H / tile) rows of TW = ceil(W / tile).
    tan_half_angles : (TH, TW) float64 ndarray
        tan(theta) of each cone, widened by 1e-9 (relative) against rounding.
    """
    forward, right, up = camera_basis(camera)
    half_height = math.tan(math.radians(camera.fov) / 2)
    half_width = half_height * width / height

    def image_plane(px, py):
        """The point of the image plane (distance 1 along forward) at pixel coordinates
        (px, py), counted from the top-left corner (as `camera_rays` aims)."""
        sx = (2 * px / width - 1) * half_width
        sy = (1 - 2 * py / height) * half_height
        return forward + sx[..., None] * right + sy[..., None] * up

    x0 = np.arange(0, width, tile, dtype=np.float64)
    y0 = np.arange(0, height, tile, dtype=np.float64)
    x1, y1 = np.minimum(x0 + tile, width), np.minimum(y0 + tile, height)
    X0, Y0 = np.meshgrid(x0, y0)
    X1, Y1 = np.meshgrid(x1, y1)
    axes = image_plane((X0 + X1) / 2, (Y0 + Y1) / 2)
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    cos_half = np.ones(X0.shape)
    for cx, cy in ((X0, Y0), (X1, Y0), (X0, Y1), (X1, Y1)):
        corner = image_plane(cx, cy)
        corner /= np.linalg.norm(corner, axis=-1, keepdims=True)
        cos_half = np.minimum(cos_half, np.sum(corner * axes, axis=-1))
    cos_half = np.clip(cos_half, -1.0, 1.0)
    tan_half = np.sqrt(1 - cos_half ** 2) / cos_half
    return axes, tan_half * (1 + 1e-9)


def cone_march(origin, axes, tan_half_angles, sdf, max_steps: int, margin: float,
               max_distance: float, start=None):
    """March cones from ``origin`` along ``axes`` (N, 3) with half-angles whose tangents are
    ``tan_half_angles`` (N,): how far along its axis each cone stays at least ``margin``
    from every surface, and the SDF evaluations that took.

    Each step evaluates d = |sdf(c(t))| and advances by (d - margin - t tan) / (1 + tan);
    a cone stops when that is less than `MIN_PROGRESS` of its width (margin + t tan), when
    t passes ``max_distance``, or after ``max_steps`` evaluations. Float64 throughout.
    ``start`` (N,), optional: where each cone starts (a distance a wider cone holding it has
    shown safe), else 0.

    Returns
    -------
    t : (N,) float64 ndarray
        The safe axial distance of each cone (0 where it cannot leave the eye).
    steps : (N,) int32 ndarray
        SDF evaluations spent on each cone.
    """
    n = len(axes)
    t = np.zeros(n) if start is None else np.array(start, np.float64)
    steps = np.zeros(n, np.int32)
    live = np.ones(n, bool)
    origin = np.asarray(origin, np.float64)
    for _ in range(max_steps):
        index = np.flatnonzero(live)
        if not len(index):
            break
        d = np.abs(sdf(origin + t[index, None] * axes[index])[0])
        steps[index] += 1
        delta = (d - margin - t[index] * tan_half_angles[index]) / (1 + tan_half_angles[index])
        moving = delta > MIN_PROGRESS * (margin + t[index] * tan_half_angles[index])
        t[index[moving]] += delta[moving]
        live[index[~moving]] = False
        live[index[moving]] &= t[index[moving]] <= max_distance
    return t, steps


def start_distances(camera: Camera, width: int, height: int, sdf, tile: int, max_steps: int,
                    epsilon: float, max_distance: float):
    """Where each pixel's primary ray may start: its tile's `cone_march` distance, with the
    hit threshold ``epsilon`` as the margin (see the module's proof).

    Returns
    -------
    start : (H, W) float64 ndarray
        Safe start distance of each pixel's ray.
    tile_steps : (TH, TW) int32 ndarray
        SDF evaluations of each tile's cone: the pre-pass's cost, shared by its pixels.
    """
    axes, tan_half = tile_cones(camera, width, height, tile)
    shape = tan_half.shape
    t, steps = cone_march(camera.position, axes.reshape(-1, 3), tan_half.reshape(-1), sdf,
                          max_steps, epsilon, max_distance)
    t, steps = t.reshape(shape), steps.reshape(shape)
    start = np.repeat(np.repeat(t, tile, axis=0), tile, axis=1)[:height, :width]
    return start, steps
