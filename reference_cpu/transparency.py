"""Transparency for the rasteriser: alpha blending, sorted back to front or by depth peeling.

A surface of opacity alpha = 1 - material.transparency lets 1 - alpha of what lies behind it
through and adds alpha times its own shaded colour c: Porter and Duff's "over" (1984),
C = alpha c + (1 - alpha) C_behind. This is blending, not refraction: the rays go straight
through a pane, unlike the sphere tracer's glass, which bends them (docs/glass.md).

"Over" depends on the order, and a depth buffer keeps only the nearest surface, so a
rasteriser needs one of two ways to composite several transparent surfaces on a pixel:

- **Sorted blending** (`sorted_blend`), the painter's algorithm: draw the opaque scene with
  its depth buffer, then the transparent triangles from the farthest to the nearest (by the
  distance of their centroids from the eye), each blended over the picture where it is in
  front of the opaque depth. One sort per frame, but a sort by one point a triangle: where
  triangles intersect, or overlap in a cycle, no order of whole triangles is right for every
  pixel, and some pixels blend in the wrong order.
- **Depth peeling** (`depth_peel`; Everitt 2001, "Interactive Order-Independent
  Transparency", NVIDIA): each pass rasterises the transparent triangles again and keeps, on
  each pixel, the nearest fragment *farther* than the previous pass kept (and nearer than the
  opaque depth). Pass k peels the k-th surface along every pixel's ray, whatever the order
  the triangles come in; they are composited front to back (``C += T alpha c``,
  ``T *= 1 - alpha``,
  the "under" form of Porter and Duff's operator that Bavoil and Myers 2008 use for peeling),
  the opaque picture last. It is exact with as many passes as the deepest pixel has
  surfaces; fewer passes drop the farthest ones. Two fragments at exactly one depth on a
  pixel are one layer: the second is never peeled.

Both start from the same fragments: every transparent triangle rasterised on its own
(`transparent_fragments`), shaded as `raster_shading.shade_raster` shades. A GPU produces
them again in every peeling pass; here each pass reads the list they were put in once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.camera import Camera
from scene_model.geometry import normalize
from scene_model.meshes import TriangleMesh
from scene_model.scene import Material

from .rasterise import Raster, interpolate, rasterise, ray_stretch
from .rasterise_batched import (clipped_triangle_batch, draw_triangles, nearest_first,
                                project_corner_batch)
from .raster_shading import shade_raster


@dataclass(frozen=True)
class Fragments:
    """The F fragments of the transparent triangles, before any depth test.

    Attributes
    ----------
    pixel : (F,) int ndarray
        Flat pixel index, row * W + column.
    depth : (F,) float64 ndarray
        Distance along the pixel's unit ray (m).
    color : (F, 3) float64 ndarray
        Shaded linear colour.
    alpha : (F,) float64 ndarray
        Opacity, 1 - the material's transparency.
    order : (F,) int ndarray
        Which transparent triangle drew it, numbered from the farthest (0) to the nearest,
        by the centroid's distance from the eye.
    """
    pixel: np.ndarray
    depth: np.ndarray
    color: np.ndarray
    alpha: np.ndarray
    order: np.ndarray


def is_transparent(materials: list[Material]) -> np.ndarray:
    """(K,) bool: which objects are drawn blended (transparency > 0)."""
    return np.array([m.transparency > 0 for m in materials], bool)


def keep_only(meshes: list[TriangleMesh], keep) -> list[TriangleMesh]:
    """``meshes`` with those not in ``keep`` (K,) bool emptied, so object k stays mesh k."""
    return [m if k else TriangleMesh(m.positions, m.normals, m.uvs, m.triangles[:0])
            for m, k in zip(meshes, keep)]


def opaque_pass(meshes, materials, lights, camera, width, height, **shade):
    """The opaque objects drawn with a depth buffer: colour (H, W, 3) and depth (H, W)."""
    raster = rasterise(keep_only(meshes, ~is_transparent(materials)), camera, width, height)
    return shade_raster(raster, camera, materials, lights, **shade), raster.depth


def transparent_fragments(meshes, materials, lights, camera: Camera, width: int, height: int,
                          textbook: bool = False, **shade) -> Fragments:
    """Every fragment of every transparent triangle (`Fragments`), by triangle from the
    farthest to the nearest, each's by pixel.

    ``textbook=True`` rasterises and shades each triangle on its own picture
    (`transparent_fragments_one_by_one`); by default all at once
    (`transparent_fragments_batched`), the same fragments to the last bit. ``shade`` holds
    `raster_shading.shade_raster`'s keywords.
    """
    find = transparent_fragments_one_by_one if textbook else transparent_fragments_batched
    return find(meshes, materials, lights, camera, width, height, **shade)


def far_to_near(meshes, materials, camera: Camera):
    """The transparent triangles as (object k, triangle i) pairs (T,) and the place (T,) of
    each from the farthest (0) to the nearest, by its centroid's distance from the eye."""
    triangles = [(k, i) for k in np.flatnonzero(is_transparent(materials))
                 for i in range(len(meshes[k].triangles))]
    eye = np.asarray(camera.position, np.float64)
    distance = [np.linalg.norm(meshes[k].positions[meshes[k].triangles[i]].mean(axis=0) - eye)
                for k, i in triangles]
    place = np.empty(len(triangles), np.int64)
    place[np.argsort(distance, kind="stable")[::-1]] = np.arange(len(triangles))
    return triangles, place


def transparent_fragments_one_by_one(meshes, materials, lights, camera: Camera, width: int,
                                     height: int, **shade) -> Fragments:
    """Every fragment of every transparent triangle: each triangle rasterised and shaded on
    a picture of its own, from the farthest to the nearest."""
    triangles, place = far_to_near(meshes, materials, camera)
    parts = []
    for order, index in enumerate(np.argsort(place)):
        k, i = triangles[index]
        alone = keep_only(meshes, np.arange(len(meshes)) == k)
        mesh = alone[k]
        alone[k] = TriangleMesh(mesh.positions, mesh.normals, mesh.uvs, mesh.triangles[i:i + 1])
        raster = rasterise(alone, camera, width, height, textbook=True)
        if not raster.hit.any():
            continue
        color = shade_raster(raster, camera, materials, lights, **shade)
        pixel = np.flatnonzero(raster.hit)
        parts.append((pixel, raster.depth.ravel()[pixel], color.reshape(-1, 3)[pixel],
                      np.full(len(pixel), 1.0 - materials[k].transparency),
                      np.full(len(pixel), order)))
    if not parts:
        return Fragments(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), np.zeros(0),
                         np.zeros(0, int))
    return Fragments(*(np.concatenate(column) for column in zip(*parts)))


def transparent_fragments_batched(meshes, materials, lights, camera: Camera, width: int,
                                  height: int, **shade) -> Fragments:
    """`transparent_fragments_one_by_one`'s fragments from all the transparent triangles
    drawn at once (`reference_cpu.rasterise_batched.draw_triangles`), then shaded a layer at a time:
    layer n holds each pixel's n-th fragment, so that a layer is a `Raster` with at most
    one surface a pixel, and one `shade_raster` call shades all its fragments."""
    triangles, place = far_to_near(meshes, materials, camera)
    first = {}                                  # where mesh k's triangles start in place
    for n, (k, i) in enumerate(triangles):
        first.setdefault(k, n)
    stretch = ray_stretch(camera, width, height).ravel()
    parts = []
    for k in first:
        index, corners = clipped_triangle_batch(meshes[k], camera, (width, height))
        image, z, normals, uvs = project_corner_batch(corners, camera, width, height)
        for tri, rows, cols, weights in draw_triangles(image, z, False, (width, height)):
            pixel = rows * width + cols
            parts.append(dict(pixel=pixel, order=place[first[k] + index[tri]],
                              depth=interpolate(weights, z[tri, :, None])[:, 0] * stretch[pixel],
                              normal=normalize(interpolate(weights, normals[tri])),
                              uv=interpolate(weights, uvs[tri]), object=np.full(len(tri), k),
                              triangle=index[tri]))
    if not parts:
        return Fragments(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), np.zeros(0),
                         np.zeros(0, int))
    f = {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}
    # Each triangle on a picture of its own: one fragment a pixel (a triangle cut in two at
    # the near plane has two pieces), the one its depth test keeps.
    _, key = np.unique(f["order"] * (width * height) + f["pixel"], return_inverse=True)
    kept = nearest_first(key, f["depth"])
    kept = kept[f["depth"][kept] < np.inf]
    kept = kept[np.lexsort((f["pixel"][kept], f["order"][kept]))]   # by triangle, by pixel
    f = {name: value[kept] for name, value in f.items()}
    color = np.zeros((len(kept), 3))
    layer = layers_of(f["pixel"])
    for n in range(layer.max(initial=-1) + 1):
        rows = np.flatnonzero(layer == n)
        # The background shows only where nothing is drawn: on none of these pixels.
        shaded = shade_raster(layer_raster(f, rows, width, height), camera, materials, lights,
                              **dict(shade, background=(0.0, 0.0, 0.0)))
        color[rows] = shaded.reshape(-1, 3)[f["pixel"][rows]]
    alpha = 1.0 - np.array([m.transparency for m in materials])[f["object"]]
    return Fragments(f["pixel"], f["depth"], color, alpha, f["order"])


def layers_of(pixel: np.ndarray) -> np.ndarray:
    """(F,) int: for each fragment, how many fragments before it fall on its pixel."""
    by_pixel = np.argsort(pixel, kind="stable")
    sorted_pixel = pixel[by_pixel]
    starts = np.flatnonzero(np.r_[True, sorted_pixel[1:] != sorted_pixel[:-1]])
    run = np.diff(np.r_[starts, len(pixel)])
    layer = np.empty(len(pixel), np.int64)
    layer[by_pixel] = np.arange(len(pixel)) - np.repeat(starts, run)
    return layer


def layer_raster(f: dict, rows: np.ndarray, width: int, height: int) -> Raster:
    """The `Raster` of the fragments ``rows`` of ``f`` (at most one a pixel)."""
    pixels = width * height
    depth, normal, uv = np.full(pixels, np.inf), np.zeros((pixels, 3)), np.zeros((pixels, 2))
    object_id, triangle = np.full(pixels, -1, np.int64), np.full(pixels, -1, np.int64)
    p = f["pixel"][rows]
    depth[p], normal[p], uv[p] = f["depth"][rows], f["normal"][rows], f["uv"][rows]
    object_id[p], triangle[p] = f["object"][rows], f["triangle"][rows]
    return Raster(depth.reshape(height, width), normal.reshape(height, width, 3),
                  uv.reshape(height, width, 2), object_id.reshape(height, width),
                  triangle.reshape(height, width), None)


def sorted_blend(meshes: list[TriangleMesh], materials: list[Material], lights,
                 camera: Camera, width: int, height: int, **shade) -> np.ndarray:
    """The linear colour (H, W, 3) with transparent triangles blended "over" the opaque
    picture from the farthest to the nearest (the painter's algorithm).

    ``shade`` holds `raster_shading.shade_raster`'s keywords (ambient, model, background,
    toon_bands)."""
    color, opaque_depth = opaque_pass(meshes, materials, lights, camera, width, height, **shade)
    f = transparent_fragments(meshes, materials, lights, camera, width, height, **shade)
    return blend_sorted(f, color, opaque_depth)


def blend_sorted(f: Fragments, color: np.ndarray, opaque_depth: np.ndarray) -> np.ndarray:
    """Fragments ``f`` blended "over" the opaque picture ``color`` (H, W, 3) triangle by
    triangle from the farthest to the nearest, where in front of ``opaque_depth`` (H, W)."""
    height, width = opaque_depth.shape
    color = color.reshape(-1, 3).copy()
    in_front = f.depth < opaque_depth.ravel()[f.pixel]
    for order in np.unique(f.order):           # farthest first
        rows = in_front & (f.order == order)
        p, a = f.pixel[rows], f.alpha[rows, None]
        color[p] = a * f.color[rows] + (1 - a) * color[p]
    return color.reshape(height, width, 3)


def depth_peel(meshes: list[TriangleMesh], materials: list[Material], lights, camera: Camera,
               width: int, height: int, layers: int, **shade) -> np.ndarray:
    """The linear colour (H, W, 3) with the ``layers`` nearest transparent surfaces of each
    pixel peeled off one pass at a time and composited front to back over the opaque
    picture (Everitt 2001). ``shade`` as `sorted_blend`."""
    color, opaque_depth = opaque_pass(meshes, materials, lights, camera, width, height, **shade)
    f = transparent_fragments(meshes, materials, lights, camera, width, height, **shade)
    return peel_layers(f, color, opaque_depth, layers)


def peel_layers(f: Fragments, color: np.ndarray, opaque_depth: np.ndarray,
                layers: int) -> np.ndarray:
    """Fragments ``f`` in front of ``opaque_depth`` (H, W), peeled nearest first, ``layers``
    passes, and composited front to back over the opaque picture ``color`` (H, W, 3)."""
    height, width = opaque_depth.shape
    pixels = width * height
    front = np.zeros((pixels, 3))
    through = np.ones(pixels)                   # transmittance T of the layers peeled so far
    peeled = np.zeros(pixels)                   # the depth the previous pass kept
    in_front = f.depth < opaque_depth.ravel()[f.pixel]
    for _ in range(layers):
        # The pass's depth test: nearest of the fragments farther than the last layer.
        live = in_front & (f.depth > peeled[f.pixel])
        if not live.any():
            break
        nearest = np.full(pixels, np.inf)
        np.minimum.at(nearest, f.pixel[live], f.depth[live])
        won = np.flatnonzero(live & (f.depth == nearest[f.pixel]))
        won = won[np.unique(f.pixel[won], return_index=True)[1]]      # one fragment a pixel
        p, a = f.pixel[won], f.alpha[won]
        front[p] += (through[p] * a)[:, None] * f.color[won]
        through[p] *= 1 - a
        peeled[p] = f.depth[won]
    return (front + through[:, None] * color.reshape(-1, 3)).reshape(height, width, 3)


def depth_complexity(fragments: Fragments, opaque_depth: np.ndarray) -> np.ndarray:
    """(H, W) int: how many transparent fragments lie in front of the opaque depth on each
    pixel, the number of peeling passes the pixel needs."""
    in_front = fragments.depth < opaque_depth.ravel()[fragments.pixel]
    count = np.bincount(fragments.pixel[in_front], minlength=opaque_depth.size)
    return count.reshape(opaque_depth.shape)
