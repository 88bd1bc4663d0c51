"""The ray caster's picture of triangle meshes: Embree's primary hits as a `Raster`.

Where the rasteriser projects triangles onto the image, a ray caster sends each pixel's ray
into the scene and asks which triangle it meets first (`reference_cpu.truth.embree`). At the
hit point p the triangle's vertex attributes are interpolated by p's barycentric coordinates
on the triangle in space, found from areas (Ericson, "Real-Time Collision Detection" 3.4):
with e1 = b - a, e2 = c - a and q = p - a,

    w_b = (|e2|^2 (q.e1) - (e1.e2)(q.e2)) / D,   w_c = (|e1|^2 (q.e2) - (e1.e2)(q.e1)) / D,
    w_a = 1 - w_b - w_c,                          D = |e1|^2 |e2|^2 - (e1.e2)^2.

No perspective correction is needed: the weights are taken in space, not in the image, which
is exactly what the rasteriser's perspective-correct interpolation reproduces
(docs/rasterisation.md). So a raster picture and this one are the same picture, pixel by
pixel, but where a centre lies within rounding of an edge.
"""

from __future__ import annotations

import numpy as np

from scene_model.camera import Camera, camera_rays
from scene_model.geometry import dot, normalize
from scene_model.meshes import TriangleMesh

from ..rasterise import Raster
from .embree import cast_triangles
from .mesh import Mesh


def truth_meshes(meshes: list[TriangleMesh]) -> list[Mesh]:
    """The meshes as the truth's `Mesh` (exact: no distance to a surface they stand for)."""
    return [Mesh(m.positions, m.triangles.astype(np.int32), 0.0, None, "exact") for m in meshes]


def barycentric(p, a, b, c):
    """The weights (N, 3) of points ``p`` (N, 3) on triangles with corners ``a, b, c`` (N, 3)."""
    e1, e2, q = b - a, c - a, p - a
    d11, d22, d12 = dot(e1, e1), dot(e2, e2), dot(e1, e2)
    q1, q2 = dot(q, e1), dot(q, e2)
    denominator = d11 * d22 - d12 * d12
    w_b = (d22 * q1 - d12 * q2) / denominator
    w_c = (d11 * q2 - d12 * q1) / denominator
    return np.stack([1 - w_b - w_c, w_b, w_c], axis=-1)


def cast_raster(meshes: list[TriangleMesh], camera: Camera, width: int, height: int) -> Raster:
    """What each pixel's ray meets first, as the rasteriser reports it.

    Parameters
    ----------
    meshes : list of TriangleMesh
        In world coordinates; mesh k is object k.
    camera : Camera
    width, height : int

    Returns
    -------
    Raster
        Depth t from Embree's float32 cast; normals and texture coordinates interpolated
        in float64 at the hit point; ``coverage`` None (a ray meets one triangle first).
    """
    origin, directions = camera_rays(camera, width, height)
    d = directions.reshape(-1, 3)
    t, _, part, triangle, _ = cast_triangles(truth_meshes(meshes), origin, d)
    hit = part >= 0
    normal = np.zeros((len(d), 3))
    uv = np.zeros((len(d), 2))
    points = origin + np.where(hit, t, 0.0)[:, None] * d
    for k, mesh in enumerate(meshes):
        rows = np.nonzero(part == k)[0]
        if len(rows) == 0:
            continue
        corners = mesh.triangles[triangle[rows]]                     # (R, 3) vertex ids
        a, b, c = (mesh.positions[corners[:, i]] for i in range(3))
        w = barycentric(points[rows], a, b, c)[:, :, None]            # (R, 3, 1)
        normal[rows] = normalize((w * mesh.normals[corners]).sum(axis=1))
        uv[rows] = (w * mesh.uvs[corners]).sum(axis=1)
    return Raster(depth=np.where(hit, t, np.inf).reshape(height, width),
                  normal=normal.reshape(height, width, 3),
                  uv=uv.reshape(height, width, 2),
                  object_id=part.reshape(height, width).astype(np.int64),
                  triangle=np.where(hit, triangle, -1).reshape(height, width).astype(np.int64),
                  coverage=None)
