"""The NumPy rasteriser's batched twin: `reference_cpu.rasterise`'s steps on many triangles at once.

`rasterise_one_by_one` pays NumPy's overhead once per triangle. `rasterise_batched` runs the
same steps without a Python loop per triangle: every mesh's triangles clipped together
(`clipped_triangle_batch`, with the textbook's `clip_triangle` for the few that cross a
clipping plane), projected together, and their pixels found by the same integer edge
functions, fill rule and weights (`draw_triangles`), about a million candidate pixels at a
time. The depth test is resolved as the loop resolves it (`nearest_first`). It gives the
loop's picture to the last bit (tests/test_rasterise.py), and `rasterise` runs it by
default.
"""

from __future__ import annotations

import numpy as np

from scene_model.camera import Camera, to_camera, view_to_image
from scene_model.geometry import normalize
from scene_model.meshes import TriangleMesh

from .rasterise import (SUBPIXELS, Raster, clip_planes, clip_triangle, edge, interpolate,
                        is_top_left, plane_distances, ray_stretch)

CHUNK = 1 << 20      # candidate pixels tested per step of `draw_triangles` (bounds memory)


def rasterise_batched(meshes: list[TriangleMesh], camera: Camera, width: int, height: int,
                      cull_back_faces: bool = False) -> Raster:
    """`reference_cpu.rasterise.rasterise_one_by_one`'s picture, to the last bit, from many
    triangles at a time.

    The loop lets a later triangle take a pixel only when it is strictly nearer, so what a
    pixel keeps is, of all the fragments drawn on it, the first (in drawing order: mesh by
    mesh, triangle by triangle) of the nearest: `nearest_first` finds it among a batch's
    fragments, and it replaces what the buffer holds from earlier batches only when
    strictly nearer.
    """
    pixels = width * height
    depth = np.full(pixels, np.inf)
    normal = np.zeros((pixels, 3))
    uv = np.zeros((pixels, 2))
    object_id = np.full(pixels, -1, np.int64)
    triangle_id = np.full(pixels, -1, np.int64)
    coverage = np.zeros(pixels, np.int64)
    stretch = ray_stretch(camera, width, height).ravel()
    # Every mesh's triangles in one list, in drawing order, each with its mesh's number.
    batches = [clipped_triangle_batch(mesh, camera, (width, height)) for mesh in meshes]
    index = np.concatenate([i for i, _ in batches] or [np.zeros(0, np.int64)])
    corners = np.concatenate([c for _, c in batches] or [np.zeros((0, 3, 11))])
    mesh_of = np.repeat(np.arange(len(meshes)), [len(i) for i, _ in batches])
    image, z, normals, uvs = project_corner_batch(corners, camera, width, height)
    for tri, rows, cols, weights in draw_triangles(image, z, cull_back_faces, (width, height)):
        pixel = rows * width + cols
        coverage += np.bincount(pixel, minlength=pixels)
        t = interpolate(weights, z[tri, :, None])[:, 0] * stretch[pixel]
        won = nearest_first(pixel, t)
        won = won[t[won] < depth[pixel[won]]]
        p, w, tw = pixel[won], weights[won], tri[won]
        depth[p] = t[won]
        normal[p] = normalize(interpolate(w, normals[tw]))
        uv[p] = interpolate(w, uvs[tw])
        object_id[p] = mesh_of[tw]
        triangle_id[p] = index[tw]
    return Raster(depth.reshape(height, width), normal.reshape(height, width, 3),
                  uv.reshape(height, width, 2), object_id.reshape(height, width),
                  triangle_id.reshape(height, width), coverage.reshape(height, width))


def nearest_first(key: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Indices of the fragments a sequential depth test keeps: for each distinct ``key``
    (P,) (a pixel), the first of those with the least ``t`` (P,) (NaN never wins; fmin
    skips it), fragments being given in drawing order."""
    nearest = np.full(int(key.max(initial=-1)) + 1, np.inf)
    np.fmin.at(nearest, key, t)
    candidates = np.flatnonzero(t == nearest[key])
    first = np.full(len(nearest), len(t))
    np.minimum.at(first, key[candidates], candidates)
    return first[first < len(t)]


def clipped_triangle_batch(mesh: TriangleMesh, camera: Camera,
                           size: tuple[int, int] | None = None):
    """`reference_cpu.rasterise.clipped_triangles`'s pieces, in its order, as arrays:
    triangle index (N,) and corners (N, 3, 11). Triangles wholly inside the clipping planes
    go through as they are, those wholly outside one are dropped, and only the few that
    cross one go through `clip_triangle`, one at a time."""
    planes = clip_planes(camera, size)
    view = to_camera(mesh.positions, camera)
    ids = mesh.triangles
    bookkeeping = np.broadcast_to(np.eye(3), (len(ids), 3, 3))
    corners = np.concatenate([view[ids], mesh.normals[ids], mesh.uvs[ids], bookkeeping],
                             axis=2)
    inner = plane_distances(planes, view)[ids] >= 0          # (N, 3, P)
    whole = inner.all(axis=(1, 2))
    index, pieces = [np.flatnonzero(whole)], [corners[whole]]
    for i in np.flatnonzero(inner.any(axis=1).all(axis=1) & ~whole):
        cut = clip_triangle(corners[i], planes)
        index.append(np.full(len(cut), i))
        pieces.append(np.stack(cut).reshape(-1, 3, corners.shape[2]))
    index, pieces = np.concatenate(index), np.concatenate(pieces)
    order = np.argsort(index, kind="stable")       # each piece in its triangle's place
    return index[order], pieces[order]


def project_corner_batch(corners: np.ndarray, camera: Camera, width: int, height: int):
    """`reference_cpu.rasterise.project_corners` of N triangles (N, 3, A): image (N, 3, 2),
    z (N, 3), normals (N, 3, 3) and uvs (N, 3, 2)."""
    image = view_to_image(corners[:, :, :3].reshape(-1, 3), camera, width, height)
    return (image.reshape(-1, 3, 2), corners[:, :, 2], corners[:, :, 3:6],
            corners[:, :, 6:8])


def winding(image: np.ndarray) -> np.ndarray:
    """(N,) int: the sign of each triangle's area (N, 3, 2) on the snapped grid, as
    `draw_triangle` finds it: +1 clockwise on the screen (y down), a back face; -1
    anticlockwise; 0 edge-on. In int64, exact while the corners lie within 2^30 subpixels
    of the origin, as every corner `clipped_triangle_batch` gives does (the guard band,
    `reference_cpu.rasterise.clip_planes`); a triangle beyond, given here unclipped, in
    Python's unbounded integers."""
    fixed = np.round(image * SUBPIXELS).astype(np.int64)
    (ax, ay), (bx, by), (cx, cy) = fixed.transpose(1, 2, 0)
    area = np.sign(edge(ax, ay, bx, by, cx, cy))
    far = np.flatnonzero(np.abs(fixed).max(axis=(1, 2), initial=0) >= 2**30)
    for i in far:
        area[i] = np.sign(edge(*fixed[i].ravel().tolist()))
    return area


def draw_triangles(image: np.ndarray, z: np.ndarray, cull_back_faces: bool = False,
                   size: tuple[int, int] = (0, 0), chunk: int | None = None):
    """The pixels whose centres N triangles cover: `draw_triangle`'s arithmetic, on many
    triangles' pixels at once, about ``chunk`` pixels at a time.

    `draw_triangle` tests every pixel of a triangle's bounding box; a long thin triangle
    across the picture (a shadow volume's side) covers a sliver of it. Here the candidates
    are, on each row of the box, the pixels near the row's crossing of the triangle
    (`row_spans`), and the same integer edge functions and fill rule decide among them.

    Parameters
    ----------
    image : (N, 3, 2) float64
        Corners in pixels (x right, y down).
    z : (N, 3) float64
        Their view depths (> 0).
    cull_back_faces : bool
    size : (width, height)
        The image's size: pixels outside it are not drawn.
    chunk : int, optional
        How many candidate pixels to test at once (the memory it takes); `CHUNK` if None.

    Yields
    ------
    triangle, row, col : (P,) int64 ndarrays
        The covered pixels, triangle by triangle in order, each's row by row (as
        ``np.nonzero(inside)`` gives them).
    weights : (P, 3) float64 ndarray
        Their perspective-correct barycentric weights, the bits `draw_triangle` gives.
    """
    width, height = size
    chunk = CHUNK if chunk is None else chunk
    sign = winding(image)
    # The fill rule is written for clockwise corners: turn the others, b and c swapped.
    order = np.where(sign[:, None] < 0, [0, 2, 1], [0, 1, 2])
    clockwise = np.take_along_axis(image, order[:, :, None], axis=1)
    fixed = np.round(clockwise * SUBPIXELS).astype(np.int64)
    low = np.floor(image.min(axis=1) - 0.5).astype(int)
    high = np.ceil(image.max(axis=1) - 0.5).astype(int)
    x0, y0 = np.maximum(low[:, 0], 0), np.maximum(low[:, 1], 0)
    x1, y1 = np.minimum(high[:, 0], width - 1), np.minimum(high[:, 1], height - 1)
    drawn = (sign != 0) & ~((sign > 0) & cull_back_faces) & (x1 >= x0) & (y1 >= y0)
    a, b, c = fixed.transpose(1, 2, 0)                     # each (2, N): x and y
    edges = [(b, c), (c, a), (a, b)]                       # opposite a, b and c
    owns = [np.broadcast_to(is_top_left(*p, *q), sign.shape) for p, q in edges]
    # Weights from the exact image positions (the snap decides coverage only).
    (ex, ey), (gx, gy), (hx, hy) = clockwise.transpose(1, 2, 0)
    total = edge(ex, ey, gx, gy, hx, hy)
    rows = np.where(drawn, y1 - y0 + 1, 0)
    for group in chunks_of(rows, max(chunk // 16, 1)):
        # Every row of each box, then the span of its columns worth testing.
        tri = np.repeat(group, rows[group])
        row = y0[tri] + ranks(rows[group])
        first, last = row_spans(fixed[tri], row, x0[tri], x1[tri])
        span = np.maximum(last - first + 1, 0)
        for part in chunks_of(span, chunk):
            t, n = tri[part], span[part]
            step = ranks(n)                                # columns right of the first
            px = first[part] * SUBPIXELS + SUBPIXELS // 2
            py = row[part] * SUBPIXELS + SUBPIXELS // 2
            # Each edge function at the row's first centre, then stepped along the row: it
            # is linear, E(x + 1, y) = E(x, y) - (q_y - p_y) SUBPIXELS (Pineda 1988), and in
            # integers the steps give exactly the values draw_triangle finds afresh.
            inside = np.ones(len(step), bool)
            for (p, q), own in zip(edges, owns):
                value = (np.repeat(edge(p[0, t], p[1, t], q[0, t], q[1, t], px, py), n)
                         - np.repeat((q[1, t] - p[1, t]) * SUBPIXELS, n) * step)
                # > 0, or = 0 on an edge the triangle owns (the top-left rule)
                inside &= value >= np.repeat(np.where(own[t], 0, 1), n)
            at = np.repeat(np.arange(len(t)), n)[inside]   # the row of each covered pixel
            t, r, col = t[at], row[part][at], first[part][at] + step[inside]
            fx, fy = col + 0.5, r + 0.5
            w_a = edge(gx[t], gy[t], hx[t], hy[t], fx, fy) / total[t]
            w_b = edge(hx[t], hy[t], ex[t], ey[t], fx, fy) / total[t]
            w_c = edge(ex[t], ey[t], gx[t], gy[t], fx, fy) / total[t]
            # Back in the triangle's own corner order, then made perspective-correct.
            turned = sign[t] < 0
            screen = np.stack([w_a, np.where(turned, w_c, w_b), np.where(turned, w_b, w_c)],
                              axis=-1)
            perspective = screen / z[t]
            weights = perspective / perspective.sum(axis=-1, keepdims=True)
            yield t, r, col, weights


def row_spans(fixed: np.ndarray, row: np.ndarray, x0: np.ndarray, x1: np.ndarray):
    """The columns ``first`` to ``last`` (R,) of the pixels on ``row`` (R,) whose centres may
    lie in the triangle with snapped corners ``fixed`` (R, 3, 2), within its box's columns
    ``x0`` to ``x1`` (R,); first > last where none can.

    The row's centre line y crosses the triangle between the leftmost and the rightmost of
    its crossings with the three edges. They are found in floating point, to well under a
    subpixel for corners within 2^30 subpixels, and rounded outwards to whole pixels, since
    only the integer edge functions may decide. A triangle with a corner beyond (never one
    clipped at the guard band) keeps its whole box: `draw_triangle`'s int64 edge functions
    may overflow there, and the loop's pixels are what they say.
    """
    y = (row * SUBPIXELS + SUBPIXELS // 2).astype(np.float64)
    corners = fixed.astype(np.float64)
    left, right = np.full(len(row), np.inf), np.full(len(row), -np.inf)
    for i in range(3):
        (ax, ay), (bx, by) = corners[:, i].T, corners[:, (i + 1) % 3].T
        crosses = (np.minimum(ay, by) <= y) & (y <= np.maximum(ay, by)) & (ay != by)
        x = ax + (y - ay) * (bx - ax) / np.where(crosses, by - ay, 1.0)
        left = np.where(crosses, np.minimum(left, x), left)
        right = np.where(crosses, np.maximum(right, x), right)
    met = right >= left
    # Column i's centre lies at (i + 1/2) SUBPIXELS: from left / SUBPIXELS - 1/2 on.
    first = np.floor(np.where(met, left, 0.0) / SUBPIXELS - 0.5).astype(np.int64)
    last = np.ceil(np.where(met, right, 0.0) / SUBPIXELS - 0.5).astype(np.int64)
    far = np.abs(fixed).max(axis=(1, 2), initial=0) >= 2**30
    first = np.where(far, x0, np.where(met, np.maximum(first, x0), 1))
    last = np.where(far, x1, np.where(met, np.minimum(last, x1), 0))
    return first, last


def ranks(count: np.ndarray) -> np.ndarray:
    """0, 1, ..., count[0] - 1, 0, 1, ..., count[1] - 1, ...: each item's place in its run."""
    return np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)


def chunks_of(count: np.ndarray, chunk: int):
    """Yield the indices of consecutive items with a nonzero ``count`` (N,) in groups whose
    counts add up to at most ``chunk`` (or one item, if its count is more)."""
    counted = np.flatnonzero(count)
    end = np.cumsum(count[counted])
    start = 0
    while start < len(counted):
        before = end[start - 1] if start else 0
        stop = max(int(np.searchsorted(end, before + chunk, side="right")), start + 1)
        yield counted[start:stop]
        start = stop
