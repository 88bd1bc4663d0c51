"""Speed against error: sweep the march settings on every backend and measure both, in one run.

For each scene, backend, precision and setting, one `Row`: the median time per frame, the steps
per pixel, and the errors against independent truth (`reference_cpu.truth`):

- **depth**: |t - t_true| where both hit, and the hit point's distance to the true surface,
  |sdf(p)| of the scene's float64 SDF (exact for the unions of spheres, boxes and planes the
  analytic truth handles);
- **hit/miss**: pixels whose classification differs from the truth's, and how many of them
  lie off the 1-pixel band around the truth's silhouettes (where a tangent ray may go either way);
- **normal**: the angle to the true normal;
- **colour**: max |Δ| against a "gold" render (NumPy float64, epsilon 1e-6, 4096 steps):
  colour has no analytic truth, so the gold render stands in.

`pareto` keeps the settings no other beats on both time and error; `recommend` names, per
backend, the fastest setting whose errors stay within `TOLERANCES`. ``marchlab bench accuracy``
runs it and writes docs/speed-vs-error.md with its plots.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from .compare import dilate, boundary
from .render import backend_problem, render
from .scene import Scene

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
}
OTHER = {
    "max_steps 64": {"max_steps": 64},
    "max_steps 1024": {"max_steps": 1024},
    "tetrahedron normals": {"normal_method": "tetrahedron"},
}


def analytic_scenes() -> dict[str, Scene]:
    """Scenes the analytic truth can trace exactly: the bundled classroom, and rotated boxes
    and spheres on a floor seen from low down (grazing floor rays, box edges and corners)."""
    from .builder import (Camera, Checker, Material, PointLight, RenderSettings, box, plane,
                          sphere)
    from .scenefile import load_scene
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
    """One configuration's time and errors (see the module docstring)."""
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

    def error(self) -> float:
        """The error the Pareto frontier uses: p99 distance of hit points to the surface."""
        return self.surface_p99

    def within(self, tolerances=TOLERANCES) -> bool:
        return (self.surface_p99 <= tolerances["surface_p99"]
                and self.off_band <= tolerances["off_band"]
                and self.normal_p99_deg <= tolerances["normal_p99_deg"])


def configured(scene: Scene, change: dict) -> Scene:
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **change))


def gold_render(scene: Scene, width: int, height: int):
    """The colour stand-in for truth: NumPy float64 with a tiny epsilon and many steps."""
    return render(configured(scene, {"epsilon": 1e-6, "max_steps": 4096}), width, height,
                  backend="numpy", precision="float64")


def timed_render(scene, width, height, backend, precision, repeat):
    """(median seconds per frame, last frame); the first render (compilation) is not timed."""
    frame = render(scene, width, height, backend=backend, precision=precision)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        frame = render(scene, width, height, backend=backend, precision=precision)
        times.append(time.perf_counter() - start)
    return float(np.median(times)), frame


def measure(name, scene, truth, gold, backend, precision, setting, change, size, repeat) -> Row:
    """Render one configuration and measure it against ``truth`` and ``gold``."""
    from reference_cpu.truth import surface_distances
    from .camera import camera_rays
    width, height = size
    seconds, frame = timed_render(configured(scene, change), width, height, backend, precision,
                                  repeat)
    both = frame.hit & truth.hit
    depth_error = np.abs(frame.depth[both].astype(np.float64) - truth.depth[both])
    origin, directions = camera_rays(scene.camera, width, height, np.float64)
    surface = surface_distances(scene.objects, origin, directions[frame.hit],
                                frame.depth[frame.hit])
    differ = frame.hit != truth.hit
    band = dilate(boundary(truth.hit.astype(np.int64)), 1)
    cosine = np.clip(np.sum(frame.normal[both].astype(np.float64) * truth.normal[both], axis=-1),
                     -1, 1)
    angle = np.degrees(np.arccos(cosine))
    steps = frame.steps.astype(np.float64)
    stat = lambda a, f: float(f(a)) if a.size else 0.0
    p99 = lambda a: np.percentile(a, 99)
    return Row(
        scene=name, backend=backend, precision=precision, setting=setting, ms=1000 * seconds,
        steps_mean=float(steps.mean()), steps_p99=float(np.percentile(steps, 99)),
        depth_mean=stat(depth_error, np.mean), depth_p99=stat(depth_error, p99),
        depth_max=stat(depth_error, np.max), surface_mean=stat(surface, np.mean),
        surface_p99=stat(surface, p99), surface_max=stat(surface, np.max),
        misclassified=int(differ.sum()), off_band=int((differ & ~band).sum()),
        normal_p99_deg=stat(angle, p99), normal_max_deg=stat(angle, np.max),
        color_p99=float(np.percentile(np.abs(frame.color - gold.color).max(axis=-1), 99)),
        color_max=float(np.abs(frame.color - gold.color).max()),
        notes=[] if np.isfinite(frame.color).all() else ["non-finite colour"])


def backends_present() -> list[tuple[str, str]]:
    """(backend, precision) pairs that can run here, numpy first."""
    pairs = [("numpy", "float64"), ("numpy", "float32")]
    if backend_problem("opencl") is None:
        pairs += [("opencl", "float64"), ("opencl", "float32")]
    if backend_problem("gpu") is None:
        pairs += [("gpu", "float32")]
    return pairs


def sweep(scenes: dict[str, Scene], size=(160, 120), repeat=3, grid=None, pairs=None,
          progress=None) -> list[Row]:
    """Every scene x backend/precision x setting of ``grid`` (default `settings_grid`)."""
    from reference_cpu.truth import ground_truth
    grid = settings_grid() if grid is None else grid
    pairs = backends_present() if pairs is None else pairs
    rows = []
    for name, scene in scenes.items():
        truth = ground_truth(scene, *size, method="analytic")
        gold = gold_render(scene, *size)
        for backend, precision in pairs:
            for setting, change in grid.items():
                rows.append(measure(name, scene, truth, gold, backend, precision, setting,
                                    change, size, repeat))
                if progress is not None:
                    progress(rows[-1])
    return rows


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


def steps_saved(rows: list[Row], setting: str, baseline: str) -> dict[str, float]:
    """Per scene: 1 - mean steps of ``setting`` / mean steps of ``baseline`` (numpy float64)."""
    out = {}
    for scene in dict.fromkeys(r.scene for r in rows):
        get = {r.setting: r for r in rows
               if r.scene == scene and (r.backend, r.precision) == ("numpy", "float64")}
        if setting in get and baseline in get:
            out[scene] = 1 - get[setting].steps_mean / get[baseline].steps_mean
    return out


def format_number(x: float) -> str:
    if x == 0:
        return "0"
    if not math.isfinite(x):
        return str(x)
    return f"{x:.3g}" if 1e-3 <= abs(x) < 1e4 else f"{x:.1e}"


# --- The report -------------------------------------------------------------------------------

COLUMNS = [("scene", "scene"), ("backend", "backend"), ("precision", "precision"),
           ("setting", "setting"), ("ms", "ms/frame"), ("steps_mean", "steps mean"),
           ("steps_p99", "steps p99"), ("depth_mean", "\\|Δt\\| mean"), ("depth_p99", "\\|Δt\\| p99"),
           ("depth_max", "\\|Δt\\| max"), ("surface_mean", "surface mean"),
           ("surface_p99", "surface p99"), ("surface_max", "surface max"),
           ("misclassified", "hit/miss wrong"), ("off_band", "off silhouette band"),
           ("normal_p99_deg", "normal p99 °"), ("normal_max_deg", "normal max °"),
           ("color_p99", "colour p99 \\|Δ\\|"), ("color_max", "colour max \\|Δ\\|")]


def table(rows: list[Row]) -> str:
    """The rows as one Markdown table."""
    head = "| " + " | ".join(title for _, title in COLUMNS) + " |\n"
    head += "| " + " | ".join("---" if i < 4 else "---:" for i in range(len(COLUMNS))) + " |\n"
    lines = []
    for r in rows:
        cells = [getattr(r, key) for key, _ in COLUMNS]
        lines.append("| " + " | ".join(c if isinstance(c, str) else
                                       (str(c) if isinstance(c, int) else format_number(c))
                                       for c in cells) + " |")
    return head + "\n".join(lines) + "\n"


def plot(rows: list[Row], scene: str, path) -> None:
    """Time against p99 surface distance for one scene, one colour per backend, the
    Pareto frontier of each backend drawn as a line."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=100)
    mine = [r for r in rows if r.scene == scene]
    for key in dict.fromkeys((r.backend, r.precision) for r in mine):
        group = [r for r in mine if (r.backend, r.precision) == key]
        label = f"{key[0]} {key[1]}"
        floor = 1e-9          # a log axis cannot show 0
        points = ax.scatter([r.ms for r in group], [max(r.error(), floor) for r in group],
                            s=14, label=label)
        front = pareto(group)
        ax.plot([r.ms for r in front], [max(r.error(), floor) for r in front],
                color=points.get_facecolor()[0], linewidth=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median time per frame (ms)")
    ax.set_ylabel("p99 distance of hit points to the surface")
    ax.set_title(f"{scene}: speed against error (lines: each backend's Pareto frontier)")
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def write_report(rows: list[Row], markdown, image_dir, command: str, size, repeat,
                 uber: list[dict] | None = None, devices: dict | None = None) -> list:
    """Write the Markdown report and one plot per scene; return the paths written.

    Everything is rendered into memory first and written at the end, each file atomically,
    so an interrupted run leaves the previous report whole.
    """
    from pathlib import Path
    from .files import write_atomically
    markdown, image_dir = Path(markdown), Path(image_dir)
    scenes = list(dict.fromkeys(r.scene for r in rows))
    best = recommend(rows)
    saved = steps_saved(rows, "auto, eps 0.001", "plain, eps 0.001")
    saved_cull = steps_saved(rows, "auto + spheres, eps 0.001", "plain, eps 0.001")
    out = ["# Speed against error", "",
           "Generated by the command below; do not edit by hand. Every figure comes from one "
           "run on one machine, so the times are comparable with each other (not with other "
           "runs on this shared machine).", "", "```sh", command, "```", "",
           f"Image size {size[0]}x{size[1]}, median of {repeat} timed frames after one "
           "untimed (compiling) frame. Scenes: " + ", ".join(f"`{s}`" for s in scenes)
           + " (both traced exactly by the analytic truth, `reference_cpu/truth.py`)."]
    if devices:
        out += ["", "Devices: " + "; ".join(f"{k}: {v}" for k, v in devices.items()) + "."]
    out += ["", "## How to read it", "",
            "- **|Δt|**: depth against the exact intersection where both hit. On grazing "
            "floors a ray may stop anywhere in the epsilon shell, up to epsilon/|cos θ| "
            "short of the surface, so this grows at the horizon.",
            "- **surface**: the hit point's distance to the true surface (|sdf| of the "
            "float64 SDF, exact for these scenes). Sphere tracing promises less than "
            "epsilon; this is the error the Pareto frontier and the recommendations use.",
            "- **hit/miss wrong**: pixels classified differently from the truth; **off "
            "silhouette band**: those more than one pixel away from the truth's silhouettes "
            "(a ray within epsilon of an edge may hit or miss).",
            "- **normal**: angle to the exact normal; **colour**: against a NumPy float64 "
            "render with epsilon 1e-6 and 4096 steps (colour has no analytic truth). "
            "Colour max is set by checker and shadow edges, which move with the hit point; "
            "p99 is the typical error.",
            "", "## Fewer steps, same surface (issue 6's goal)", "",
            "Mean SDF evaluations per pixel saved against plain sphere tracing at epsilon "
            "1e-3 (NumPy float64; the goal is at least 25% with the hit mask unchanged and "
            "the surface within epsilon):", "",
            "| scene | auto relaxation | auto + bounding spheres |", "| --- | ---: | ---: |"]
    for scene in scenes:
        out.append(f"| {scene} | {100 * saved.get(scene, float('nan')):.1f}% | "
                   f"{100 * saved_cull.get(scene, float('nan')):.1f}% |")
    out += ["", "The same settings on every backend, against the truth:", "",
            table([r for r in rows if r.setting in ("plain, eps 0.001", "auto, eps 0.001",
                                                    "auto + spheres, eps 0.001")]),
            "## Recommended settings", "",
            "Per backend, the fastest setting (time summed over the scenes) whose p99 surface "
            f"distance is at most {TOLERANCES['surface_p99']:g}, with no misclassified pixel "
            f"off the silhouette band and p99 normal error at most "
            f"{TOLERANCES['normal_p99_deg']:g}° on every scene:", "",
            "| backend | precision | recommended |", "| --- | --- | --- |"]
    for (backend, precision), setting in best.items():
        out.append(f"| {backend} | {precision} | {setting or 'none within tolerance'} |")
    if uber:
        out += ["", "## A specialised shader against an uber shader", "",
                "The gpu backend generates a shader holding only what the scene uses. The "
                "uber shader (`gpu_shader/uber.py`) is one text for every scene: all "
                "primitives, lights, shading modes and features, chosen at run time by "
                "values in the parameter block (source 002 measured the same trade-off). "
                "Same images (tests/gpu/test_uber_shader.py); times side by side:", "",
                "| scene | specialised ms | uber ms | uber / specialised | compile ms "
                "(specialised, uber) |", "| --- | ---: | ---: | ---: | ---: |"]
        for u in uber:
            out.append(f"| {u['scene']} | {u['specialised_ms']:.1f} | {u['uber_ms']:.1f} | "
                       f"{u['ratio']:.2f}x | {u['specialised_compile_ms']:.0f}, "
                       f"{u['uber_compile_ms']:.0f} |")
    images = {}
    for scene in scenes:
        images[scene] = image_dir / f"speed-vs-error-{scene}.png"
        front = pareto([r for r in rows if r.scene == scene])
        relative = Path("images") / images[scene].name
        out += ["", f"## `{scene}`", "", f"![Speed against error, {scene}]({relative})", "",
                "Pareto frontier over all backends (no other configuration is both faster "
                "and more accurate):", "", table(front)]
    out += ["## Every configuration", "", table(rows)]
    written = []
    for scene, path in images.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp.png")
        plot(rows, scene, tmp)
        tmp.replace(path)
        written.append(path)
    write_atomically(markdown, ("\n".join(out) + "\n").encode())
    written.append(markdown)
    return written


def run(markdown="docs/speed-vs-error.md", image_dir="docs/images", size=(160, 120), repeat=3,
        command="marchlab bench accuracy", quick=False, echo=print) -> list:
    """The whole report: sweep, compare the uber shader if the gpu backend runs, write."""
    scenes = analytic_scenes()
    grid = settings_grid()
    if quick:                       # a smoke run: two settings, one scene
        scenes = {"classroom": scenes["classroom"]}
        grid = {k: grid[k] for k in ("plain, eps 0.001", "auto, eps 0.001")}
    pairs = backends_present()
    total = len(scenes) * len(grid) * len(pairs)
    done = []

    def progress(row):
        done.append(row)
        echo(f"[{len(done)}/{total}] {row.scene} {row.backend} {row.precision} {row.setting}: "
             f"{row.ms:.1f} ms, {row.steps_mean:.1f} steps, surface p99 "
             f"{format_number(row.surface_p99)}")

    rows = sweep(scenes, size, repeat, grid, pairs, progress)
    uber, devices = None, {"numpy": "NumPy on the CPU"}
    if any(b == "opencl" for b, _ in pairs):
        from reference_cpu.opencl import device_name
        devices["opencl"] = f"OpenCL device {device_name()}"
    if any(b == "gpu" for b, _ in pairs):
        from gpu_shader.render import device_name
        devices["gpu"] = f"OpenGL renderer {device_name()}"
        from gpu_shader.uber import compare_specialised_uber
        uber = []
        for name, scene in scenes.items():
            try:
                result = compare_specialised_uber(scene, *size, repeat=max(3, repeat))
            except Exception as err:        # noqa: BLE001 - a scene the uber shader lacks
                echo(f"uber shader: {name}: {err}")
                continue
            uber.append({"scene": name, **result})
    return write_report(rows, markdown, image_dir, command, size, repeat, uber, devices)
