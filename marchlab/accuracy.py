"""Speed against error: sweep the march settings on every backend and measure both, in one run.

For each scene, backend, precision and setting, one `Row`: the median time per frame, the steps
per pixel, and the errors against independent truth (`reference_cpu.truth`): the analytic
truth for the scenes made only of spheres, boxes and planes, the Embree truth (meshes
ray-cast by Intel Embree) for the others. Each scene's truth is built once (`scene_truth`),
with its own error (`marchlab.accuracy_truth`), and every row says which truth it was
measured against:

- **depth**: |t - t_true| where both hit, and the hit point's distance to the true surface,
  |sdf(p)| of the scene's float64 SDF (the *surface* error: it needs no truth at all);
- **hit/miss**: pixels whose classification differs from the truth's, and how many of them
  lie off the band around the truth's silhouettes (where a tangent ray may go either way,
  widened by the truth's own error in pixels);
- **normal**: the angle to the true normal (the Embree truth's is the float64 SDF's gradient
  at its hit point, not the mesh's facet);
- **colour**: max |Δ| against a "gold" render (NumPy float64, epsilon 1e-6, 4096 steps):
  colour has no truth, so the gold render stands in.

An error that lies, pixel by pixel, within the truth's own error (`SceneTruth`) is marked
(`within_truth`): the truth cannot tell it from 0. `pareto` keeps the settings no other beats
on both time and error; `recommend` names, per backend, the fastest setting whose errors stay
within `TOLERANCES`. ``marchlab bench accuracy`` runs it and writes the report with its plots
(`marchlab.accuracy_report`; ``make speed-vs-error`` writes docs/speed-vs-error.md).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from scene_model.scene import Scene, rendered_scene

from .accuracy_truth import (TRUTH_RESOLUTION, SceneTruth, angle_deg, p99, scene_truth, statistic,
                             truth_method, within_truth)
from .budget import MAX_BENCH_RAY_STEPS, check, ray_steps
from .compare import boundary, dilate
from .render import backend_problem, render

# What "accurate enough" means for a recommendation: surface distance within epsilon at the
# default epsilon, no misclassified pixel off the silhouette band, normals within half a degree.
TOLERANCES = {"surface_p99": 1e-3, "off_band": 0, "normal_p99_deg": 0.5}

# The settings swept: each is a label and the render settings it changes. One axis at a
# time around the scene's own settings, plus the relaxation modes at every epsilon.
EPSILONS = (1e-2, 1e-3, 1e-4)
MARCHING = {
    "plain": {},
    "fixed 1.2": {"relaxation": "fixed", "omega": 1.2},
    "fixed 1.6": {"relaxation": "fixed", "omega": 1.6},
    "auto": {"relaxation": "auto"},
    "auto + spheres": {"relaxation": "auto", "bounding_spheres": True},
    "plain + spheres": {"bounding_spheres": True},
    "cone": {"prepass": "cone"},
    "cone + auto": {"prepass": "cone", "relaxation": "auto"},
}
OTHER = {
    "max_steps 64": {"max_steps": 64},
    "max_steps 1024": {"max_steps": 1024},
    "tetrahedron normals": {"normal_method": "tetrahedron"},
}

# --- The scenes ------------------------------------------------------------------------------

def analytic_scenes() -> dict[str, Scene]:
    """Scenes the analytic truth can trace exactly: the bundled classroom, and rotated boxes
    and spheres on a floor seen from low down (grazing floor rays, box edges and corners)."""
    from scene_model.builder import (Camera, Checker, Material, PointLight, RenderSettings, box,
                                     plane, sphere)
    from scene_model.scenefile import load_scene
    boxes = Scene(
        description="rotated boxes and spheres on a checker floor, seen from low down",
        camera=Camera(position=(0.0, 0.9, 6.0), look_at=(0.0, 0.5, 0.0), fov=55.0),
        render=RenderSettings(shadows="hard", max_distance=60.0),
        materials={"floor": Material(checker=Checker()), "default": Material(ks=0.5)},
        lights=(PointLight(position=(-3.0, 5.0, 4.0), linear=0.02),),
        objects=(plane(material="floor"),
                 box(0.6, 0.4, 0.5).rotate(0, 35, 0).at(-1.4, 0.4, 0.0),
                 box(0.35).rotate(30, 45, 10).at(0.4, 0.9, -0.8),
                 sphere(0.5).at(1.5, 0.5, 0.6),
                 sphere(0.25).at(0.2, 0.25, 1.2)))
    return {"classroom": load_scene("classroom"), "boxes": boxes}


def sweep_scenes() -> dict[str, Scene]:
    """`analytic_scenes`, then every bundled scene the analytic truth cannot trace (those
    are measured against the Embree truth, `truth_method`)."""
    from scene_model.scenefile import bundled_scene_names, load_scene
    scenes = analytic_scenes()
    for name in bundled_scene_names(meshes=False):
        scene = load_scene(name)
        if truth_method(scene) == "embree":
            scenes[name] = scene
    return scenes


# --- One configuration -------------------------------------------------------------------------

def settings_grid() -> dict[str, dict]:
    """Label -> render-setting changes: the marching modes at each epsilon, then the others."""
    grid = {}
    for eps in EPSILONS:
        for name, change in MARCHING.items():
            grid[f"{name}, eps {eps:g}"] = {**change, "epsilon": eps}
    for name, change in OTHER.items():
        grid[f"plain, eps 0.001, {name}"] = {**change, "epsilon": 1e-3}
    return grid


@dataclass
class Row:
    """One configuration's time and errors (see the module docstring).

    ``truth`` names the truth the errors were measured against (`SceneTruth.label`);
    ``within_truth`` the error fields that truth cannot tell from 0 (`within_truth`, marked
    † in the report); ``hit_changed`` the pixels whose hit/miss differs from plain sphere
    tracing at the same epsilon on the same backend (None without that baseline in the grid).
    """
    scene: str
    backend: str
    precision: str
    setting: str
    ms: float
    steps_mean: float
    steps_p99: float
    depth_mean: float
    depth_p99: float
    depth_max: float
    surface_mean: float
    surface_p99: float
    surface_max: float
    misclassified: int
    off_band: int
    normal_p99_deg: float
    normal_max_deg: float
    color_p99: float
    color_max: float
    notes: list[str] = field(default_factory=list)
    truth: str = "analytic"
    within_truth: tuple[str, ...] = ()
    hit_changed: int | None = None

    def error(self) -> float:
        """The error the Pareto frontier uses: p99 distance of hit points to the surface."""
        return self.surface_p99

    def within(self, tolerances=TOLERANCES) -> bool:
        """Whether the errors are within ``tolerances``; a normal error no larger than the
        truth's own cannot be held against the renderer."""
        return (self.surface_p99 <= tolerances["surface_p99"]
                and self.off_band <= tolerances["off_band"]
                and (self.normal_p99_deg <= tolerances["normal_p99_deg"]
                     or "normal_p99_deg" in self.within_truth))


def configured(scene: Scene, change: dict) -> Scene:
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **change))


GOLD = {"epsilon": 1e-6, "max_steps": 4096}


def gold_render(scene: Scene, width: int, height: int, allow_large: bool = False):
    """The colour stand-in for truth: NumPy float64 with a tiny epsilon and many steps."""
    return render(configured(scene, GOLD), width, height, backend="numpy", precision="float64",
                  allow_large=allow_large)


def timed_render(scene, width, height, backend, precision, repeat, allow_large=False):
    """(median seconds per frame, last frame); the first render (compilation) is not timed."""
    frame = render(scene, width, height, backend=backend, precision=precision,
                   allow_large=allow_large)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        frame = render(scene, width, height, backend=backend, precision=precision,
                       allow_large=allow_large)
        times.append(time.perf_counter() - start)
    return float(np.median(times)), frame


def measure(name, scene, reference: SceneTruth, gold, backend, precision, setting, change,
            size, repeat, allow_large=False):
    """Render one configuration and measure it against ``reference`` and ``gold``.

    Returns
    -------
    row : Row
    hit : (H, W) bool ndarray
        The frame's hit mask (a baseline for `Row.hit_changed`).
    """
    from reference_cpu.truth import surface_distances
    from scene_model.camera import camera_rays
    width, height = size
    truth = reference.truth
    seconds, frame = timed_render(configured(scene, change), width, height, backend, precision,
                                  repeat, allow_large)
    both = frame.hit & truth.hit
    depth_error = np.abs(frame.depth[both].astype(np.float64) - truth.depth[both])
    origin, directions = camera_rays(scene.camera, width, height, np.float64)
    surface = surface_distances(rendered_scene(scene).objects, origin, directions[frame.hit],
                                frame.depth[frame.hit])
    differ = frame.hit != truth.hit
    angle = angle_deg(frame.normal[both].astype(np.float64), reference.normal[both])
    steps = frame.steps.astype(np.float64) + prepass_share(configured(scene, change), width,
                                                           height, precision)
    errors = {"depth_mean": statistic(depth_error, np.mean), "depth_p99": statistic(depth_error, p99),
              "depth_max": statistic(depth_error, np.max),
              "normal_p99_deg": statistic(angle, p99), "normal_max_deg": statistic(angle, np.max)}
    marked = within_truth({"depth": depth_error, "normal": angle},
                          {"depth": reference.depth_error[both],
                           "normal": reference.normal_error_deg[both]})
    off_band = differ & ~reference.band
    if reference.band_px and not off_band.any():
        # Misclassified pixels that only the truth's wider band excuses are marked too.
        if (differ & ~dilate(boundary(truth.hit.astype(np.int64)), 1)).any():
            marked += ("off_band",)
    row = Row(
        scene=name, backend=backend, precision=precision, setting=setting, ms=1000 * seconds,
        steps_mean=float(steps.mean()), steps_p99=float(np.percentile(steps, 99)),
        **errors, surface_mean=statistic(surface, np.mean), surface_p99=statistic(surface, p99),
        surface_max=statistic(surface, np.max),
        misclassified=int(differ.sum()), off_band=int(off_band.sum()),
        color_p99=float(np.percentile(np.abs(frame.color - gold.color).max(axis=-1), 99)),
        color_max=float(np.abs(frame.color - gold.color).max()),
        notes=[] if np.isfinite(frame.color).all() else ["non-finite colour"],
        truth=reference.label(), within_truth=marked)
    return row, frame.hit


def prepass_share(scene: Scene, width: int, height: int, precision: str) -> np.ndarray:
    """(H, W): each pixel's share of the cone pre-pass's SDF evaluations (its tile's cone
    steps over the tile's pixels; 0 without a pre-pass), so that a row's steps per pixel
    count all the work. The same in every backend: they run the same cone march."""
    from reference_cpu.cone_prepass import over_pixels, start_distances, tile_pixels
    from reference_cpu.scene_sdf import build_scene_sdf
    r = scene.render
    if r.prepass == "none":
        return np.zeros((height, width))
    dtype, tile = np.dtype(precision), r.prepass_tile
    _, tile_steps = start_distances(scene.camera, width, height,
                                    build_scene_sdf(rendered_scene(scene).objects, dtype),
                                    tile, r.max_steps, r.epsilon, r.max_distance, dtype)
    return over_pixels(tile_steps / tile_pixels(width, height, tile), width, height, tile)


def backends_present() -> list[tuple[str, str]]:
    """(backend, precision) pairs that can run here, numpy first."""
    pairs = [("numpy", "float64"), ("numpy", "float32")]
    if backend_problem("opencl") is None:
        pairs += [("opencl", "float64"), ("opencl", "float32")]
    if backend_problem("gpu") is None:
        pairs += [("gpu", "float32")]
    return pairs


def baseline_setting(change: dict, scene: Scene) -> str:
    """The label of plain sphere tracing at the epsilon of ``change`` (as `settings_grid`)."""
    return f"plain, eps {change.get('epsilon', scene.render.epsilon):g}"


def sweep_ray_steps(scenes: dict[str, Scene], grid: dict, pairs: list, size, repeat) -> int:
    """The work of `sweep` at worst, in ray steps (`marchlab.budget.ray_steps`): each
    scene's gold render, and 1 + ``repeat`` renders of every configuration."""
    total = 0
    for scene in scenes.values():
        total += ray_steps(configured(scene, GOLD), *size)
        for change in grid.values():
            total += len(pairs) * (1 + repeat) * ray_steps(configured(scene, change), *size)
    return total


def sweep(scenes: dict[str, Scene], size=(160, 120), repeat=3, grid=None, pairs=None,
          progress=None, truths: dict | None = None,
          resolution: int = TRUTH_RESOLUTION, allow_large: bool = False) -> list[Row]:
    """Every scene x backend/precision x setting of ``grid`` (default `settings_grid`).

    ``truths`` caches each scene's `SceneTruth` by name: the ones missing are built (at
    ``resolution`` for the Embree truth) and added, so one run builds each truth once.
    The whole sweep's work (`sweep_ray_steps`) is checked against
    `marchlab.budget.MAX_BENCH_RAY_STEPS` before it starts, unless ``allow_large``.
    """
    grid = settings_grid() if grid is None else grid
    pairs = backends_present() if pairs is None else pairs
    truths = {} if truths is None else truths
    check(sweep_ray_steps(scenes, grid, pairs, size, repeat), MAX_BENCH_RAY_STEPS,
          f"the sweep at {size[0]}x{size[1]}", "ray steps at worst", allow_large)
    rows = []
    for name, scene in scenes.items():
        if name not in truths:
            truths[name] = scene_truth(scene, *size, resolution=resolution)
        gold = gold_render(scene, *size, allow_large=True)         # within the sweep's budget
        for backend, precision in pairs:
            hits = {}
            for setting, change in grid.items():
                row, hits[setting] = measure(name, scene, truths[name], gold, backend,
                                             precision, setting, change, size, repeat,
                                             allow_large=True)
                baseline = hits.get(baseline_setting(change, scene))
                if baseline is not None:
                    row.hit_changed = int((baseline != hits[setting]).sum())
                rows.append(row)
                if progress is not None:
                    progress(rows[-1])
    return rows


# --- Choosing ---------------------------------------------------------------------------------

def pareto(rows: list[Row]) -> list[Row]:
    """The rows no other row beats on both time and `Row.error` (ties kept), fastest first."""
    front = [r for r in rows
             if not any(o.ms <= r.ms and o.error() <= r.error()
                        and (o.ms < r.ms or o.error() < r.error()) for o in rows)]
    return sorted(front, key=lambda r: r.ms)


def recommend(rows: list[Row], tolerances=TOLERANCES) -> dict[tuple[str, str], Row | None]:
    """Per (backend, precision): the fastest setting within ``tolerances`` on every scene.

    A setting's time is the sum over scenes, so a setting must be good everywhere.
    """
    out = {}
    for key in dict.fromkeys((r.backend, r.precision) for r in rows):
        mine = [r for r in rows if (r.backend, r.precision) == key]
        by_setting: dict[str, list[Row]] = {}
        for r in mine:
            by_setting.setdefault(r.setting, []).append(r)
        good = [(sum(r.ms for r in rs), s) for s, rs in by_setting.items()
                if all(r.within(tolerances) for r in rs)]
        out[key] = min(good)[1] if good else None
    return out


def numpy_rows(rows: list[Row], scene: str) -> dict[str, Row]:
    """The NumPy float64 rows of ``scene`` by setting."""
    return {r.setting: r for r in rows
            if r.scene == scene and (r.backend, r.precision) == ("numpy", "float64")}


def steps_saved(rows: list[Row], setting: str, baseline: str) -> dict[str, float]:
    """Per scene: 1 - mean steps of ``setting`` / mean steps of ``baseline`` (numpy float64)."""
    out = {}
    for scene in dict.fromkeys(r.scene for r in rows):
        get = numpy_rows(rows, scene)
        if setting in get and baseline in get:
            out[scene] = 1 - get[setting].steps_mean / get[baseline].steps_mean
    return out


def embree_problem() -> str | None:
    """Why the Embree truth cannot run here, or None."""
    from importlib.util import find_spec
    if find_spec("embreex") is None or find_spec("skimage") is None:
        return "the Embree truth needs embreex and scikit-image: pip install 'marchlab[embree]'"
    return None
