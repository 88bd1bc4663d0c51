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

`tile_cones` gives each tile's axis and half-angle, `cone_march` marches them, and
`start_distances` spreads the result over the tile's pixels; `reference_cpu.march.march` takes
it as ``start``. All of it runs in the render's precision, with the operations of
glsl/cone.glsl in the same order, so the OpenCL program finds the same starts to the bit and
the gpu backend's float32 ones to within rounding. The scene setting is
``render.prepass = "cone"`` with ``render.prepass_tile`` pixels a side.
"""

from __future__ import annotations

import numpy as np

from scene_model.camera import image_rays
from scene_model.scene import Camera

# A cone stops once a step would carry it less than this fraction of its own width
# (margin + t tan(theta)) further. Near a surface the steps shrink geometrically toward the
# point where the cone touches it (delta -> 0), so without this rule a cone spends most of
# its steps there: 163 evaluations per 8 x 8 tile of the classroom instead of about 20, for
# a start a fraction of a tile's width further on. Stopping sooner is always safe.
MIN_PROGRESS = 0.1
# Added to each cone's tan(theta): the corner directions are unit vectors rounded to the
# render's precision (about 1e-7 in float32), so the measured angle may come out that much
# too small; 1e-6 keeps every ray of the tile inside its cone whatever the rounding.
CONE_SLACK = 1e-6


def tile_grid(width: int, height: int, tile: int) -> tuple[int, int]:
    """(TW, TH): the columns and rows of ``tile`` x ``tile`` tiles that cover a width x height
    image, the last of each cut by the image's edge."""
    return -(-width // tile), -(-height // tile)


def tile_pixels(width: int, height: int, tile: int) -> np.ndarray:
    """(TH, TW) int: how many pixels each tile holds (fewer at the right and bottom edges)."""
    widths = np.minimum(tile, width - np.arange(0, width, tile))
    heights = np.minimum(tile, height - np.arange(0, height, tile))
    return np.outer(heights, widths)


def over_pixels(per_tile: np.ndarray, width: int, height: int, tile: int) -> np.ndarray:
    """(H, W): each pixel given its tile's value of ``per_tile`` (TH, TW)."""
    return np.repeat(np.repeat(per_tile, tile, axis=0), tile, axis=1)[:height, :width]


def tile_cones(camera: Camera, width: int, height: int, tile: int, dtype=np.float64):
    """The cone of each tile of ``tile`` x ``tile`` pixels (tiles at the right and bottom
    edges may be smaller): the axis through the tile's centre and the half-angle that holds
    the rays through all four corners of the tile, so the ray through every point of the
    tile (the cone is convex, and such a ray's direction is a positive combination of the
    corners'): every pixel's ray, and every anti-aliasing sample's, which lies inside its
    pixel (`scene_model.sampling`). ``tile_cone`` in glsl/cone.glsl, for every tile at once.

    The angle between the axis a and a corner's ray r is measured as
    tan = |a x r| / (a . r): for the small angles of a tile, 1 - cos^2 would lose most of
    its digits to cancellation (0.08 % of tan(theta) in float32 at 8 pixels a tile).

    Returns
    -------
    axes : (TH, TW, 3) ndarray of ``dtype``
        Unit axis of each tile's cone, TH = ceil(H / tile) rows of TW = ceil(W / tile).
    tan_half_angles : (TH, TW) ndarray of ``dtype``
        tan(theta) of each cone, plus `CONE_SLACK`.
    """
    dtype = np.dtype(dtype)
    tiles_wide, tiles_high = tile_grid(width, height, tile)
    x0 = np.arange(tiles_wide, dtype=dtype)[None, :] * dtype.type(tile)
    y0 = np.arange(tiles_high, dtype=dtype)[:, None] * dtype.type(tile)
    x1 = np.minimum(x0 + dtype.type(tile), dtype.type(width))
    y1 = np.minimum(y0 + dtype.type(tile), dtype.type(height))
    x0, y0, x1, y1 = np.broadcast_arrays(x0, y0, x1, y1)
    half = dtype.type(0.5)
    axes = image_rays(camera, half * (x0 + x1), half * (y0 + y1), width, height, dtype)
    widest = np.zeros(x0.shape, dtype)
    for cx, cy in ((x0, y0), (x1, y0), (x0, y1), (x1, y1)):
        widest = np.maximum(widest, cone_tan(axes, image_rays(camera, cx, cy, width, height,
                                                              dtype)))
    return axes, widest + dtype.type(CONE_SLACK)


def cone_tan(axis, ray):
    """tan of the angle between unit vectors ``axis`` and ``ray`` (..., 3): |a x r| / (a . r),
    with the products in the order of GLSL's ``cross`` and ``dot``."""
    a, r = axis, ray
    c = np.stack([a[..., 1] * r[..., 2] - a[..., 2] * r[..., 1],
                  a[..., 2] * r[..., 0] - a[..., 0] * r[..., 2],
                  a[..., 0] * r[..., 1] - a[..., 1] * r[..., 0]], axis=-1)
    return np.sqrt(_dot(c, c)) / _dot(a, r)


def _dot(a, b):
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def cone_march(origin, axes, tan_half_angles, sdf, max_steps: int, margin: float,
               max_distance: float):
    """March cones from ``origin`` along ``axes`` (N, 3) with half-angles whose tangents are
    ``tan_half_angles`` (N,): how far along its axis each cone stays at least ``margin``
    from every surface, and the SDF evaluations that took. ``cone_march`` of glsl/cone.glsl.

    Each step evaluates d = |sdf(c(t))|, the cone's width w = margin + t tan and
    delta = (d - w) / (1 + tan); a cone stops when delta is at most `MIN_PROGRESS` w,
    else advances by delta and stops once t passes ``max_distance``; at most ``max_steps``
    evaluations. The precision is that of ``axes``.

    Returns
    -------
    t : (N,) ndarray
        The safe axial distance of each cone (0 where it cannot leave the eye).
    steps : (N,) int32 ndarray
        SDF evaluations spent on each cone.
    """
    dtype = axes.dtype
    n = len(axes)
    t = np.zeros(n, dtype)
    steps = np.zeros(n, np.int32)
    live = np.ones(n, bool)
    origin = np.asarray(origin, dtype)
    margin, max_distance = dtype.type(margin), dtype.type(max_distance)
    one, progress = dtype.type(1), dtype.type(MIN_PROGRESS)
    for _ in range(max_steps):
        index = np.flatnonzero(live)
        if not len(index):
            break
        d = np.abs(sdf(origin + t[index, None] * axes[index])[0])
        steps[index] += 1
        tan = tan_half_angles[index]
        width = margin + t[index] * tan
        delta = (d - width) / (one + tan)
        moving = delta > progress * width
        t[index[moving]] += delta[moving]
        live[index[~moving]] = False
        live[index[moving]] &= t[index[moving]] <= max_distance
    return t, steps


def start_distances(camera: Camera, width: int, height: int, sdf, tile: int, max_steps: int,
                    epsilon: float, max_distance: float, dtype=np.float64):
    """Where each pixel's primary ray may start: its tile's `cone_march` distance, with the
    hit threshold ``epsilon`` as the margin (see the module's proof), in ``dtype`` (``sdf``
    evaluates in it too).

    Returns
    -------
    start : (H, W) ndarray of ``dtype``
        Safe start distance of each pixel's ray.
    tile_steps : (TH, TW) int32 ndarray
        SDF evaluations of each tile's cone: the pre-pass's cost, shared by its pixels.
    """
    axes, tan_half = tile_cones(camera, width, height, tile, dtype)
    shape = tan_half.shape
    t, steps = cone_march(camera.position, axes.reshape(-1, 3), tan_half.reshape(-1), sdf,
                          max_steps, epsilon, max_distance)
    t, steps = t.reshape(shape), steps.reshape(shape)
    return over_pixels(t, width, height, tile), steps
