"""Shadow volumes: the exact hard shadows of closed meshes, counted in a stencil buffer.

Crow (1977) bounds the region a closed object hides from a light by the object's
*silhouette as seen from the light*, extruded away from it. A pixel's surface point is in
shadow when it lies inside such a volume, and a ray from the eye tells: count the volume's
faces along it. Heidmann (1991) counted them with the stencil buffer, and Carmack's reverse
(*depth-fail*; Everitt and Kilgard 2002, "Practical and Robust Stenciled Shadow Volumes",
section 3) counts the faces **behind** the visible surface instead of in front of it: a
closed volume is entered as often as it is left, so the faces beyond the point, +1 for each
back face (leaving) and -1 for each front face (entering), add up to 1 exactly when the
point is inside, wherever the eye is. Counting in front (depth-pass) is off by one when
the eye itself sits in a shadow, and near-plane clipping cuts the faces it counts; the
faces behind the surface are never near the eye.

Depth-fail needs the volume closed behind the point too, so it gets caps (Everitt and
Kilgard, section 4): the **front cap** is the object's light-facing triangles, the **back
cap** its light-averted ones pushed away from the light. Between them the **sides** are the
silhouette edges (an edge between a light-facing and a light-averted triangle) extruded.
The light-facing triangles at their own place close the volume exactly where the object
is drawn: counted where they are the visible surface itself (a depth test that *fails* on
equal depth), they keep a lit face of the object lit.

Everitt and Kilgard extrude to infinity with homogeneous w = 0 vertices (the GPU version,
`gpu_shader.raster_shadows`, does). This NumPy version extrudes to a finite ``reach``
instead, so that its corners are ordinary points for the rasteriser: a point light's
extruded vertices go onto a sphere of radius ``reach`` around it, a directional light's
``reach`` along its direction. The count is the same as long as every surface the eye can
see lies inside that reach (`volume_reach` takes twice the farthest scene vertex).

Only closed meshes cast a volume (a floor plane has no inside to bound); every mesh
receives the shadows. Spot lights cast from their position, as point lights.
"""

from __future__ import annotations

import numpy as np

from scene_model.camera import Camera
from scene_model.meshes import TriangleMesh
from scene_model.scene import DirectionalLight

from .rasterise import (SUBPIXELS, Raster, clipped_triangles, draw_triangle, edge, interpolate,
                        project_corners, ray_stretch)
from .rasterise_batched import (clipped_triangle_batch, draw_triangles, project_corner_batch,
                                winding)

MATCH = 1e-9         # vertices closer than this fraction of a mesh's size are one point


def light_source(light) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(position, direction)`` of a light for shadows: a point light's (or spot light's)
    position and None, or None and a directional light's unit travel direction."""
    if isinstance(light, DirectionalLight):
        d = np.asarray(light.direction, np.float64)
        return None, d / np.linalg.norm(d)
    return np.asarray(light.position, np.float64), None


def facing_light(mesh: TriangleMesh, light) -> np.ndarray:
    """(T,) bool: which triangles have the light on their outer side, n . (L - v0) > 0 for a
    light at L, n . (-d) > 0 for light travelling along d (n the right-hand face normal)."""
    position, direction = light_source(light)
    v0, v1, v2 = (mesh.positions[mesh.triangles[:, k]] for k in range(3))
    n = np.cross(v1 - v0, v2 - v0)
    to_light = -direction if position is None else position - v0
    return np.sum(n * to_light, axis=-1) > 0


def neighbours(mesh: TriangleMesh) -> np.ndarray | None:
    """(T, 3) int: the triangle across each edge (corner k to corner k + 1) of each triangle,
    edges matched by the positions of their ends (a seam's vertices are stored twice); None
    unless the mesh is closed, every edge used once in each direction.

    Positions are compared to `MATCH` of the mesh's size: a cone's rim, computed once for
    its side and once for its base, differs there in the last bits."""
    size = max(float(np.ptp(mesh.positions, axis=0).max(initial=0.0)), 1e-300)
    _, canonical = np.unique(np.round(mesh.positions / (MATCH * size)), axis=0,
                             return_inverse=True)
    corner = canonical.reshape(-1)[mesh.triangles]                   # (T, 3) point ids
    start, end = corner.reshape(-1), np.roll(corner, -1, axis=1).reshape(-1)
    points = int(corner.max()) + 1 if corner.size else 1
    keys, reverse = start * points + end, end * points + start
    order = np.argsort(keys)
    found = np.searchsorted(keys[order], reverse)
    found = np.minimum(found, len(keys) - 1)
    if len(np.unique(keys)) != len(keys) or np.any(keys[order][found] != reverse):
        return None
    return (order[found] // 3).reshape(-1, 3)


def silhouette_edges(mesh: TriangleMesh, light) -> np.ndarray:
    """(S, 2) vertex indices (a, b) of the silhouette edges of a closed mesh seen from the
    light: each edge between a light-facing and a light-averted triangle, in the order
    the light-facing one is wound (a -> b)."""
    across = neighbours(mesh)
    if across is None:
        raise ValueError("silhouette_edges needs a closed mesh (see neighbours)")
    lit = facing_light(mesh, light)
    on_edge = lit[:, None] & ~lit[across]                            # (T, 3)
    triangle, k = np.nonzero(on_edge)
    return np.stack([mesh.triangles[triangle, k], mesh.triangles[triangle, (k + 1) % 3]], 1)


def volume_reach(meshes: list[TriangleMesh], light) -> float:
    """How far to extrude (m): twice the distance from the light (point) or the extent of
    the scene (directional) to its farthest vertex, so every visible surface lies within."""
    points = np.concatenate([m.positions for m in meshes])
    position, _ = light_source(light)
    centre = points.mean(axis=0) if position is None else position
    return 2.0 * float(np.max(np.linalg.norm(points - centre, axis=1))) + 1.0


def extruded(points: np.ndarray, light, reach: float) -> np.ndarray:
    """Points (N, 3) pushed away from the light: onto the sphere of radius ``reach`` round a
    point light, or ``reach`` along a directional light's direction."""
    position, direction = light_source(light)
    if position is None:
        return points + reach * direction
    away = points - position
    return position + reach * away / np.linalg.norm(away, axis=1, keepdims=True)


def volume_sides_and_back_cap(mesh: TriangleMesh, light, reach: float) -> TriangleMesh:
    """The shadow volume of a closed mesh less its front cap, wound outward: each silhouette
    edge a -> b extruded into the quad (b, a, a', b'), which runs along the edge the other way
    from the light-facing triangle beside it, and the light-averted triangles extruded with
    their own winding (the back cap). Vertices: the mesh's, then their extruded copies."""
    count = len(mesh.positions)
    a, b = silhouette_edges(mesh, light).T
    sides = np.concatenate([np.stack([b, a, a + count], 1),
                            np.stack([b, a + count, b + count], 1)])
    back_cap = mesh.triangles[~facing_light(mesh, light)] + count
    positions = np.concatenate([mesh.positions, extruded(mesh.positions, light, reach)])
    return TriangleMesh(positions, np.zeros_like(positions), np.zeros((2 * count, 2)),
                        np.concatenate([sides, back_cap]).astype(np.int64))


def stencil_counts(meshes: list[TriangleMesh], raster: Raster, camera: Camera, light,
                   method: str = "depth-fail", reach: float | None = None,
                   textbook: bool = False) -> np.ndarray:
    """The stencil buffer (H, W) after drawing every closed mesh's shadow volume.

    ``textbook=True`` draws the volumes one triangle at a time (`stencil_counts_one_by_one`);
    by default many at once (`stencil_counts_batched`), the same counts, many times faster.
    The other parameters are `stencil_counts_one_by_one`'s.
    """
    if method not in ("depth-fail", "depth-pass"):
        raise ValueError(f"method must be 'depth-fail' or 'depth-pass' (got {method!r})")
    count = stencil_counts_one_by_one if textbook else stencil_counts_batched
    return count(meshes, raster, camera, light, method, reach)


def stencil_counts_one_by_one(meshes: list[TriangleMesh], raster: Raster, camera: Camera,
                              light, method: str = "depth-fail",
                              reach: float | None = None) -> np.ndarray:
    """The stencil buffer (H, W) after drawing every closed mesh's shadow volume, one
    triangle at a time.

    Parameters
    ----------
    meshes : list of TriangleMesh
        The meshes ``raster`` shows, in the same order (`reference_cpu.rasterise.rasterise`
        with this ``camera``): a front cap triangle must reach the very depth it was drawn at.
    raster : Raster
    camera : Camera
    light : PointLight, SpotLight or DirectionalLight
    method : "depth-fail" or "depth-pass"
        Depth-fail counts the faces not in front of the surface drawn (+1 back, -1 front);
        depth-pass (Heidmann 1991) those in front of it (+1 front, -1 back), which goes
        wrong when the eye is inside a volume.
    reach : float, optional
        How far to extrude (m); `volume_reach` by default.

    Returns
    -------
    (H, W) int64 ndarray
        Nonzero where the surface drawn lies inside a shadow volume.
    """
    height, width = raster.depth.shape
    reach = volume_reach(meshes, light) if reach is None else reach
    stretch = ray_stretch(camera, width, height)
    stencil = np.zeros((height, width), np.int64)
    for mesh in meshes:
        if neighbours(mesh) is None:
            continue                                         # open: casts no volume
        lit = facing_light(mesh, light)
        # The front cap goes through the very steps that drew the mesh, so where it is the
        # surface drawn its depth is that depth to the last bit.
        pieces = [c for index, c in clipped_triangles(mesh, camera, (width, height))
                  if lit[index]]
        pieces += [c for _, c in clipped_triangles(
            volume_sides_and_back_cap(mesh, light, reach), camera, (width, height))]
        for corners in pieces:
            image, z, _, _ = project_corners(corners, camera, width, height)
            drawn = draw_triangle(image, z, False, (width, height))
            if drawn is None:
                continue
            (x0, y0), inside, weights = drawn
            rows, cols = np.nonzero(inside)
            t = interpolate(weights[inside], z[:, None])[:, 0] * stretch[rows + y0, cols + x0]
            behind = t >= raster.depth[rows + y0, cols + x0]   # the depth test fails
            counted = behind if method == "depth-fail" else ~behind
            step = 1 if is_back_face(image) else -1
            if method == "depth-pass":
                step = -step
            stencil[rows[counted] + y0, cols[counted] + x0] += step
    return stencil


def stencil_counts_batched(meshes: list[TriangleMesh], raster: Raster, camera: Camera,
                           light, method: str = "depth-fail",
                           reach: float | None = None) -> np.ndarray:
    """`stencil_counts_one_by_one`'s counts from all of a mesh's volume triangles at once
    (`reference_cpu.rasterise_batched.draw_triangles`): each fragment's depth is the same number,
    and a sum does not depend on the order its terms come in."""
    height, width = raster.depth.shape
    reach = volume_reach(meshes, light) if reach is None else reach
    stretch = ray_stretch(camera, width, height).ravel()
    surface = raster.depth.ravel()
    corners = []
    for mesh in meshes:
        if neighbours(mesh) is None:
            continue                                         # open: casts no volume
        index, cap = clipped_triangle_batch(mesh, camera, (width, height))
        _, volume = clipped_triangle_batch(volume_sides_and_back_cap(mesh, light, reach),
                                           camera, (width, height))
        corners += [cap[facing_light(mesh, light)[index]], volume]
    corners = np.concatenate(corners or [np.zeros((0, 3, 11))])
    image, z, _, _ = project_corner_batch(corners, camera, width, height)
    step = np.where(winding(image) > 0, 1, -1)             # +1 a back face, -1 a front one
    if method == "depth-pass":
        step = -step
    stencil = np.zeros(height * width, np.int64)
    for tri, rows, cols, weights in draw_triangles(image, z, False, (width, height)):
        pixel = rows * width + cols
        t = interpolate(weights, z[tri, :, None])[:, 0] * stretch[pixel]
        behind = t >= surface[pixel]                         # the depth test fails
        counted = behind if method == "depth-fail" else ~behind
        np.add.at(stencil, pixel[counted], step[tri[counted]])
    return stencil.reshape(height, width)


def is_back_face(image: np.ndarray) -> bool:
    """Whether a triangle's corners (3, 2) in pixels turn clockwise on the screen (y down):
    the side of a face wound outward that is seen from inside, decided on the same snapped
    corners as `reference_cpu.rasterise.draw_triangle`."""
    (ax, ay), (bx, by), (cx, cy) = np.round(image * SUBPIXELS).astype(np.int64).tolist()
    return edge(ax, ay, bx, by, cx, cy) > 0


def shadow_volume_visibility(meshes: list[TriangleMesh], raster: Raster, camera: Camera,
                             light, reach: float | None = None) -> np.ndarray:
    """Visibility (H, W) of one light: 0 where the surface drawn is inside a shadow volume
    (depth-fail stencil count not zero), 1 where it is not and where nothing is drawn. The
    arguments are `stencil_counts`'s."""
    counts = stencil_counts(meshes, raster, camera, light, "depth-fail", reach)
    return np.where(raster.hit & (counts != 0), 0.0, 1.0)
