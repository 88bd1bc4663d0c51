"""The ground truth a speed-against-error sweep measures against, with its own error.

`marchlab.accuracy` compares every render with an independent truth
(`reference_cpu.truth`): exact intersections for scenes of spheres, boxes and planes, Embree
ray casts of meshed scenes for the others. A meshed truth is itself off by a little, so
`scene_truth` also measures, pixel by pixel, how far the truth's own hits lie from the
surface (a Newton step along the ray) and how far its normal turns over that step, and widens
the silhouette band by its stated bound; `within_truth` then says which of a render's errors
the truth cannot tell from 0. `truth_scene` writes repeats out as unions of copies, which
Embree can trace.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from scene_model.bounds import bounding_sphere
from scene_model.errors import MarchlabError
from scene_model.geometry import angle_between, dot, rotation_matrix
from scene_model.scene import Scene, rendered_scene
from scene_model.shapes import Repeat, Rotate, Scale, Translate, Union

from .compare import boundary, dilate

if TYPE_CHECKING:
    from reference_cpu.truth import Truth

# Marching-cubes cells across each meshed part of an Embree truth. Measured on the bundled
# scenes at 160x120: at 128 the p99 distance of the truth's hits from the surface is 1.7e-4 to
# 5e-4, and its own depth error p99 4e-4 to 7e-4 (`SceneTruth`), under 1e-3, the middle epsilon
# swept; the four truths take about 15 s to build. 256 halves the stated bound and takes 4 to
# 6 times as long (docs/ground-truth.md), while float32 rounding and the icospheres keep the
# p99 of the scenes with spheres near 1e-4.
TRUTH_RESOLUTION = 128
# Central differences of the float64 SDF: truncation ~h^2 |f'''| / 6, rounding ~1e-16 |p| / h;
# about 1e-9 or less for surfaces of radius above 0.1 within 100 units of the origin.
GRADIENT_STEP = 1e-6
# Most copies an infinite repeat is written out into (`written_out`).
MAX_COPIES = 10_000


def truth_method(scene: Scene) -> str:
    """``"analytic"`` where every part of the scene is a sphere, box or plane (what
    `reference_cpu.truth.analytic` intersects exactly), else ``"embree"``."""
    from reference_cpu.truth.analytic import ANALYTIC_KINDS
    from reference_cpu.truth.parts import scene_parts
    parts = scene_parts(rendered_scene(scene).objects)
    return "analytic" if all(isinstance(p.leaf, ANALYTIC_KINDS) for p in parts) else "embree"


def written_out(node, eye, reach: float):
    """``node`` with every repeat replaced by the union of its copies, for the Embree truth.

    A repeat folds space into cells and evaluates its child in the nearest one (Quilez,
    "Domain repetition", https://iquilezles.org/articles/sdfrepetition/); when the child lies
    inside its cell, the union of its translated copies has the same surface, inside and
    outside. Written out, each copy is a part of its own (`reference_cpu.truth.parts`): a
    sphere becomes an icosphere rather than a piece of one marching-cubes grid over the whole
    row. An infinite repeat keeps the copies within ``reach`` of ``eye``: the truth ignores
    surfaces beyond ``render.max_distance`` anyway.

    Parameters
    ----------
    node : scene_model.shapes.Node
    eye : (3,) ndarray
        The camera position in ``node``'s frame.
    reach : float
        ``render.max_distance`` in ``node``'s frame.

    Raises
    ------
    MarchlabError
        A repeated child reaches out of its cell, is unbounded, or an infinite repeat would
        need more than `MAX_COPIES` copies.
    """
    eye = np.asarray(eye, dtype=np.float64)
    match node:
        case Translate():          # the child is evaluated at p - offset
            return dataclasses.replace(node, child=written_out(node.child, eye - node.offset,
                                                                reach))
        case Rotate():             # ... at R^T p
            return dataclasses.replace(node, child=written_out(
                node.child, rotation_matrix(node.degrees).T @ eye, reach))
        case Scale():              # ... at p / f
            return dataclasses.replace(node, child=written_out(node.child, eye / node.factor,
                                                                reach / node.factor))
        case Repeat():
            child = written_out(node.child, eye, reach)      # a repeat in a repeat: bounded
            sphere = bounding_sphere(child)
            period = np.asarray(node.period, dtype=np.float64)
            if sphere is None:
                raise MarchlabError(f"a repeated {child.kind!r} is unbounded: cannot write "
                                    "out its copies for the truth")
            centre, radius = sphere
            axes = period > 0
            if np.any(np.abs(centre[axes]) + radius > period[axes] / 2):
                raise MarchlabError(f"a repeated {child.kind!r} reaches out of its cell: its "
                                    "copies would not have the repeat's surface")
            cells = []
            for axis in range(3):
                if not axes[axis]:
                    cells.append([0])
                elif node.count is not None:
                    cells.append(range(-node.count[axis], node.count[axis] + 1))
                else:   # the copies whose bounding sphere comes within reach of the eye
                    low = (eye[axis] - centre[axis] - reach - radius) / period[axis]
                    high = (eye[axis] - centre[axis] + reach + radius) / period[axis]
                    cells.append(range(math.ceil(low), math.floor(high) + 1))
            if math.prod(len(c) for c in cells) > MAX_COPIES:
                raise MarchlabError(f"a repeated {child.kind!r} would be written out into more "
                                    f"than {MAX_COPIES} copies for the truth")
            return Union(tuple(Translate(child, tuple(float(x) for x in period * cell))
                               for cell in itertools.product(*cells)))
    if hasattr(node, "children"):
        return dataclasses.replace(node, children=tuple(written_out(c, eye, reach)
                                                        for c in node.children))
    return node


def truth_scene(scene: Scene) -> Scene:
    """The scene the truth traces: its bodies drawn as objects, its repeats `written_out`."""
    scene = rendered_scene(scene)
    eye = np.asarray(scene.camera.position, dtype=np.float64)
    objects = tuple(written_out(o, eye, scene.render.max_distance) for o in scene.objects)
    return dataclasses.replace(scene, objects=objects)


# --- The truth of a scene, and its own error --------------------------------------------------

@dataclass
class SceneTruth:
    """A scene's ground truth, what the renders are compared with, and how wrong it may be.

    Attributes
    ----------
    truth : reference_cpu.truth.Truth
        Depth, hit mask, stated bound and measured |sdf| (`reference_cpu.truth.ground_truth`).
    normal : (H, W, 3) float64 ndarray
        The normal renders are compared with: the analytic truth's exact normal, or for the
        Embree truth the float64 SDF's gradient at its hit point (a mesh's facets tilt).
    surface_error : (H, W) float64 ndarray
        |sdf| of the float64 SDF at the truth's hits (its measured error); 0 on a miss.
    depth_error : (H, W) float64 ndarray
        The truth's own depth error at each hit, |sdf(p)| / |∇sdf(p) . d|: the length of a
        Newton step along the ray from its hit p to the SDF's zero, to first order in the
        surface's curvature; the stated bound over |cos θ| for the analytic truth; 0 on a miss.
    normal_error_deg : (H, W) float64 ndarray
        How much ``normal`` turns over that step (0 for the analytic truth).
    facet_error_deg : (H, W) float64 ndarray or None
        Embree only: angle between the mesh's facet normal and ``normal``.
    band : (H, W) bool ndarray
        Where a misclassified pixel is excused: within 1 + ``band_px`` pixels of the
        truth's silhouettes.
    band_px : int
        The truth's stated bound in pixels at its nearest silhouette, rounded up.
    resolution : int or None
        Embree's marching-cubes cells across each meshed part.
    seconds : float
        Time to build all of it.
    """
    truth: Truth
    normal: np.ndarray
    surface_error: np.ndarray
    depth_error: np.ndarray
    normal_error_deg: np.ndarray
    facet_error_deg: np.ndarray | None
    band: np.ndarray
    band_px: int
    resolution: int | None
    seconds: float

    @property
    def method(self) -> str:
        return self.truth.method

    def label(self) -> str:
        """``"analytic"``, or ``"embree 128"`` with its grid resolution."""
        return self.method if self.resolution is None else f"{self.method} {self.resolution}"

    def errors(self) -> dict[str, float]:
        """The truth's own error in the statistics of `Row` that it limits (key: Row field)."""
        hit = self.truth.hit
        return {"depth_mean": statistic(self.depth_error[hit], np.mean),
                "depth_p99": statistic(self.depth_error[hit], p99),
                "depth_max": statistic(self.depth_error[hit], np.max),
                "normal_p99_deg": statistic(self.normal_error_deg[hit], p99),
                "normal_max_deg": statistic(self.normal_error_deg[hit], np.max)}


def p99(a):
    return np.percentile(a, 99)


def statistic(a, f) -> float:
    return float(f(a)) if a.size else 0.0


def sdf_gradient(sdf, points, h=GRADIENT_STEP):
    """∇sdf at ``points`` (N, 3) by central differences: (N, 3) float64.

    The stencil of `reference_cpu.normals` (Quilez, "Normals for an SDF"), divided by 2h so
    that the length is kept: |∇sdf| < 1 says where an operator made the SDF only a bound.
    """
    from reference_cpu.normals import STENCILS
    gradient = np.zeros_like(points)
    for k in STENCILS["central"]:
        gradient += sdf(points + h * k)[0][:, None] * k
    return gradient / (2 * h)


def angle_deg(a, b):
    """Angles in degrees between vectors a and b, (N, 3) each: (N,) (`geometry.angle_between`)."""
    return np.degrees(angle_between(a, b))


def unit(v):
    """v (N, 3) normalised; 0 where v is 0."""
    size = np.sqrt(dot(v, v))[:, None]
    return np.divide(v, size, out=np.zeros_like(v), where=size > 0)


def silhouette_band_px(truth: Truth, directions) -> int:
    """The truth's stated bound in pixels where it is largest: at the nearest silhouette.

    A surface off by ``error_bound`` moves its silhouette by that much sideways, seen at the
    silhouette's depth t, which is error_bound / (t · α) pixels for rays α radians apart (the
    smallest spacing of neighbouring rays is used). Under a thousandth of a pixel counts as 0.
    ``directions`` are the camera's unit rays, (H, W, 3).
    """
    edge = boundary(truth.hit.astype(np.int64)) & truth.hit
    if not edge.any() or truth.error_bound <= 0:
        return 0
    across = angle_between(directions[:, 1:], directions[:, :-1]).min()
    down = angle_between(directions[1:], directions[:-1]).min()
    pixels = truth.error_bound / (truth.depth[edge].min() * min(across, down))
    return math.ceil(pixels) if pixels >= 1e-3 else 0


def scene_truth(scene: Scene, width: int, height: int, resolution: int = TRUTH_RESOLUTION,
                method: str | None = None) -> SceneTruth:
    """The truth of ``scene`` by ``method`` (default `truth_method`), and its own errors
    (see `SceneTruth`)."""
    from reference_cpu.scene_sdf import build_scene_sdf
    from reference_cpu.truth import ground_truth, surface_distances
    from scene_model.camera import camera_rays
    start = time.perf_counter()
    method = truth_method(scene) if method is None else method
    truth = ground_truth(truth_scene(scene), width, height, method=method, resolution=resolution)
    origin, directions = camera_rays(scene.camera, width, height, np.float64)
    hit = truth.hit
    d = directions[hit]
    objects = rendered_scene(scene).objects
    surface_error = np.zeros((height, width))
    surface_error[hit] = surface_distances(objects, origin, d, truth.depth[hit])
    depth_error = np.zeros((height, width))
    normal_error = np.zeros((height, width))
    if method == "analytic":
        normal, facet = truth.normal, None
        with np.errstate(divide="ignore"):      # a ray exactly along the surface: inf
            depth_error[hit] = truth.error_bound / np.abs(dot(truth.normal[hit], d))
    else:
        sdf = build_scene_sdf(objects, np.float64)
        p = origin + truth.depth[hit][:, None] * d
        gradient = sdf_gradient(sdf, p)
        normal = np.zeros((height, width, 3))
        normal[hit] = unit(gradient)
        # One Newton step along the ray, t -> t - f / (∇f . d), to the SDF's zero: its
        # length is the truth's depth error to first order, and the normal there tells how
        # much the true normal may differ from the one at the truth's hit.
        with np.errstate(divide="ignore", invalid="ignore"):
            step = sdf(p)[0] / dot(gradient, d)
        step = np.where(np.isfinite(step), step, np.inf)
        depth_error[hit] = np.abs(step)
        q = p - np.where(np.isfinite(step), step, 0.0)[:, None] * d
        normal_error[hit] = angle_deg(normal[hit], unit(sdf_gradient(sdf, q)))
        facet = np.zeros((height, width))
        facet[hit] = angle_deg(truth.normal[hit], normal[hit])
    band_px = silhouette_band_px(truth, directions)
    band = dilate(boundary(hit.astype(np.int64)), 1 + band_px)
    return SceneTruth(truth=truth, normal=normal, surface_error=surface_error,
                      depth_error=depth_error,
                      normal_error_deg=normal_error, facet_error_deg=facet, band=band,
                      band_px=band_px, resolution=None if method == "analytic" else resolution,
                      seconds=time.perf_counter() - start)


# The statistics of Row that a truth's own error can explain: (prefix, {statistic: field}).
MARKED = {"depth": {"mean": "depth_mean", "p99": "depth_p99", "max": "depth_max"},
          "normal": {"p99": "normal_p99_deg", "max": "normal_max_deg"}}
STATISTICS = {"mean": np.mean, "p99": p99, "max": np.max}


def within_truth(errors: dict[str, np.ndarray], own: dict[str, np.ndarray]) -> tuple[str, ...]:
    """The fields of `Row` that the truth cannot tell from 0, pixel by pixel.

    At a pixel, the true surface lies within the truth's own error of the truth's hit; a
    renderer whose error there is no larger may be exactly right, so the truth cannot tell
    its error from 0.

    Parameters
    ----------
    errors, own : dict of str to (N,) ndarray
        By ``"depth"`` and ``"normal"``: the renderer's error at each pixel where both hit,
        and the truth's own error there (`SceneTruth.depth_error`, ``normal_error_deg``).

    Returns
    -------
    tuple of str
        The fields (`MARKED`) whose statistic of the *excess*, max(error - own, 0) at each
        pixel, is 0: for a p99, at least 99% of the pixels are within the truth's own
        error; for a mean or a max, all of them. A truth without error of its own marks
        nothing.
    """
    marked = []
    for name, fields in MARKED.items():
        error, truth = errors[name], own[name]
        if error.size == 0 or not truth.max() > 0:
            continue
        excess = np.maximum(error - truth, 0.0)
        marked += [f for stat, f in fields.items() if STATISTICS[stat](excess) == 0]
    return tuple(marked)
