"""Back faces that no pixel can show: which meshes a rasteriser may cull and draw the same.

A closed mesh (every edge used once in each direction, `shadow_volumes.neighbours`) whose
triangles are wound outward bounds a solid. A ray that starts outside the solid enters it
before it leaves it, so along that ray a front face (one turned towards where the ray came
from) always lies in front of any back face, and the depth test would throw every back
face's fragment away. Skipping them before they are rasterised, back-face culling (Foley et
al., "Computer Graphics: Principles and Practice", 2nd ed., section 15.2.4), then changes no
pixel, only the work.

The condition is on where the rays start. A rasteriser's pixel ray counts only from the
near plane on (`reference_cpu.rasterise.NEAR`): a solid that reaches in front of that plane
is cut open there, and its inside, back faces, shows through the cut. Every point where a
ray crosses the near plane lies within `near_reach` of the eye (the near plane's corner is
the farthest), so a solid whose bounding box is farther than that from the eye is met from
outside by every ray. `culled_meshes` asks both questions of each mesh.

The NumPy rasteriser's ``cull_back_faces`` culls every mesh, closed or not, as the lesson's
step does; the GPU pipeline (`gpu_shader.raster_render`) culls only what this module allows,
because its pictures must stay the reference's.
"""

from __future__ import annotations

import math

import numpy as np

from scene_model.camera import Camera
from scene_model.meshes import TriangleMesh

from .rasterise import NEAR
from .shadow_volumes import neighbours


def signed_volume(mesh: TriangleMesh) -> float:
    """The volume a closed mesh encloses, positive when its triangles are wound outward
    (anticlockwise seen from outside): the sum over triangles of a . (b x c) / 6, the
    divergence theorem on the tetrahedra from the origin (Zhang and Chen 2001, "Efficient
    feature extraction for 2D/3D objects in mesh representation")."""
    a, b, c = (mesh.positions[mesh.triangles[:, k]].astype(np.float64) for k in range(3))
    return float(np.sum(a * np.cross(b, c)) / 6.0)


def bounds_a_solid(mesh: TriangleMesh, closed: bool | None = None) -> bool:
    """Whether ``mesh`` is closed and wound outward, so that its back faces are hidden from
    any eye outside it. ``closed``: whether `neighbours` found it closed, where the caller
    has asked already (None: ask)."""
    if closed is None:
        closed = len(mesh.triangles) > 0 and neighbours(mesh) is not None
    return closed and signed_volume(mesh) > 0


def near_reach(camera: Camera, width: int, height: int, near: float = NEAR) -> float:
    """The farthest from the eye any pixel ray meets the near plane: its corner's distance,
    near sqrt(1 + (h W / H)^2 + h^2) with h = tan(fov / 2)."""
    h = math.tan(math.radians(camera.fov) / 2)
    return near * math.sqrt(1.0 + (h * width / height) ** 2 + h * h)


def box_distance(point, low, high) -> float:
    """The distance from ``point`` (3,) to the box [low, high] (each (3,)): 0 inside."""
    outside = np.maximum(np.maximum(np.subtract(low, point), np.subtract(point, high)), 0.0)
    return float(np.sqrt(np.sum(outside * outside)))


def culled_meshes(solid, boxes, camera: Camera, width: int, height: int) -> np.ndarray:
    """(K,) bool: the meshes whose back faces no pixel ray of ``camera`` can meet first.

    Parameters
    ----------
    solid : (K,) bool
        `bounds_a_solid` of each mesh (it does not change as the camera moves).
    boxes : list of K ((3,), (3,)) float
        Each mesh's bounding box, its low and high corners.
    camera : Camera
    width, height : int
        The image's size (the near plane's corners depend on its aspect).
    """
    reach = near_reach(camera, width, height)
    eye = np.asarray(camera.position, dtype=np.float64)
    # 2x: the near plane's corner and the box are compared in float64 while a GPU clips in
    # float32 (a millimetre of reach is a thousand float32 steps at 10 m); a box nearer than
    # twice the reach is simply drawn whole.
    return np.array([bool(s) and box_distance(eye, low, high) > 2.0 * reach
                     for s, (low, high) in zip(solid, boxes)], dtype=bool)
