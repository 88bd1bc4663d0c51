"""Rays cast against triangle meshes of the scene with Intel Embree (through ``embreex``).

Embree intersects in float32. Like trimesh's ``ray_pyembree``, the scene is first moved and
scaled into a box about 100 units wide, where float32 spacing is fine and Embree's internal
epsilons are sized for; the distances it finds are scaled back. Embree's geometric normal Ng is
not unit length and its sign follows the triangle's winding, so it is normalised here and
turned to agree with the face's outward normal (the meshes are wound outward,
`reference_cpu.truth.mesh`).

A hit on one part's surface that lies inside another part is not on the surface of the union
(two overlapping spheres: the ray meets the second sphere's shell inside the first); such a
ray is cast again from just past that point.
"""

from __future__ import annotations

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.geometry import dot

from .mesh import Mesh, face_normals

SCENE_BOX = 100.0                     # width of the box the scene is scaled into (as trimesh)
FLOAT32_EPS = float(np.finfo(np.float32).eps)
ROUNDING_ULPS = 16                    # float32 units in the last place allowed per hit (stated)


def import_embreex():
    """The embreex modules, or a one-line `MarchlabError` saying how to install them."""
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        raise MarchlabError("the embree method needs embreex and scikit-image: "
                            "pip install 'marchlab[embree]'") from None
    return rtcore_scene, TriangleMesh


def scene_frame(meshes: list[Mesh]) -> tuple[np.ndarray, float]:
    """(centre, scale) that map the meshes' bounding box onto a cube `SCENE_BOX` wide."""
    vertices = np.concatenate([m.vertices for m in meshes])
    if len(vertices) == 0:
        return np.zeros(3), 1.0
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    return (low + high) / 2, SCENE_BOX / max(float(np.max(high - low)), 1e-30)


def embree_scene(meshes: list[Mesh]):
    """Embree's scene of ``meshes`` (none empty), moved and scaled by `scene_frame`: the
    scene, and the (centre, scale) that map world points into it."""
    rtcore_scene, TriangleMesh = import_embreex()
    centre, scale = scene_frame(meshes)
    scene = rtcore_scene.EmbreeScene()
    for mesh in meshes:
        TriangleMesh(scene, ((mesh.vertices - centre) * scale).astype(np.float32),
                     np.ascontiguousarray(mesh.faces, dtype=np.int32))
    return scene, centre, scale


def cast(meshes: list[Mesh], origin, directions, inside_other=None, max_recasts: int = 8):
    """First hit of each ray with the meshes: `cast_triangles` less the triangle indices.
    """
    t, normal, part, _, rounding = cast_triangles(meshes, origin, directions, inside_other,
                                                  max_recasts)
    return t, normal, part, rounding


def cast_triangles(meshes: list[Mesh], origin, directions, inside_other=None,
                   max_recasts: int = 8):
    """First hit of each ray with the meshes, and the triangle hit.

    Parameters
    ----------
    meshes : list of Mesh
        One per part, in world coordinates, wound outward.
    origin : (3,) ndarray
        Shared ray origin.
    directions : (N, 3) float64 ndarray
        Unit ray directions.
    inside_other : callable, optional
        ``inside_other(points (M, 3), part (M,)) -> (M,) bool``: whether each hit point on
        ``part`` lies inside another part (then the ray is cast again beyond it).
    max_recasts : int
        How many times a ray may be cast again.

    Returns
    -------
    t : (N,) float64 ndarray
        Depth (inf on a miss).
    normal : (N, 3) float64 ndarray
        Unit outward normal of the triangle hit (0 on a miss).
    part : (N,) int ndarray
        Index of the mesh hit (-1 on a miss).
    triangle : (N,) int ndarray
        Index of the triangle hit within its mesh (-1 on a miss).
    rounding : (N,) float64 ndarray
        Bound on the float32 rounding of each hit point, `ROUNDING_ULPS` units in the last
        place of its scaled coordinates, in world units (0 on a miss).
    """
    import_embreex()                      # a one-line error where embreex is missing
    n = len(directions)
    t = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    part = np.full(n, -1)
    triangle = np.full(n, -1)
    # Embree numbers the meshes it is given 0, 1, ...; an empty mesh (a solid with nothing
    # in it, such as two disjoint shapes intersected) is not given, so map its numbers back.
    given = np.array([i for i, m in enumerate(meshes) if len(m.faces)], dtype=int)
    meshes = [meshes[i] for i in given]
    if not meshes:
        return t, normal, part, triangle, np.zeros(n)
    scene, centre, scale = embree_scene(meshes)

    # Every face's outward normal, found by (mesh, face) as first[mesh] + face.
    outward_normals = np.concatenate([face_normals(m.vertices, m.faces) for m in meshes])
    first = np.cumsum([0] + [len(m.faces) for m in meshes])

    start = np.zeros(n)                     # where each ray's latest cast began (world t)
    pending = np.arange(n)
    for _ in range(max_recasts + 1):
        if len(pending) == 0:
            break
        o = (origin + start[pending, None] * directions[pending] - centre) * scale
        found = scene.run(o.astype(np.float32),
                          np.ascontiguousarray(directions[pending], dtype=np.float32),
                          output=1)
        hit = found["geomID"] >= 0
        rays = pending[hit]
        geom, prim = found["geomID"][hit], found["primID"][hit]
        t[rays] = start[rays] + found["tfar"][hit].astype(np.float64) / scale
        part[rays] = given[geom]
        triangle[rays] = prim
        ng = found["Ng"][hit].astype(np.float64)
        ng /= np.sqrt(dot(ng, ng))[:, None]
        # Turn Ng to the outward side: agree with the right-hand normal of the face hit.
        outward = outward_normals[first[geom] + prim]
        normal[rays] = ng * np.where(dot(ng, outward) < 0, -1.0, 1.0)[:, None]

        if inside_other is None:
            break
        points = origin + t[rays, None] * directions[rays]
        again = inside_other(points, given[geom])
        # Step past the surface by a few float32 units of the scaled scene.
        start[rays[again]] = t[rays[again]] + 64 * FLOAT32_EPS * SCENE_BOX / scale
        t[rays[again]], part[rays[again]], triangle[rays[again]] = np.inf, -1, -1
        normal[rays[again]] = 0.0
        pending = rays[again]

    hit_points = origin + np.where(np.isfinite(t), t, 0.0)[:, None] * directions
    reach = np.sqrt(dot(hit_points - centre, hit_points - centre))
    rounding = np.where(np.isfinite(t), ROUNDING_ULPS * FLOAT32_EPS * (
        reach + np.sqrt(dot(origin - centre, origin - centre))), 0.0)
    return t, normal, part, triangle, rounding
