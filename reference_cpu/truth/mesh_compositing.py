"""Ray-cast truth for the raster pipeline's mirrors and transparency, with Embree.

What a rasteriser gets by tricks (a mirrored scene through a stencil, layers peeled off a
depth buffer) a ray caster gets by following rays (Whitted 1980):

- **A mirror** (`ray_traced_mirrors`): at each pixel whose ray first meets a mirror (a mesh
  whose material has kr > 0), cast the reflected ray r = d - 2 (d . n) n from the hit point
  and shade what it meets first, seen along r. The pixel shows the mirror's own colour plus
  kr times that (or the background along r), as the sphere tracer's ``lit_color`` adds them.
  The mirror itself is not in the scene the reflected ray sees (a flat mirror cannot see
  itself), and the ray starts on the mirror, so nothing behind it can show.
- **Transparency** (`ordered_composite`): every surface along each pixel's ray, found by
  casting again from just past each hit, sorted by distance and composited front to back with
  opacity alpha = 1 - transparency: ``C += T alpha c``, ``T *= 1 - alpha`` (Porter and Duff 1984's
  "over", accumulated from the front), the background last. No refraction: the rays go
  straight through, as the raster pipeline's blending assumes (not the sphere tracer's glass).

Embree says which triangle a ray meets (in float32, `truth.embree`); where, is then found in
float64 from that triangle's corners (Moller and Trumbore 1997, "Fast, Minimum Storage
Ray/Triangle Intersection", J. Graphics Tools 2(1)), and the normal and texture coordinates
are interpolated with those barycentric coordinates, as the rasteriser interpolates them.
Every point is shaded by `raster_shading.shade_points`, the sphere tracer's functions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.camera import Camera, camera_rays
from scene_model.geometry import dot, normalize
from scene_model.meshes import TriangleMesh
from scene_model.scene import LIT_SHADING, Material

from ..planar_reflection import background_along
from ..raster_shading import shade_points
from ..shading import reflect
from .embree import FLOAT32_EPS, SCENE_BOX, embree_scene, import_embreex
from .mesh_cast import truth_meshes

MAX_HITS = 16        # surfaces found along a ray at most (`ordered_composite`)


@dataclass(frozen=True)
class Hits:
    """The surfaces met along N rays, nearest first, K at most per ray.

    Attributes
    ----------
    t : (N, K) float64 ndarray
        Distance along each unit ray (inf where there are fewer hits).
    part : (N, K) int ndarray
        Mesh hit (-1 where none).
    triangle : (N, K) int ndarray
        Triangle hit within its mesh (-1 where none).
    weights : (N, K, 3) float64 ndarray
        Barycentric coordinates of the hit in its triangle (0 where none).
    """
    t: np.ndarray
    part: np.ndarray
    triangle: np.ndarray
    weights: np.ndarray


def exact_hits(corners: np.ndarray, origins: np.ndarray, directions: np.ndarray):
    """Distance t (N,) and barycentrics (N, 3) of rays (N, 3) against the planes of their
    triangles ``corners`` (N, 3, 3), in float64 (Moller and Trumbore 1997)."""
    v0, v1, v2 = corners[:, 0], corners[:, 1], corners[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    p = np.cross(directions, e2)
    det = dot(e1, p)
    s = origins - v0
    u = dot(s, p) / det
    q = np.cross(s, e1)
    v = dot(directions, q) / det
    return dot(e2, q) / det, np.stack([1 - u - v, u, v], axis=-1)


def all_hits(meshes: list[TriangleMesh], origins, directions, max_hits: int = MAX_HITS) -> Hits:
    """Up to ``max_hits`` surfaces along each ray, nearest first.

    Parameters
    ----------
    meshes : list of TriangleMesh
        In world coordinates; mesh k is part k (an empty one is skipped).
    origins : (N, 3) or (3,) float64 ndarray
        Where each ray starts (one shared origin or one each).
    directions : (N, 3) float64 ndarray
        Unit directions.
    """
    import_embreex()                      # a one-line error where embreex is missing
    n = len(directions)
    origins = np.broadcast_to(np.asarray(origins, np.float64), (n, 3))
    t = np.full((n, max_hits), np.inf)
    part = np.full((n, max_hits), -1)
    triangle = np.full((n, max_hits), -1)
    weights = np.zeros((n, max_hits, 3))
    given = [k for k, m in enumerate(meshes) if len(m.triangles)]
    if not given or n == 0:
        return Hits(t, part, triangle, weights)
    scene, centre, scale = embree_scene(truth_meshes([meshes[k] for k in given]))
    # Each new cast starts a few float32 units of the scaled scene past the last hit.
    step = 64 * FLOAT32_EPS * SCENE_BOX / scale
    start = np.zeros(n)
    pending = np.arange(n)
    for layer in range(max_hits):
        if len(pending) == 0:
            break
        o = (origins[pending] + start[pending, None] * directions[pending] - centre) * scale
        found = scene.run(o.astype(np.float32),
                          np.ascontiguousarray(directions[pending], dtype=np.float32),
                          output=1)
        hit = found["geomID"] >= 0
        rays = pending[hit]
        k = np.asarray(given)[found["geomID"][hit]]
        prim = found["primID"][hit]
        corners = np.stack([meshes[a].positions[meshes[a].triangles[b]]
                            for a, b in zip(k, prim)]) if len(rays) else np.zeros((0, 3, 3))
        exact_t, w = exact_hits(corners, origins[rays], directions[rays])
        t[rays, layer], part[rays, layer], triangle[rays, layer] = exact_t, k, prim
        weights[rays, layer] = w
        start[rays] = exact_t + step
        pending = rays
    return Hits(t, part, triangle, weights)


def surface_at(meshes: list[TriangleMesh], part: np.ndarray, triangle: np.ndarray,
               weights: np.ndarray):
    """The interpolated unit normals (M, 3) and texture coordinates (M, 2) at M hits (part,
    triangle, weights (M, 3))."""
    normal = np.zeros((len(part), 3))
    uv = np.zeros((len(part), 2))
    for k in np.unique(part):
        rows = part == k
        corners = meshes[k].triangles[triangle[rows]]                        # (m, 3)
        normal[rows] = np.einsum("mc,mcx->mx", weights[rows], meshes[k].normals[corners])
        uv[rows] = np.einsum("mc,mcx->mx", weights[rows], meshes[k].uvs[corners])
    return normalize(normal), uv


def shade_hits(meshes, hits_t, part, triangle, weights, origins, directions, materials,
               lights, ambient, model, toon_bands) -> np.ndarray:
    """The colour (M, 3) of M hits along rays (origins, directions (M, 3)), seen along them."""
    position = origins + hits_t[:, None] * directions
    normal, uv = surface_at(meshes, part, triangle, weights)
    return shade_points(position, normal, -directions, uv, part, materials, lights, ambient,
                        model, toon_bands)


def ray_traced_mirrors(meshes: list[TriangleMesh], materials: list[Material], lights,
                       camera: Camera, width: int, height: int, ambient=(0.0, 0.0, 0.0),
                       model: str = "phong", background=(0.0, 0.0, 0.0), toon_bands: int = 4):
    """The picture with one bounce of mirror rays, by ray casting.

    Returns
    -------
    color : (H, W, 3) float64 ndarray
        Linear colour, not clipped.
    part : (H, W) int ndarray
        Mesh each pixel's ray meets first (-1: none).
    reflected_part : (H, W) int ndarray
        Mesh the reflected ray meets, on mirror pixels (-1: none, or not a mirror).
    """
    origin, directions = camera_rays(camera, width, height)
    d = directions.reshape(-1, 3)
    shade = dict(materials=materials, lights=lights, ambient=ambient, model=model,
                 toon_bands=toon_bands)
    first = all_hits(meshes, origin, d, max_hits=1)
    t, part, tri, w = first.t[:, 0], first.part[:, 0], first.triangle[:, 0], first.weights[:, 0]
    color = background_along(d, background)
    hit = part >= 0
    o = np.broadcast_to(origin, d.shape)
    color[hit] = shade_hits(meshes, t[hit], part[hit], tri[hit], w[hit], o[hit], d[hit],
                            **shade)
    reflected_part = np.full(len(d), -1)
    for k, material in enumerate(materials):
        on = hit & (part == k)
        if material.kr <= 0 or model not in LIT_SHADING or not on.any():
            continue
        light, bpart, _ = mirror_rays(meshes, k, tri[on], origin + t[on, None] * d[on],
                                      d[on], background=background, **shade)
        color[on] += material.kr * light
        reflected_part[np.flatnonzero(on)] = bpart
    return (color.reshape(height, width, 3), part.reshape(height, width),
            reflected_part.reshape(height, width))


def mirror_rays(meshes: list[TriangleMesh], k: int, triangle: np.ndarray, points: np.ndarray,
                directions: np.ndarray, materials: list[Material], lights,
                ambient=(0.0, 0.0, 0.0), model: str = "phong", background=(0.0, 0.0, 0.0),
                toon_bands: int = 4):
    """What M rays arriving along ``directions`` (M, 3) at ``points`` (M, 3) on triangles
    ``triangle`` (M,) of mirror mesh ``k`` see reflected (one bounce, no shadows), by ray
    casting: the colour (M, 3), not yet weighted by kr, and the mesh and triangle each
    reflected ray meets (M,), -1 for none."""
    corners = meshes[k].positions[meshes[k].triangles[triangle]]
    n = normalize(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))
    r = reflect(directions, n)
    others = [m if j != k else TriangleMesh(m.positions, m.normals, m.uvs, m.triangles[:0])
              for j, m in enumerate(meshes)]
    bounce = all_hits(others, points, r, max_hits=1)
    bt, bpart = bounce.t[:, 0], bounce.part[:, 0]
    seen = bpart >= 0
    light = background_along(r, background)
    light[seen] = shade_hits(others, bt[seen], bpart[seen], bounce.triangle[seen, 0],
                             bounce.weights[seen, 0], points[seen], r[seen], materials,
                             lights, ambient, model, toon_bands)
    return light, bpart, bounce.triangle[:, 0]


def composite_over(meshes: list[TriangleMesh], materials: list[Material], lights,
                   camera: Camera, color: np.ndarray, opaque_depth: np.ndarray,
                   ambient=(0.0, 0.0, 0.0), model: str = "phong", toon_bands: int = 4,
                   max_hits: int = MAX_HITS) -> np.ndarray:
    """The transparent ``meshes`` (the others emptied) in front of ``opaque_depth`` (H, W)
    composited front to back, by ray casting, over the opaque picture ``color`` (H, W, 3).

    Returns
    -------
    color : (H, W, 3) float64 ndarray
    layers : (H, W) int ndarray
        How many transparent surfaces each pixel's ray crossed (at most ``max_hits``).
    """
    height, width = opaque_depth.shape
    origin, directions = camera_rays(camera, width, height)
    d = directions.reshape(-1, 3)
    hits = all_hits(meshes, origin, d, max_hits)
    color, layers = front_to_back(meshes, materials, lights, hits, origin, d,
                                  color.reshape(-1, 3), opaque_depth.ravel(), ambient, model,
                                  toon_bands)
    return color.reshape(height, width, 3), layers.reshape(height, width)


def front_to_back(meshes, materials, lights, hits: Hits, origin, d, behind, limit, ambient,
                  model, toon_bands):
    """The surfaces ``hits`` along N rays from ``origin`` along ``d`` (N, 3), those nearer
    than ``limit`` (N,), composited front to back with opacity 1 - transparency over the
    colour ``behind`` (N, 3): the colour (N, 3) and how many surfaces each ray crossed."""
    alpha = 1.0 - np.array([m.transparency for m in materials], np.float64)
    front = np.zeros((len(d), 3))
    through = np.ones(len(d))                     # what still gets through (transmittance)
    layers = np.zeros(len(d), int)
    o = np.broadcast_to(origin, d.shape)
    for layer in range(hits.t.shape[1]):
        on = (hits.part[:, layer] >= 0) & (hits.t[:, layer] < limit) & (through > 0)
        if not on.any():
            break
        k = hits.part[on, layer]
        c = shade_hits(meshes, hits.t[on, layer], k, hits.triangle[on, layer],
                       hits.weights[on, layer], o[on], d[on], materials, lights, ambient,
                       model, toon_bands)
        front[on] += (through[on] * alpha[k])[:, None] * c
        through[on] *= 1.0 - alpha[k]
        layers[on] += 1
    return front + through[:, None] * behind, layers


def ordered_composite(meshes: list[TriangleMesh], materials: list[Material], lights,
                      camera: Camera, width: int, height: int, ambient=(0.0, 0.0, 0.0),
                      model: str = "phong", background=(0.0, 0.0, 0.0), toon_bands: int = 4,
                      max_hits: int = MAX_HITS):
    """Every surface along each pixel's ray composited front to back with opacity
    1 - transparency, by ray casting.

    Returns
    -------
    color : (H, W, 3) float64 ndarray
        Linear colour, not clipped.
    hits : Hits
        The surfaces along each pixel's ray (N = H W rays), nearest first.
    """
    origin, directions = camera_rays(camera, width, height)
    d = directions.reshape(-1, 3)
    hits = all_hits(meshes, origin, d, max_hits)
    color, _ = front_to_back(meshes, materials, lights, hits, origin, d,
                             background_along(d, background), np.full(len(d), np.inf),
                             ambient, model, toon_bands)
    return color.reshape(height, width, 3), hits
