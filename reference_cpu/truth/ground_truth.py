"""Ground truth for the reference: depth, normal and hit images computed without sphere tracing.

Two methods, both over the same primary rays as every renderer (`marchlab.camera_rays`, float64):

- ``"analytic"``: exact float64 ray intersections with unions of spheres, boxes and planes
  (`reference_cpu.truth.analytic`). Its error is float64 rounding.
- ``"embree"``: any bounded scene, meshed (`reference_cpu.truth.mesh`) and ray-cast in float32
  by Intel Embree (`reference_cpu.truth.embree`). Its error is the mesh's distance from the
  true surface, stated as a bound and measured at every hit.

Both follow the rendering contract where it is geometry: t is the distance along the unit ray,
a ray that starts inside a solid sees the inside of its surface, and a hit farther than
``render.max_distance`` is a miss. The error of a method is measured, not assumed: at every hit
point p, |sdf(p)| of the scene's float64 SDF (`reference_cpu.scene_sdf`) is p's distance to the
true surface when the SDF is exact (a lower bound on it where operators make the SDF a bound).
docs/ground-truth.md explains the methods and the numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from scene_model.camera import camera_rays, check_image_size
from scene_model.errors import MarchlabError
from scene_model.scene import Scene, rendered_scene

from ..scene_sdf import build_scene_sdf
from .analytic import trace_analytic
from .parts import Part, part_sdf, scene_parts

METHODS = ("analytic", "embree")
DEFAULT_RESOLUTION = 128
FLOAT64_ULPS = 64          # float64 units in the last place allowed per analytic hit (stated)


@dataclass(frozen=True)
class Truth:
    """Depth, normal and hit images of a scene, and how far they may be from the surface.

    Attributes
    ----------
    depth : (H, W) float64 ndarray
        t along the unit ray to the first surface; inf on a miss.
    normal : (H, W, 3) float64 ndarray
        Unit outward normal there; 0 on a miss.
    hit : (H, W) bool ndarray
    object_id : (H, W) int32 ndarray
        Depth-first index of the primitive hit (`scene_model.shapes.primitives`); -1 on a miss.
    method : str
        ``"analytic"`` or ``"embree"``.
    error_bound : float
        Largest distance from a hit point to the true surface that the method allows (world
        units): the sum of ``error_terms``.
    error_terms : dict of str to float
        ``"mesh"``: half a cell diagonal of the coarsest marching-cubes grid (0 if none);
        ``"tessellation"``: the largest computed distance of a tessellated sphere from the
        sphere; ``"rounding"``: floating-point rounding of the hit points.
    measured_error, measured_error_p99 : float
        Largest and 99th-percentile |sdf(hit point)| over the hits (0 without hits).
    """
    depth: np.ndarray
    normal: np.ndarray
    hit: np.ndarray
    object_id: np.ndarray
    method: str
    error_bound: float
    error_terms: dict = field(default_factory=dict)
    measured_error: float = 0.0
    measured_error_p99: float = 0.0

    def arrays(self) -> dict:
        """Everything as NumPy arrays, the contents of a ``marchlab truth`` .npz file."""
        out = {"depth": self.depth, "normal": self.normal, "hit": self.hit,
               "object_id": self.object_id, "method": np.array(self.method),
               "error_bound": np.array(self.error_bound),
               "measured_error": np.array(self.measured_error),
               "measured_error_p99": np.array(self.measured_error_p99)}
        out.update({f"error_{name}": np.array(value) for name, value in self.error_terms.items()})
        return out


def ground_truth(scene: Scene, width: int, height: int, method: str = "analytic",
                 resolution: int = DEFAULT_RESOLUTION, progress=None) -> Truth:
    """The ground truth of ``scene`` seen by its camera at ``width`` x ``height`` pixels.

    Parameters
    ----------
    scene : Scene
        Its bodies are drawn as spheres after its objects, as every renderer draws them.
    width, height : int
    method : {"analytic", "embree"}
    resolution : int
        Embree only: marching-cubes cells across each meshed part's bounding sphere.
    progress : callable(done, total), optional
        Embree only: called after each part is meshed and once the rays are cast (meshing
        at a high resolution takes seconds a part).

    Raises
    ------
    SceneError
        The analytic method met a node other than sphere, box, plane, union, translate,
        rotate or scale; or the embree method an unbounded one. The error names its path.
    MarchlabError
        An unknown method, or embreex missing.
    """
    if method not in METHODS:
        raise MarchlabError(f"unknown method {method!r} (one of: {', '.join(METHODS)})")
    if not isinstance(scene, Scene):
        raise MarchlabError(f"scene must be a marchlab.Scene (got {type(scene).__name__})")
    check_image_size(width, height)
    scene = rendered_scene(scene)
    parts = scene_parts(scene.objects)
    origin, directions = camera_rays(scene.camera, width, height, np.float64)
    rays = directions.reshape(-1, 3)
    if method == "analytic":
        t, normal, object_id = trace_analytic(parts, origin, rays)
        rounding = FLOAT64_ULPS * float(np.finfo(np.float64).eps) * (np.linalg.norm(origin) + t)
        terms = {}
    else:
        t, normal, object_id, rounding, terms = _trace_embree(parts, scene, origin, rays,
                                                              resolution, progress)

    # The contract's far limit: a surface beyond max_distance is not seen.
    beyond = t > scene.render.max_distance
    t = np.where(beyond, np.inf, t)
    normal = np.where(beyond[:, None], 0.0, normal)
    object_id = np.where(beyond, -1, object_id).astype(np.int32)
    hit = np.isfinite(t)
    terms["rounding"] = float(rounding[hit].max(initial=0.0))

    measured = measured_errors(scene.objects, origin, rays[hit], t[hit])
    return Truth(depth=t.reshape(height, width), normal=normal.reshape(height, width, 3),
                 hit=hit.reshape(height, width), object_id=object_id.reshape(height, width),
                 method=method, error_bound=float(sum(terms.values())), error_terms=terms,
                 measured_error=measured[0], measured_error_p99=measured[1])


def surface_distances(objects, origin, directions, t) -> np.ndarray:
    """|sdf| at the hit points origin + t d (float64 scene SDF): each point's distance to the
    true surface where the SDF is exact, a lower bound on it elsewhere. (N,) ndarray."""
    points = origin + np.asarray(t, np.float64)[:, None] * directions
    return np.abs(build_scene_sdf(objects, np.float64)(points)[0])


def measured_errors(objects, origin, directions, t) -> tuple[float, float]:
    """(max, 99th percentile) of `surface_distances`."""
    if len(t) == 0:
        return 0.0, 0.0
    error = surface_distances(objects, origin, directions, t)
    return float(error.max()), float(np.percentile(error, 99))


def _trace_embree(parts: list[Part], scene: Scene, origin, rays, resolution: int,
                  progress=None):
    """Mesh every part, cast the rays with Embree, and label the hits with object ids.

    Returns t, normal, object_id, the rounding bound of each ray, and the mesh error terms.
    """
    from .embree import (FLOAT32_EPS, ROUNDING_ULPS, SCENE_BOX, cast, import_embreex,
                               scene_frame)
    from .mesh import part_mesh

    import_embreex()                          # say what is missing before meshing anything
    if isinstance(resolution, bool) or not isinstance(resolution, int) or resolution < 2:
        raise MarchlabError(f"resolution must be an integer of at least 2 (got {resolution!r})")
    n = len(rays)
    if not parts:
        return (np.full(n, np.inf), np.zeros((n, 3)), np.full(n, -1, np.int32), np.zeros(n),
                {"mesh": 0.0, "tessellation": 0.0})
    # A plane's square reaches a little past max_distance, so every hit within it is found.
    reach = 1.01 * scene.render.max_distance
    report = progress or (lambda done, total: None)
    meshes = []
    for part in parts:
        meshes.append(part_mesh(part, resolution, origin, reach))
        report(len(meshes), len(parts) + 1)        # the last step: casting the rays
    sdfs = [part_sdf(part) for part in parts]
    marched = [m.method == "marching cubes" for m in meshes]
    mesh_term = max((m.bound for m, mc in zip(meshes, marched) if mc), default=0.0)
    tessellation_term = max((m.bound for m, mc in zip(meshes, marched) if not mc), default=0.0)

    # A hit counts as inside another part when it is deeper in it than both meshes' errors
    # and the float32 rounding of the whole scaled scene could explain.
    _, scale = scene_frame(meshes)
    slack = 2 * (mesh_term + tessellation_term) + ROUNDING_ULPS * FLOAT32_EPS * SCENE_BOX / scale

    def inside_other(points, part_index):
        inside = np.zeros(len(points), bool)
        for j, sdf in enumerate(sdfs):
            elsewhere = part_index != j
            if elsewhere.any():
                inside[elsewhere] |= sdf(points[elsewhere])[0] < -slack
        return inside

    t, normal, part, rounding = cast(meshes, origin, rays, inside_other if len(parts) > 1
                                     else None)
    report(len(parts) + 1, len(parts) + 1)
    object_id = np.full(n, -1, np.int32)
    for j, (p, sdf) in enumerate(zip(parts, sdfs)):
        on = part == j
        if not on.any():
            continue
        if marched[j]:   # a CSG subtree: the primitive its operators choose at the hit point
            object_id[on] = sdf(origin + t[on, None] * rays[on])[1]
        else:
            object_id[on] = p.first_id
    terms = {"mesh": float(mesh_term), "tessellation": float(tessellation_term)}
    return t, normal, object_id, rounding, terms
