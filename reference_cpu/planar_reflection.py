"""Planar reflections for the rasteriser: the scene mirrored about the mirror's plane.

A ray tracer finds what a mirror shows by casting the reflected ray (Whitted 1980). A
rasteriser casts no rays, but for a *flat* mirror it needs none: the reflected ray from the
eye e off mirror point h to a point p is, unfolded, the straight line from e to p' = M p,
where M reflects space about the mirror's plane (an image in a plane mirror lies as far behind
it as the object in front). So the mirror shows the scene reflected about its plane, drawn by
the same camera, only where the mirror itself is drawn. The recipe of Kilgard ("Improving
Shadows and Reflections via the Stencil Buffer", NVIDIA 1999) and of Real-Time Rendering
(Akenine-Moller, Haines and Hoffman, 3rd ed. 2008, Section 9.3.1):

1. **The stencil.** Draw the scene; the pixels where the mirror won the depth test are the
   only ones the reflection may colour (`stencil`).
2. **The clip plane.** What lies behind the mirror must not show in it, yet reflected it
   comes to lie in front, between the eye and the glass. Every mesh is cut at the plane and
   only the part on the eye's side is kept (`clip_to_plane`, a GPU's user clip plane). Cutting
   whole triangles, as `rasterise.clip_near` does at the near plane, rather than discarding
   fragments keeps the depth test right: a discarded nearer fragment must not hide a farther
   one, and `rasterise` has no per-fragment discard.
3. **The mirrored pass.** The kept geometry, mirrored by `mirror_matrix` (the mirror itself
   left out), rasterised by the real camera. A pixel's depth is the length of the bent path
   eye -> mirror -> object.
4. **Shading.** Lights are not mirrored: the mirror shows the real objects under the real
   lights. Each mirrored fragment p' is shaded at its real point p = M p', with its real
   normal H n' and seen along the reflected direction H d (H the linear part of M), which is
   what a reflected ray would find there (`raster_shading.shade_points`, the sphere tracer's
   functions: colour, checkerboard or texture).
5. **Combining**, as the sphere tracer does (`reference_cpu.render`, ``lit_color``): the
   mirror's own shaded colour plus kr times what the reflection shows (the background along
   H d where it shows nothing).

One bounce only: a mirror seen in a mirror shows its own colour, not a second reflection, as
the sphere tracer does with ``reflection_depth = 1``. A mirror reflects on both faces (the
sphere tracer's mirror rays do too); it must be flat (`mirror_plane` refuses a curved one).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from scene_model.camera import Camera, camera_rays
from scene_model.meshes import TriangleMesh, transformed
from scene_model.scene import LIT_SHADING, Background, Material

from . import shading
from .rasterise import Raster, rasterise
from .raster_shading import shade_points, shade_raster

PLANAR_TOLERANCE = 1e-9      # largest distance of a mirror's vertex from its plane, per metre


def mirror_matrix(point, normal) -> np.ndarray:
    """The 4 x 4 reflection about the plane through ``point`` (3,) with normal ``normal`` (3,).

    Householder's reflection (Householder 1958, "Unitary Triangularization of a Nonsymmetric
    Matrix", J. ACM 5(4)) moves x to x - 2 n (n . (x - q)) for unit n and q on the plane: the
    linear part H = I - 2 n n^T, and the offset 2 (n . q) n. H is symmetric and its own
    inverse (det -1), so normals go by H as well.
    """
    n = np.asarray(normal, np.float64)
    n = n / np.linalg.norm(n)
    m = np.eye(4)
    m[:3, :3] -= 2.0 * np.outer(n, n)
    m[:3, 3] = 2.0 * np.dot(n, np.asarray(point, np.float64)) * n
    return m


def mirror_plane(mesh: TriangleMesh, tolerance: float = PLANAR_TOLERANCE):
    """The plane (point (3,), unit normal (3,)) a mirror mesh lies in.

    The plane through the vertices' centroid whose normal is the direction they spread
    least along (the last right-singular vector of the centred vertices: a least-squares
    fit). A vertex farther from it than ``tolerance`` times the mesh's size is refused with
    a `ValueError`: a curved mirror has no single mirrored scene.
    """
    centre = mesh.positions.mean(axis=0)
    offsets = mesh.positions - centre
    normal = np.linalg.svd(offsets)[2][-1]
    size = max(float(np.ptp(mesh.positions, axis=0).max()), 1e-300)
    off = float(np.abs(offsets @ normal).max())
    if off > tolerance * size:
        raise ValueError(f"a planar reflection needs a flat mirror: its vertices are up to "
                         f"{off:.3g} m off their plane ({tolerance * size:.3g} allowed)")
    return centre, normal


def clip_to_plane(mesh: TriangleMesh, point, normal) -> TriangleMesh:
    """The part of ``mesh`` strictly on the side of the plane its ``normal`` points to.

    Sutherland and Hodgman (1974) against one plane, as `rasterise.clip_near`: a triangle
    with one or two corners outside becomes one or two triangles, positions, normals and
    texture coordinates interpolated along the cut edges (normals renormalised later, when
    the mesh is transformed). Corners are kept in order, so the winding stays outward.
    """
    return clipped_with_origin(mesh, point, normal)[0]


def clipped_with_origin(mesh: TriangleMesh, point, normal):
    """`clip_to_plane`'s mesh, and the index (T',) of the triangle of ``mesh`` each of its
    triangles was cut from: a picture of the clipped mesh names the original triangles."""
    signed = (mesh.positions - np.asarray(point, np.float64)) @ np.asarray(normal, np.float64)
    attributes = np.concatenate([mesh.positions, mesh.normals, mesh.uvs], axis=1)
    pieces, origin = [], []
    for index, corner_ids in enumerate(mesh.triangles):
        d = signed[corner_ids]
        if (d > 0).all():
            pieces.append(attributes[corner_ids])
            origin.append(index)
            continue
        polygon = []
        for i in range(3):
            j = (i + 1) % 3
            if d[i] > 0:
                polygon.append(attributes[corner_ids[i]])
            if (d[i] > 0) != (d[j] > 0):
                s = d[i] / (d[i] - d[j])                     # where d is 0 along the edge
                a, b = attributes[corner_ids[i]], attributes[corner_ids[j]]
                polygon.append(a + s * (b - a))
        cut = [np.stack([polygon[0], polygon[k], polygon[k + 1]])
               for k in range(1, len(polygon) - 1)]
        pieces += cut
        origin += [index] * len(cut)
    if not pieces:
        return (TriangleMesh(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2)),
                             np.zeros((0, 3), np.int64)), np.zeros(0, np.int64))
    corners = np.concatenate(pieces)
    return (TriangleMesh(corners[:, :3], corners[:, 3:6], corners[:, 6:8],
                         np.arange(len(corners), dtype=np.int64).reshape(-1, 3)),
            np.asarray(origin, np.int64))


def eye_side_normal(point, normal, camera: Camera) -> np.ndarray:
    """``normal`` turned towards the eye: the side of the mirror the camera sees."""
    n = np.asarray(normal, np.float64)
    return n if np.dot(np.subtract(camera.position, point), n) >= 0 else -n


def mirrored_raster(meshes: list[TriangleMesh], mirror_index: int, camera: Camera,
                    width: int, height: int) -> Raster:
    """The scene mirrored about mesh ``mirror_index``'s plane, as ``camera`` sees it.

    Everything behind the plane (seen from the eye) is cut away first, and the mirror itself
    is left out (an empty mesh keeps the object numbers). The raster's depth is the length
    of the bent path eye -> mirror -> object; its normals are the mirrored ones.
    """
    point, normal = mirror_plane(meshes[mirror_index])
    normal = eye_side_normal(point, normal, camera)
    m = mirror_matrix(point, normal)
    empty = np.zeros(0, np.int64)
    clipped = [clipped_with_origin(mesh, point, normal) if k != mirror_index
               else (TriangleMesh(mesh.positions, mesh.normals, mesh.uvs, mesh.triangles[:0]),
                     empty)
               for k, mesh in enumerate(meshes)]
    raster = rasterise([transformed(mesh, m) for mesh, _ in clipped], camera, width, height)
    # Name the original triangles, as a picture of the unclipped meshes would.
    triangle = raster.triangle.copy()
    for k, (_, origin) in enumerate(clipped):
        drawn = raster.object_id == k
        triangle[drawn] = origin[raster.triangle[drawn]]
    return dataclasses.replace(raster, triangle=triangle)


def background_along(directions, background) -> np.ndarray:
    """What rays of unit ``directions`` (N, 3) that hit nothing see: ``background``, one
    colour (3,) or a scene's `Background` looked up by direction."""
    if isinstance(background, Background):
        return np.asarray(shading.background(directions, background), np.float64)
    return np.broadcast_to(np.asarray(background, np.float64), directions.shape).copy()


def reflect_through(meshes: list[TriangleMesh], mirror_index: int, stencil: np.ndarray,
                    materials: list[Material], lights, camera: Camera, width: int,
                    height: int, ambient=(0.0, 0.0, 0.0), model: str = "phong",
                    background=(0.0, 0.0, 0.0), toon_bands: int = 4):
    """What mirror ``mirror_index`` shows on the ``stencil`` pixels (H, W) bool.

    Returns
    -------
    color : (H, W, 3) float64 ndarray
        The reflected scene's linear colour on the stencil, 0 elsewhere (not yet weighted by
        the mirror's kr).
    raster : Raster
        The mirrored pass (`mirrored_raster`), over the whole image.
    """
    raster = mirrored_raster(meshes, mirror_index, camera, width, height)
    point, normal = mirror_plane(meshes[mirror_index])
    m = mirror_matrix(point, normal)
    h = m[:3, :3]
    origin, directions = camera_rays(camera, width, height)
    color = np.zeros((height, width, 3))
    reflected = directions[stencil] @ h.T                 # H d: the reflected rays
    seen = raster.hit[stencil]
    # The real point behind each mirrored fragment: M (e + t d) = M e + t H d.
    t = raster.depth[stencil][seen]
    real = (m[:3, :3] @ origin + m[:3, 3]) + t[:, None] * reflected[seen]
    shaded = background_along(reflected, background)
    shaded[seen] = shade_points(real, raster.normal[stencil][seen] @ h.T, -reflected[seen],
                                raster.uv[stencil][seen], raster.object_id[stencil][seen],
                                materials, lights, ambient, model, toon_bands)
    color[stencil] = shaded
    return color, raster


def render_with_mirrors(meshes: list[TriangleMesh], materials: list[Material], lights,
                        camera: Camera, width: int, height: int, ambient=(0.0, 0.0, 0.0),
                        model: str = "phong", background=(0.0, 0.0, 0.0),
                        toon_bands: int = 4) -> np.ndarray:
    """The linear colour (H, W, 3) of the scene with every mirror (a mesh whose material has
    kr > 0) showing one bounce of reflection: its own colour plus kr times the reflection,
    as the sphere tracer adds them (not clipped to [0, 1]; the sphere tracer clips the sum).
    Arguments as `raster_shading.shade_raster`; a mirror that is not flat is refused."""
    mirrors = [k for k, material in enumerate(materials) if material.kr > 0]
    for k in mirrors:
        mirror_plane(meshes[k])               # refuse a curved mirror, seen or not
    raster = rasterise(meshes, camera, width, height)
    color = shade_raster(raster, camera, materials, lights, ambient, model, background,
                         toon_bands)
    if model not in LIT_SHADING:
        return color                          # the sphere tracer reflects lit models only
    for k in mirrors:
        stencil = raster.object_id == k
        if not stencil.any():
            continue
        reflected, _ = reflect_through(meshes, k, stencil, materials, lights, camera, width,
                                       height, ambient, model, background, toon_bands)
        color[stencil] += materials[k].kr * reflected[stencil]
    return color
