"""A readable rasteriser in NumPy: triangles to pixels, the reference of the raster pipeline.

What a GPU's fixed-function hardware does between the vertex and the fragment shader, step by
step, in the spirit of tinyrenderer (Sokolov, https://github.com/ssloy/tinyrenderer):

1. **Vertex transform.** Each vertex into the camera's frame (right, up, forward), with the
   same camera as the sphere tracer (`scene_model.camera`): the pixel whose centre a point
   projects to is the pixel whose ray goes through it (`scene_model.camera.project`).
2. **Near-plane clipping.** A triangle behind the eye has no image, and one that crosses the
   plane z = `NEAR` in front of it would project through infinity: it is cut at that plane
   into one or two triangles (Sutherland and Hodgman 1974), with its attributes interpolated
   along the cut edges.
3. **Edge functions** (Pineda 1988). Pixel centre p is inside triangle (a, b, c) when it lies
   on the inner side of all three edges: E_ab(p) = (b - a) x (p - a) > 0, and so on. The
   three values, divided by twice the area, are p's barycentric coordinates in the image.
4. **The fill rule.** A centre exactly on an edge shared by two triangles must be drawn by
   exactly one of them, or a mesh shows cracks or double-drawn pixels. Direct3D's *top-left*
   rule (OpenGL's implementations use the same) counts such a pixel for the triangle whose
   edge is a top edge (horizontal, above the triangle) or a left edge. "Exactly" needs exact
   arithmetic: like a GPU, the rasteriser snaps vertices to a fixed-point grid of
   1/`SUBPIXELS` of a pixel and evaluates the edge functions in integers, where a shared
   edge gives the two triangles exactly opposite values.
5. **Perspective-correct interpolation.** Barycentrics in the image are not barycentrics on
   the triangle in space: the image shrinks what is far. Attributes divided by each vertex's
   depth z interpolate linearly in the image, so a_p = (sum b_i a_i / z_i) / (sum b_i / z_i)
   (Heckbert and Moreton 1991). Depth, normals and texture coordinates are interpolated
   that way, from the exact (not snapped) image positions.
6. **The depth buffer.** Of the triangles covering a pixel the nearest is kept (Catmull
   1974). The buffer holds the distance t along the pixel's unit ray, as a marchlab `Frame`'s
   depth does, so the two pipelines' pictures compare pixel by pixel.

`rasterise_one_by_one` does all this one triangle at a time, as the steps read: the version
to read first. A Python loop pays NumPy's overhead per triangle, though, so `rasterise` by
default runs `rasterise_batched`: the same integer edge functions, fill rule and weights
on the pixels of many triangles at once (`draw_triangles`), and the depth test resolved as
the loop resolves it (`nearest_first`). It gives the same picture to the last bit
(tests/test_rasterise.py), which is why attributes are interpolated with `interpolate`
written out, not with a matrix product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.camera import Camera, camera_basis, camera_rays, to_camera, view_to_image
from scene_model.geometry import normalize
from scene_model.meshes import TriangleMesh

NEAR = 1e-3          # the near clipping plane, metres in front of the eye
SUBPIXELS = 256      # vertices snap to 1/256 of a pixel (8 bits: Direct3D 11's precision)


@dataclass(frozen=True)
class Raster:
    """What the rasteriser found at each pixel (H, W) of the image.

    Attributes
    ----------
    depth : (H, W) float64 ndarray
        Distance t along the pixel's unit ray to the surface drawn there; inf where none.
    normal : (H, W, 3) float64 ndarray
        Unit normal interpolated from the vertex normals; 0 where nothing is drawn.
    uv : (H, W, 2) float64 ndarray
        Interpolated texture coordinates; 0 where nothing is drawn.
    object_id : (H, W) int64 ndarray
        Index of the mesh drawn; -1 where none.
    triangle : (H, W) int64 ndarray
        Index of the triangle drawn, within its mesh; -1 where none.
    coverage : (H, W) int64 ndarray or None
        How many triangles covered the pixel's centre (depth test or not): the fill rule's
        check (a closed mesh's front faces cover each pixel of its image once). None from
        the GPU pipeline (`gpu_shader.raster`), which does not count them.
    """
    depth: np.ndarray
    normal: np.ndarray
    uv: np.ndarray
    object_id: np.ndarray
    triangle: np.ndarray
    coverage: np.ndarray | None

    @property
    def hit(self) -> np.ndarray:
        """(H, W) bool: whether a triangle was drawn at the pixel."""
        return self.object_id >= 0


def rasterise(meshes: list[TriangleMesh], camera: Camera, width: int, height: int,
              cull_back_faces: bool = False, textbook: bool = False) -> Raster:
    """Draw ``meshes`` as ``camera`` sees them at width x height pixels.

    ``textbook=True`` draws one triangle at a time (`rasterise_one_by_one`); by default many
    at once (`rasterise_batched`), the same `Raster` to the last bit, many times faster.
    The other parameters are `rasterise_one_by_one`'s.
    """
    draw = rasterise_one_by_one if textbook else rasterise_batched
    return draw(meshes, camera, width, height, cull_back_faces)


# --- One triangle at a time: the textbook rasteriser ---------------------------------------

def rasterise_one_by_one(meshes: list[TriangleMesh], camera: Camera, width: int, height: int,
                         cull_back_faces: bool = False) -> Raster:
    """Draw ``meshes`` as ``camera`` sees them at width x height pixels, triangle by triangle.

    Parameters
    ----------
    meshes : list of TriangleMesh
        In world coordinates; mesh k is object k.
    camera : Camera
    width, height : int
    cull_back_faces : bool
        Skip triangles that face away from the eye (wound clockwise on the screen, where an
        outward-wound face seen from outside turns anticlockwise): a closed mesh hides them
        anyway, and a GPU skips them before rasterising.

    Returns
    -------
    Raster
    """
    depth = np.full((height, width), np.inf)
    normal = np.zeros((height, width, 3))
    uv = np.zeros((height, width, 2))
    object_id = np.full((height, width), -1, np.int64)
    triangle_id = np.full((height, width), -1, np.int64)
    coverage = np.zeros((height, width), np.int64)
    # The length of each pixel's ray direction before normalising: t = z |d| for view depth z.
    stretch = ray_stretch(camera, width, height)
    for k, mesh in enumerate(meshes):
        for index, corners in clipped_triangles(mesh, camera):
            image, z, normals, uvs = project_corners(corners, camera, width, height)
            drawn = draw_triangle(image, z, cull_back_faces, (width, height))
            if drawn is None:
                continue
            (x0, y0), inside, weights = drawn
            rows, cols = np.nonzero(inside)
            rows, cols = rows + y0, cols + x0
            coverage[rows, cols] += 1
            w = weights[inside]                             # (P, 3) perspective-correct
            t = interpolate(w, z[:, None])[:, 0] * stretch[rows, cols]
            nearer = t < depth[rows, cols]
            rows, cols, w, t = rows[nearer], cols[nearer], w[nearer], t[nearer]
            depth[rows, cols] = t
            normal[rows, cols] = normalize(interpolate(w, normals))
            uv[rows, cols] = interpolate(w, uvs)
            object_id[rows, cols] = k
            triangle_id[rows, cols] = index
    return Raster(depth, normal, uv, object_id, triangle_id, coverage)


def ray_stretch(camera: Camera, width: int, height: int) -> np.ndarray:
    """|d| (H, W) of each pixel centre's ray direction d = forward + sx right + sy up before
    it is normalised: a point at view depth z along the pixel's ray is z |d| from the eye."""
    forward, _, _ = camera_basis(camera)
    _, directions = camera_rays(camera, width, height)
    return 1.0 / (directions @ forward)


def clipped_triangles(mesh: TriangleMesh, camera: Camera):
    """Yield (triangle index, corners) for every piece of ``mesh``'s triangles in front of
    the near plane; corners is a (3, 11) array of camera-frame position, normal, uv and the
    three barycentric coordinates within the original triangle (the clip's bookkeeping)."""
    view = to_camera(mesh.positions, camera)
    for index, corner_ids in enumerate(mesh.triangles):
        corners = np.concatenate([view[corner_ids], mesh.normals[corner_ids],
                                  mesh.uvs[corner_ids], np.eye(3)], axis=1)
        front = corners[:, 2] >= NEAR
        if front.all():
            yield index, corners
        elif front.any():
            for piece in clip_near(corners):
                yield index, piece


def clip_near(corners: np.ndarray) -> list[np.ndarray]:
    """The part of a triangle (3, A) (column 2: view depth z) with z >= `NEAR`, as one or
    two triangles: Sutherland-Hodgman against one plane, every attribute interpolated along
    the cut edges."""
    polygon = []
    for i in range(3):
        a, b = corners[i], corners[(i + 1) % 3]
        a_in, b_in = a[2] >= NEAR, b[2] >= NEAR
        if a_in:
            polygon.append(a)
        if a_in != b_in:
            s = (NEAR - a[2]) / (b[2] - a[2])
            cut = a + s * (b - a)
            cut[2] = NEAR
            polygon.append(cut)
    return [np.stack([polygon[0], polygon[i], polygon[i + 1]])
            for i in range(1, len(polygon) - 1)]


def project_corners(corners: np.ndarray, camera: Camera, width: int, height: int):
    """The image position (3, 2) in pixels (x right, y down, from the top-left corner), view
    depth z (3,), normals (3, 3) and uvs (3, 2) of a triangle's corners (3, A)."""
    return (view_to_image(corners[:, :3], camera, width, height), corners[:, 2],
            corners[:, 3:6], corners[:, 6:8])


def edge(ax, ay, bx, by, px, py):
    """The edge function of edge a -> b at p: (b - a) x (p - a), positive on its inner side
    for a triangle wound clockwise on the screen (positive area with y down)."""
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


def is_top_left(ax, ay, bx, by):
    """Whether edge a -> b of a clockwise triangle (y down) is a top edge (horizontal, going
    right: the triangle lies below it) or a left edge (going up). Written with & and | so
    that it takes arrays of edges too (`draw_triangles`)."""
    return ((ay == by) & (bx > ax)) | (by < ay)


def draw_triangle(image: np.ndarray, z: np.ndarray, cull_back_faces: bool = False,
                  size: tuple[int, int] | None = None):
    """The pixels whose centres a triangle covers, by the top-left rule.

    Parameters
    ----------
    image : (3, 2) float64
        Corners in pixels (x right, y down).
    z : (3,) float64
        Their view depths (> 0).
    size : (width, height), optional
        The image's size: pixels outside it are not drawn.

    Returns
    -------
    drawn : tuple or None
        None if it covers no pixel centre; else ``((x0, y0), inside, weights)``: the
        top-left pixel of its bounding box, which pixels of the box it covers ((h, w)
        bool), and their perspective-correct barycentric weights ((h, w, 3) float64).
    """
    fixed = np.round(image * SUBPIXELS).astype(np.int64)      # the snapped corners
    (ax, ay), (bx, by), (cx, cy) = fixed.tolist()
    area = edge(ax, ay, bx, by, cx, cy)
    if area == 0:
        return None                                           # seen edge-on
    # A face wound outward and seen from outside turns anticlockwise on the screen, which
    # with y down makes the area negative: a positive one is a back face.
    if area > 0 and cull_back_faces:
        return None
    # The rule below is written for clockwise corners (positive area): turn a front face.
    order = [0, 1, 2]
    if area < 0:
        order = [0, 2, 1]
        (bx, by), (cx, cy) = (cx, cy), (bx, by)
        area = -area
    low = np.floor(image.min(axis=0) - 0.5).astype(int)
    high = np.ceil(image.max(axis=0) - 0.5).astype(int)
    x0, y0 = max(low[0], 0), max(low[1], 0)
    x1, y1 = high[0], high[1]
    if size is not None:
        x1, y1 = min(x1, size[0] - 1), min(y1, size[1] - 1)
    if x1 < x0 or y1 < y0:
        return None
    # Pixel centres (i + 0.5, j + 0.5) in fixed point.
    px = (np.arange(x0, x1 + 1) * SUBPIXELS + SUBPIXELS // 2)[None, :]
    py = (np.arange(y0, y1 + 1) * SUBPIXELS + SUBPIXELS // 2)[:, None]
    w = [edge(bx, by, cx, cy, px, py),                        # opposite a
         edge(cx, cy, ax, ay, px, py),                        # opposite b
         edge(ax, ay, bx, by, px, py)]                        # opposite c
    owns = [is_top_left(bx, by, cx, cy), is_top_left(cx, cy, ax, ay),
            is_top_left(ax, ay, bx, by)]
    inside = np.ones(w[0].shape, bool)
    for value, own in zip(w, owns):
        inside &= (value > 0) | ((value == 0) & own)
    if not inside.any():
        return None
    # Weights from the exact image positions (the snap decides coverage only).
    corners = image[order]
    fx = np.arange(x0, x1 + 1)[None, :] + 0.5
    fy = np.arange(y0, y1 + 1)[:, None] + 0.5
    (ex, ey), (gx, gy), (hx, hy) = corners.tolist()
    total = edge(ex, ey, gx, gy, hx, hy)
    b = np.stack([edge(gx, gy, hx, hy, fx, fy), edge(hx, hy, ex, ey, fx, fy),
                  edge(ex, ey, gx, gy, fx, fy)], axis=-1) / total
    # Back in the triangle's own corner order, then made perspective-correct.
    screen = np.empty_like(b)
    screen[..., order] = b
    perspective = screen / z
    weights = perspective / perspective.sum(axis=-1, keepdims=True)
    return (x0, y0), inside, weights


def interpolate(weights: np.ndarray, values: np.ndarray) -> np.ndarray:
    """An attribute (P, C) at P fragments from their perspective-correct weights (P, 3) and
    its values at the corners: (3, C), one triangle's, or (P, 3, C), each fragment's own.

    w_a v_a + w_b v_b + w_c v_c written out, as `scene_model.geometry.dot` is, rather than
    ``weights @ values``: a matrix product goes to BLAS, whose fused multiply-adds round in
    a way that depends on the CPU and on the size of the product, and a fragment must come
    out to the same bits whether its triangle is drawn alone or among thousands.
    """
    return (weights[:, 0, None] * values[..., 0, :] + weights[:, 1, None] * values[..., 1, :]
            + weights[:, 2, None] * values[..., 2, :])


# --- Many triangles at once: the same arithmetic, without a Python loop per triangle -------

CHUNK = 1 << 20      # candidate pixels tested per step of `draw_triangles` (bounds memory)


def rasterise_batched(meshes: list[TriangleMesh], camera: Camera, width: int, height: int,
                      cull_back_faces: bool = False) -> Raster:
    """`rasterise_one_by_one`'s picture, to the last bit, from many triangles at a time.

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
    batches = [clipped_triangle_batch(mesh, camera) for mesh in meshes]
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


def clipped_triangle_batch(mesh: TriangleMesh, camera: Camera):
    """`clipped_triangles`'s pieces, in its order, as arrays: triangle index (N,) and
    corners (N, 3, 11). Triangles wholly in front of the near plane go through as they are;
    only the few that cross it go through `clip_near`, one at a time."""
    view = to_camera(mesh.positions, camera)
    ids = mesh.triangles
    bookkeeping = np.broadcast_to(np.eye(3), (len(ids), 3, 3))
    corners = np.concatenate([view[ids], mesh.normals[ids], mesh.uvs[ids], bookkeeping],
                             axis=2)
    front = corners[:, :, 2] >= NEAR
    whole = front.all(axis=1)
    index, pieces = [np.flatnonzero(whole)], [corners[whole]]
    for i in np.flatnonzero(front.any(axis=1) & ~whole):
        cut = clip_near(corners[i])
        index.append(np.full(len(cut), i))
        pieces.append(np.stack(cut))
    index, pieces = np.concatenate(index), np.concatenate(pieces)
    order = np.argsort(index, kind="stable")       # each piece in its triangle's place
    return index[order], pieces[order]


def project_corner_batch(corners: np.ndarray, camera: Camera, width: int, height: int):
    """`project_corners` of N triangles (N, 3, A): image (N, 3, 2), z (N, 3), normals
    (N, 3, 3) and uvs (N, 3, 2)."""
    image = view_to_image(corners[:, :, :3].reshape(-1, 3), camera, width, height)
    return (image.reshape(-1, 3, 2), corners[:, :, 2], corners[:, :, 3:6],
            corners[:, :, 6:8])


def winding(image: np.ndarray) -> np.ndarray:
    """(N,) int: the sign of each triangle's area (N, 3, 2) on the snapped grid, as
    `draw_triangle` finds it: +1 clockwise on the screen (y down), a back face; -1
    anticlockwise; 0 edge-on. In int64, exact while the corners lie within 2^30 subpixels
    of the origin; the rare triangle beyond (a corner near the near plane) in Python's
    unbounded integers."""
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
    only the integer edge functions may decide. A triangle with a corner beyond keeps its
    whole box: `draw_triangle`'s int64 edge functions may overflow there, and the loop's
    pixels are what they say.
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
