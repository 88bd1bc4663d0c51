"""A readable rasteriser in NumPy: triangles to pixels, the reference of the raster pipeline.

What a GPU's fixed-function hardware does between the vertex and the fragment shader, step by
step, in the spirit of tinyrenderer (Sokolov, https://github.com/ssloy/tinyrenderer):

1. **Vertex transform.** Each vertex into the camera's frame (right, up, forward), with the
   same camera as the sphere tracer (`scene_model.camera`): the pixel whose centre a point
   projects to is the pixel whose ray goes through it (`scene_model.camera.project`).
2. **Clipping.** A triangle behind the eye has no image, and one that crosses the plane
   z = `NEAR` in front of it would project through infinity: it is cut at that plane
   (Sutherland and Hodgman 1974), its attributes interpolated along the cut edges. It is
   also cut at four planes `GUARD_BAND` pixels outside the image's sides, as a GPU's
   guard-band clipper does, so that no corner lands so far off screen that the integer edge
   functions of step 3 overflow (`clip_planes`).
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
default runs its batched twin (`reference_cpu.rasterise_batched`), which gives the same
picture to the last bit (tests/test_rasterise.py); that is why attributes are interpolated
with `interpolate` written out, not with a matrix product.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scene_model.camera import Camera, camera_basis, camera_rays, to_camera, view_to_image
from scene_model.geometry import normalize
from scene_model.meshes import TriangleMesh

NEAR = 1e-3          # the near clipping plane, metres in front of the eye
SUBPIXELS = 256      # vertices snap to 1/256 of a pixel (8 bits: Direct3D 11's precision)
GUARD_BAND = 2**16   # pixels beyond each side of the image where triangles are cut
NEAR_PLANE = (0.0, 0.0, 1.0, -NEAR)    # z - NEAR >= 0, as `clip_planes` writes planes


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


def rasterise_batched(meshes: list[TriangleMesh], camera: Camera, width: int, height: int,
                      cull_back_faces: bool = False) -> Raster:
    """`reference_cpu.rasterise_batched.rasterise_batched`, imported when called.

    That module is built from this one's steps and imports them: the one import back, here,
    is the single cycle the import-linter contract allows (pyproject.toml says so).
    """
    from . import rasterise_batched as batched
    return batched.rasterise_batched(meshes, camera, width, height, cull_back_faces)


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
        for index, corners in clipped_triangles(mesh, camera, (width, height)):
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


def clipped_triangles(mesh: TriangleMesh, camera: Camera,
                      size: tuple[int, int] | None = None):
    """Yield (triangle index, corners) for every piece of ``mesh``'s triangles inside the
    clipping planes (`clip_planes`); corners is a (3, 11) array of camera-frame position,
    normal, uv and the three barycentric coordinates within the original triangle (the
    clip's bookkeeping). Without the image's ``size`` (width, height) the near plane alone
    clips."""
    planes = clip_planes(camera, size)
    view = to_camera(mesh.positions, camera)
    distance = plane_distances(planes, view)               # (V, P): >= 0 on the inner side
    for index, corner_ids in enumerate(mesh.triangles):
        corners = np.concatenate([view[corner_ids], mesh.normals[corner_ids],
                                  mesh.uvs[corner_ids], np.eye(3)], axis=1)
        inner = distance[corner_ids] >= 0                  # (3, P)
        if inner.all():
            yield index, corners
        elif inner.any(axis=0).all():                      # not wholly outside any plane
            for piece in clip_triangle(corners, planes):
                yield index, piece


def clip_planes(camera: Camera, size: tuple[int, int] | None = None) -> np.ndarray:
    """The clipping planes (P, 4), each (n, w) keeping the camera-frame points v where
    n . v + w >= 0: the near plane z >= `NEAR`, and, given the image's ``size`` (width,
    height), four planes through the eye that project to the lines `GUARD_BAND` pixels
    outside the image's sides.

    With f = H / (2 tan(fov / 2)) pixels per unit of x / z, a point projects to
    x_img = W / 2 + f x / z and y_img = H / 2 - f y / z (`scene_model.camera.view_to_image`);
    for z > 0, -G <= x_img <= W + G reads f x + (W / 2 + G) z >= 0 and -f x + (W / 2 + G) z
    >= 0, and likewise in y. A GPU clips at such a guard band rather than at the image's
    edges (Blinn, "Calculating Screen Coverage", IEEE CG&A 16(3), 1996; Giesen, "A trip
    through the Graphics Pipeline 2011, part 5", https://fgiesen.wordpress.com/2011/07/05/
    a-trip-through-the-graphics-pipeline-2011-part-5/): a triangle that crosses only the
    image's edges is drawn whole, its pixels outside skipped, and only the rare one reaching
    far beyond is cut.

    Why G = 2^16 pixels. After the cut every corner lies within [-G, W + G] x [-G, H + G],
    W and H at most 2^14 (`scene_model.camera.MAX_SIDE`), so a snapped coordinate is at
    most B = 256 (2^16 + 2^14) + 1 < 2^24.33 subpixels from the origin, up to the rounding
    of the cut (a few ulps: far below a subpixel). An edge function (b - a) x (p - a), p a
    pixel centre inside the image, is a difference of two products of factors under
    2B < 2^25.33, so below 2^51.7 in size: far inside int64 (to 2^63). Before, a corner cut
    at the near plane could land 2^40 subpixels off screen, and the products wrapped round.
    The band also bounds the rounding of the weights, found in floating point from the
    corners' image positions: it grows with their distance (on a 10 km floor, measured: 1e-11
    relative in depth at G = 2^12, 1e-10 at 2^16, 3e-9 at 2^20).

    Why the picture does not change. The planes lie 65536 pixels outside the image: a
    cut replaces a triangle by its part inside them, the same set of points wherever the
    image is, with new corners that lie on the triangle's edges, out there. Attributes vary
    linearly along an edge in space, and the cut interpolates them with the same fraction
    as the position, so a cut corner carries the very values the edge had there. Inside
    the image the only change is the snap of the new corners to 1/256 of a pixel, like any
    corner's: a pixel centre within that of a cut edge's line may fall to either side.
    """
    planes = [NEAR_PLANE]
    if size is not None:
        width, height = size
        f = height / (2 * math.tan(math.radians(camera.fov) / 2))
        half_w, half_h = width / 2 + GUARD_BAND, height / 2 + GUARD_BAND
        planes += [(f, 0.0, half_w, 0.0), (-f, 0.0, half_w, 0.0),      # left, right
                   (0.0, -f, half_h, 0.0), (0.0, f, half_h, 0.0)]      # top, bottom
    return np.array(planes)


def plane_distances(planes: np.ndarray, view: np.ndarray) -> np.ndarray:
    """n . v + w (N, P) of N camera-frame points (N, 3) for P planes (P, 4): positive on the
    side kept. Written out, not as a matrix product, so that a point gets the same bits
    alone or among many (see `interpolate`)."""
    n = planes.T[:, None, :]                               # (4, 1, P)
    return (n[0] * view[:, 0, None] + n[1] * view[:, 1, None] + n[2] * view[:, 2, None]
            + n[3])


def clip_triangle(corners: np.ndarray, planes: np.ndarray) -> list[np.ndarray]:
    """The part of a triangle (3, A) (columns 0 to 2: camera-frame position) inside every
    plane of ``planes`` (P, 4), as triangles (3, A): cut at each plane in turn
    (`clip_polygon`), then fanned from the first corner."""
    polygon = corners
    for plane in planes:
        polygon = clip_polygon(polygon, plane_distances(plane[None], polygon[:, :3])[:, 0])
    return [np.stack([polygon[0], polygon[i], polygon[i + 1]])
            for i in range(1, len(polygon) - 1)]


def clip_polygon(polygon: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """The part (K', A) of a convex polygon (K, A) where ``distance`` (K,), its corners'
    signed distances to a plane, is >= 0: Sutherland and Hodgman (1974) against one plane.
    Walk round the corners, keep those inside, and where an edge crosses the plane add the
    point a fraction s = d_a / (d_a - d_b) of the way along it, every attribute
    interpolated."""
    kept = []
    for i in range(len(polygon)):
        j = (i + 1) % len(polygon)
        a_in, b_in = distance[i] >= 0, distance[j] >= 0
        if a_in:
            kept.append(polygon[i])
        if a_in != b_in:
            s = distance[i] / (distance[i] - distance[j])
            kept.append(polygon[i] + s * (polygon[j] - polygon[i]))
    return np.array(kept).reshape(-1, polygon.shape[1])


def clip_near(corners: np.ndarray) -> list[np.ndarray]:
    """The part of a triangle (3, A) (column 2: view depth z) with z >= `NEAR`, as one or
    two triangles: Sutherland-Hodgman against one plane (`clip_polygon`), every attribute
    interpolated along the cut edges. `clip_triangle` does the same at every clipping
    plane."""
    return clip_triangle(corners, np.array([NEAR_PLANE]))


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
    that it takes arrays of edges too (`reference_cpu.rasterise_batched.draw_triangles`)."""
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


