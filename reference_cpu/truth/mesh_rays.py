"""Shadow rays against triangle meshes with Embree: the exact hard shadows, point by point.

A surface point is lit by a point light when the segment from it to the light meets no
triangle, and by a directional light when the ray from it against the light's direction
meets none (Whitted 1980; Shirley and Marschner, "Fundamentals of Computer Graphics",
4.7). Each ray starts a little off the surface, ``offset`` along its normal, so that it does
not find the very triangle it starts on ("shadow acne" of ray tracers).

`reference_cpu.truth.embree.cast_triangles` shoots every ray from one shared origin (the
eye); shadow rays start at every surface point, so this module hands Embree one origin per
ray, in the same frame (`reference_cpu.truth.embree.embree_scene`): the scene moved and
scaled into a box `reference_cpu.truth.embree.SCENE_BOX` wide, where float32 is fine.
"""

from __future__ import annotations

import numpy as np

from scene_model.meshes import TriangleMesh
from scene_model.scene import DirectionalLight

from .embree import embree_scene, import_embreex
from .mesh_cast import truth_meshes


def first_hits(meshes: list[TriangleMesh], origins: np.ndarray,
               directions: np.ndarray) -> np.ndarray:
    """Distance (N,) along each ray to the first triangle it meets, inf where none.

    Parameters
    ----------
    meshes : list of TriangleMesh
        In world coordinates (m).
    origins : (N, 3) float64 ndarray
        One origin per ray.
    directions : (N, 3) float64 ndarray
        Unit directions.
    """
    import_embreex()                      # a one-line error where embreex is missing
    t = np.full(len(origins), np.inf)
    meshes = [m for m in meshes if len(m.triangles)]
    if not meshes or len(origins) == 0:
        return t
    scene, centre, scale = embree_scene(truth_meshes(meshes))
    found = scene.run(((origins - centre) * scale).astype(np.float32),
                      np.ascontiguousarray(directions, dtype=np.float32), output=1)
    hit = found["geomID"] >= 0
    t[hit] = found["tfar"][hit].astype(np.float64) / scale
    return t


def shadow_rays(meshes: list[TriangleMesh], points: np.ndarray, normals: np.ndarray, light,
                offset: float = 1e-4) -> np.ndarray:
    """Visibility (N,) of one light from surface points: 1 if the shadow ray reaches it,
    else 0.

    Parameters
    ----------
    meshes : list of TriangleMesh
        Every occluder, open or closed.
    points : (N, 3) float64 ndarray
        Surface points (m).
    normals : (N, 3) float64 ndarray
        Unit normals on the side the points are seen from; each ray starts ``offset`` along
        its normal from its point.
    light : PointLight, SpotLight or DirectionalLight
        A spot light casts from its position, as a point light.
    offset : float
        Metres, well above Embree's float32 rounding in its scaled frame (about 1e-7 of the
        scene's size).
    """
    origins = points + offset * normals
    if isinstance(light, DirectionalLight):
        d = np.asarray(light.direction, np.float64)
        directions = np.broadcast_to(-d / np.linalg.norm(d), origins.shape)
        reach = np.full(len(origins), np.inf)
    else:
        to_light = np.asarray(light.position, np.float64) - origins
        reach = np.linalg.norm(to_light, axis=1)
        directions = to_light / reach[:, None]
    # Occluded by a triangle nearer than the light; a directional light is never reached.
    return np.where(first_hits(meshes, origins, directions) < reach, 0.0, 1.0)
