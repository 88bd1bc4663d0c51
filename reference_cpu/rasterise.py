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
              cull_back_faces: bool = False) -> Raster:
    """Draw ``meshes`` as ``camera`` sees them at width x height pixels.

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
            t = (w @ z) * stretch[rows, cols]
            nearer = t < depth[rows, cols]
            rows, cols, w, t = rows[nearer], cols[nearer], w[nearer], t[nearer]
            depth[rows, cols] = t
            normal[rows, cols] = normalize(w @ normals)
            uv[rows, cols] = w @ uvs
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


def is_top_left(ax, ay, bx, by) -> bool:
    """Whether edge a -> b of a clockwise triangle (y down) is a top edge (horizontal, going
    right: the triangle lies below it) or a left edge (going up)."""
    return (ay == by and bx > ax) or by < ay


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
