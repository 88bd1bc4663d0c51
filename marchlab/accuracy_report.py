"""The speed-against-error report: tables, Pareto plots and docs/speed-vs-error.md.

Turns the rows of a sweep (`marchlab.accuracy`) and the truths they were measured against
(`marchlab.accuracy_truth`) into the Markdown page that ``marchlab bench accuracy`` writes
(into out/; ``make speed-vs-error`` writes the documentation's copy), with one
time-against-error plot per scene in `PLOTTED`. `plan_run` says what a run will do and its
work at worst, before it starts; `run` does the whole command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scene_model.scene import Scene

from .accuracy import (TOLERANCES, Row, backends_present, embree_problem, numpy_rows, pareto,
                       recommend, settings_grid, sweep, sweep_ray_steps, sweep_scenes)
from .accuracy_truth import TRUTH_RESOLUTION, SceneTruth, p99, scene_truth, statistic, truth_method
from .budget import MAX_BENCH_RAY_STEPS, check
from .outputs import make_folders

# The scenes whose time-against-error plot the report shows (docs/images is committed).
PLOTTED = ("classroom", "boxes", "csg")

# --- The report -------------------------------------------------------------------------------

MARK = "†"            # an error the truth cannot tell from 0 (`within_truth`)

COLUMNS = [("scene", "scene"), ("backend", "backend"), ("precision", "precision"),
           ("setting", "setting"), ("truth", "truth (its own \\|Δt\\| p99, normal p99)"),
           ("ms", "ms/frame"), ("steps_mean", "steps mean"), ("steps_p99", "steps p99"),
           ("depth_mean", "\\|Δt\\| mean"), ("depth_p99", "\\|Δt\\| p99"),
           ("depth_max", "\\|Δt\\| max"), ("surface_mean", "surface mean"),
           ("surface_p99", "surface p99"), ("surface_max", "surface max"),
           ("misclassified", "hit/miss wrong"), ("off_band", "off silhouette band"),
           ("normal_p99_deg", "normal p99 °"), ("normal_max_deg", "normal max °"),
           ("color_p99", "colour p99 \\|Δ\\|"), ("color_max", "colour max \\|Δ\\|")]
TEXT_COLUMNS = 5


def format_number(x: float) -> str:
    if x == 0:
        return "0"
    if not math.isfinite(x):
        return str(x)
    return f"{x:.3g}" if 1e-3 <= abs(x) < 1e4 else f"{x:.1e}"


def format_cell(value) -> str:
    return value if isinstance(value, str) else (str(value) if isinstance(value, int)
                                                 else format_number(value))


def truth_cell(reference: SceneTruth | None, label: str) -> str:
    """The truth column: its method, and for Embree its own depth and normal error."""
    if reference is None or reference.method == "analytic":
        return label
    own = reference.errors()
    return (f"{label} ({format_number(own['depth_p99'])}, "
            f"{format_number(own['normal_p99_deg'])}°)")


def table(rows: list[Row], truths: dict | None = None) -> str:
    """The rows as one Markdown table; errors the truth cannot tell from 0 are marked `MARK`."""
    truths = truths or {}
    head = "| " + " | ".join(title for _, title in COLUMNS) + " |\n"
    head += "| " + " | ".join("---" if i < TEXT_COLUMNS else "---:"
                              for i in range(len(COLUMNS))) + " |\n"
    lines, truth_cells = [], {}
    for r in rows:
        cells = []
        for key, _ in COLUMNS:
            if key == "truth":
                if (r.scene, r.truth) not in truth_cells:
                    truth_cells[r.scene, r.truth] = truth_cell(truths.get(r.scene), r.truth)
                cells.append(truth_cells[r.scene, r.truth])
            else:
                cells.append(format_cell(getattr(r, key))
                             + (MARK if key in r.within_truth else ""))
        lines.append("| " + " | ".join(cells) + " |")
    return head + "\n".join(lines) + "\n"


def truth_table(truths: dict[str, SceneTruth]) -> str:
    """One line per scene: the truth's method, stated bound, measured and own errors, time."""
    lines = ["| scene | truth | grid | stated bound (mesh + tessellation + rounding) | "
             "measured \\|sdf\\| mean, p99, max | own \\|Δt\\| mean, p99, max | "
             "own normal p99, max ° | facet normal p99 ° | silhouette band px | build s |",
             "| --- | --- | ---: | --- | --- | --- | --- | ---: | ---: | ---: |"]
    for name, ref in truths.items():
        t, own = ref.truth, ref.errors()
        measured = ref.surface_error[t.hit]
        if ref.method == "analytic":
            bound = f"{format_number(t.error_bound)} (rounding)"
        else:
            terms = " + ".join(format_number(t.error_terms.get(k, 0.0))
                               for k in ("mesh", "tessellation", "rounding"))
            bound = f"{format_number(t.error_bound)} = {terms}"
        facet = ("–" if ref.facet_error_deg is None
                 else format_number(statistic(ref.facet_error_deg[t.hit], p99)))
        lines.append(
            f"| {name} | {ref.method} | {ref.resolution or '–'} | {bound} | "
            f"{format_number(statistic(measured, np.mean))}, {format_number(statistic(measured, p99))}, "
            f"{format_number(statistic(measured, np.max))} | "
            f"{format_number(own['depth_mean'])}, {format_number(own['depth_p99'])}, "
            f"{format_number(own['depth_max'])} | {format_number(own['normal_p99_deg'])}, "
            f"{format_number(own['normal_max_deg'])} | {facet} | {1 + ref.band_px} | "
            f"{ref.seconds:.1f} |")
    return "\n".join(lines) + "\n"


# The settings of the faster-marching table, each against plain sphere tracing.
FASTER = ("auto", "auto + spheres", "cone", "cone + auto")


def fewer_steps_table(rows: list[Row], truths: dict | None = None) -> str:
    """The faster-marching goal per scene, NumPy float64 at epsilon 1e-3: steps saved by each
    of `FASTER` (auto relaxation, auto + bounding spheres, the cone pre-pass, and the cone
    pre-pass with auto relaxation; a pre-pass's own evaluations count as steps) against
    plain sphere tracing, the pixels whose hit/miss changed (and how many are wrong against
    the truth), and the surface error."""
    truths = truths or {}
    settings = ["plain, eps 0.001"] + [f"{name}, eps 0.001" for name in FASTER]
    names = ", ".join(FASTER)
    lines = ["| scene | truth | plain: steps mean | "
             + " | ".join(f"{name}: saved" for name in FASTER)
             + f" | hit/miss changed ({names}) | hit/miss wrong (plain, {names}) | "
             f"surface max (plain, {names}) |",
             "| --- | --- | ---: | " + "---: | " * len(FASTER) + "---: | ---: | ---: |"]
    for scene in dict.fromkeys(r.scene for r in rows):
        get = numpy_rows(rows, scene)
        if settings[0] not in get:
            continue
        plain = get[settings[0]]
        mine = [get.get(s) for s in settings]
        saved = ["–" if r is None else f"{100 * (1 - r.steps_mean / plain.steps_mean):.1f}%"
                 for r in mine[1:]]
        changed = ", ".join("–" if r is None or r.hit_changed is None else str(r.hit_changed)
                            for r in mine[1:])
        wrong = ", ".join("–" if r is None else str(r.misclassified) for r in mine)
        surface = ", ".join("–" if r is None else format_number(r.surface_max) for r in mine)
        label = truths[scene].label() if scene in truths else plain.truth
        lines.append(f"| {scene} | {label} | {plain.steps_mean:.1f} | " + " | ".join(saved)
                     + f" | {changed} | {wrong} | {surface} |")
    return "\n".join(lines) + "\n"


def plot(rows: list[Row], scene: str, path) -> None:
    """Time against p99 surface distance for one scene, one colour per backend, the
    Pareto frontier of each backend drawn as a line, as a PNG to ``path`` (a file name or a
    binary file object)."""
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
    fig.savefig(path, format="png")
    plt.close(fig)


HOW_TO_READ = [
    "- **truth**: what the row is measured against. `analytic` is exact (float64 ray "
    "intersections, error about 1e-15). `embree N` meshes the scene (marching cubes, N cells "
    "across each part; icospheres for spheres; boxes and planes exact) and ray-casts the "
    "meshes in float32, so the truth itself is off; the brackets give its own error at the "
    "99th percentile, as a depth and as a normal angle (see *The truth of each scene*).",
    f"- **{MARK}** marks an error the truth cannot tell from 0. At a pixel the true surface "
    "lies within the truth's own error of the truth's hit (see below); a renderer whose "
    "error there is no larger may be exactly right. A p99 is marked when at least 99% of "
    "the pixels are so, a mean or max when all are; normals likewise. A marked error is "
    "never held against a setting. (The Embree truth's hits lie mostly inside the surface, "
    "on the far side from where sphere tracing stops, so a mark needs a renderer much "
    "finer than the truth.)",
    "- **|Δt|**: depth against the truth's where both hit. On grazing floors a ray may stop "
    "anywhere in the epsilon shell, up to epsilon/|cos θ| short of the surface, so this "
    "grows at the horizon; |Δt| max is set by pixels on depth edges.",
    "- **surface**: the hit point's distance to the true surface, |sdf| of the float64 SDF at "
    "the renderer's own hit point. It needs no truth, so it means the same on every scene "
    "(exact for spheres, boxes and planes, a lower bound where a subtraction or a smooth "
    "blend makes the SDF only a bound). Sphere tracing promises less than epsilon; this is "
    "the error the Pareto frontier and the recommendations use.",
    "- **hit/miss wrong**: pixels classified differently from the truth; **off silhouette "
    "band**: those more than one pixel from the truth's silhouettes (a ray within epsilon of "
    "an edge may hit or miss), the band widened for an Embree truth by its stated bound in "
    "pixels at its nearest silhouette (*silhouette band px* below). A count marked "
    f"{MARK} has misclassified pixels that only this widening excuses.",
    "- **normal**: angle to the true normal. For an Embree truth that is not the mesh's "
    "facet normal, which tilts by a degree or more (*facet normal p99* below), but the "
    "float64 SDF's gradient at the truth's hit point.",
    "- **colour**: against a NumPy float64 render with epsilon 1e-6 and 4096 steps (colour "
    "has no truth). Colour max is set by checker and shadow edges, which move with the hit "
    "point; p99 is the typical error.",
]

TRUTH_NOTES = [
    "The truth's own errors, per scene (world units; angles in degrees). The **stated bound** "
    "is what `reference_cpu.truth` promises for every hit point: half a marching-cubes cell "
    "diagonal, plus the icospheres' computed distance from their spheres, plus float32 "
    "rounding (docs/ground-truth.md). It is loose: on smooth surfaces marching cubes misses "
    "by about the cell squared, not half the cell, so the errors are also **measured**: |sdf| "
    "of the float64 SDF at the truth's hit points. The truth's **own |Δt|** at a pixel is the "
    "length of one Newton step along the ray from its hit p to the SDF's zero, "
    "|sdf(p)| / |∇sdf(p) · d|, first order in the surface's curvature (large where the ray "
    "grazes the surface, and on the creases marching cubes bevels); its **own normal** error "
    "is the angle the SDF's gradient turns through over that step. These per-pixel errors "
    f"are what the {MARK} marks compare with. Traced by Embree, `classroom` and `boxes` "
    "show that the estimate is the actual error against their analytic truth, to within "
    "1% (tests/test_accuracy.py). The **silhouette band** is 1 px plus the stated bound in "
    f"pixels at the nearest silhouette, rounded up. A `repeat` is traced as the union of its "
    "copies, an infinite one out to `max_distance` (the same surface, as each copy lies "
    "inside its cell; Embree cannot mesh an endless row, and one marching-cubes grid over "
    f"a whole row would be coarse). The default grid, {TRUTH_RESOLUTION} cells across each "
    "meshed part, keeps the measured p99 and the own |Δt| p99 under 1e-3, the middle "
    "epsilon swept, for seconds of building (*build s*).",
]


def write_report(rows: list[Row], markdown, image_dir, command: str, size, repeat,
                 uber: list[dict] | None = None, devices: dict | None = None,
                 truths: dict | None = None, skipped: dict | None = None) -> list:
    """Write the Markdown report and the plots of the `PLOTTED` scenes; return the paths
    written.

    ``truths`` holds each scene's `SceneTruth` (by name), ``skipped`` the scenes left out and
    why. Everything is rendered into memory first and written at the end, all files together
    (`scene_model.files.write_together`), so an interrupted run leaves the previous report
    and plots whole.
    """
    import io
    from pathlib import Path
    from scene_model.files import write_together
    markdown, image_dir = Path(markdown), Path(image_dir)
    truths = truths or {}
    scenes = list(dict.fromkeys(r.scene for r in rows))
    method = {s: (truths[s].label() if s in truths else
                  next(r.truth for r in rows if r.scene == s)) for s in scenes}
    best = recommend(rows)
    out = ["# Speed against error", "",
           "Generated by the command below; do not edit by hand (`make speed-vs-error` "
           "regenerates the documentation's copy; `marchlab bench accuracy` alone writes into "
           "out/). Every figure comes from one run on one machine, so the times are comparable "
           "with each other (not with other runs on this shared machine).", "", "```sh",
           command, "```", "",
           f"Image size {size[0]}x{size[1]}, median of {repeat} timed frames after one "
           "untimed (compiling) frame. Scenes, with the truth each is measured against "
           "(`reference_cpu/truth/ground_truth.py`): "
           + ", ".join(f"`{s}` ({method[s]})" for s in scenes) + "."]
    if skipped:
        out += ["", "Left out: " + "; ".join(f"`{s}` ({why})" for s, why in skipped.items())
                + "."]
    if devices:
        out += ["", "Devices: " + "; ".join(f"{k}: {v}" for k, v in devices.items()) + "."]
    marked = sum(1 for r in rows if r.within_truth)
    out += ["", "## How to read it", "", *HOW_TO_READ, "",
            f"In this run {marked} of {len(rows)} rows have an error marked {MARK}."]
    if truths:
        out += ["", "## The truth of each scene", "", *TRUTH_NOTES, "", truth_table(truths)]
    out += ["## Fewer steps, same surface", "",
            "Mean SDF evaluations per pixel saved against plain sphere tracing at epsilon "
            "1e-3 (NumPy float64; the goal is at least 25% with the hit mask unchanged and "
            "the surface within epsilon). *hit/miss changed* counts the pixels whose hit/miss "
            "differs from plain sphere tracing's, *hit/miss wrong* those that differ from the "
            "truth's (a change that puts right a pixel plain sphere tracing got wrong shows "
            "in both); the surface error needs no truth:", "",
            fewer_steps_table(rows, truths),
            "The same settings on every backend, against the truth:", "",
            table([r for r in rows if r.setting in ["plain, eps 0.001"] + [
                f"{name}, eps 0.001" for name in FASTER]], truths),
            "## Recommended settings", "",
            "Per backend, the fastest setting (time summed over the scenes) whose p99 surface "
            f"distance is at most {TOLERANCES['surface_p99']:g}, with no misclassified pixel "
            f"off the silhouette band and p99 normal error at most "
            f"{TOLERANCES['normal_p99_deg']:g}° (or within the truth's own) on every scene:",
            "", "| backend | precision | recommended |", "| --- | --- | --- |"]
    for (backend, precision), setting in best.items():
        out.append(f"| {backend} | {precision} | {setting or 'none within tolerance'} |")
    if uber:
        out += ["", "## A specialised shader against an uber shader", "",
                "The gpu backend generates a shader holding only what the scene uses. The "
                "uber shader (`gpu_shader/uber.py`) is one text for every scene: all "
                "primitives, lights, shading modes and features, chosen at run time by "
                "values in the parameter block. "
                "Same images (tests/gpu/test_uber_shader.py); times side by side:", "",
                "| scene | specialised ms | uber ms | uber / specialised | compile ms "
                "(specialised, uber) |", "| --- | ---: | ---: | ---: | ---: |"]
        for u in uber:
            out.append(f"| {u['scene']} | {u['specialised_ms']:.1f} | {u['uber_ms']:.1f} | "
                       f"{u['ratio']:.2f}x | {u['specialised_compile_ms']:.0f}, "
                       f"{u['uber_compile_ms']:.0f} |")
    images = {}
    for scene in scenes:
        front = pareto([r for r in rows if r.scene == scene])
        out += ["", f"## `{scene}`", ""]
        if scene in PLOTTED:
            images[scene] = image_dir / f"speed-vs-error-{scene}.png"
            relative = Path("images") / images[scene].name
            out += [f"![Speed against error, {scene}]({relative})", ""]
        out += ["Pareto frontier over all backends (no other configuration is both faster "
                "and more accurate):", "", table(front, truths)]
    out += ["## Every configuration", "", table(rows, truths)]
    payloads = {}
    for scene, path in images.items():
        buffer = io.BytesIO()
        plot(rows, scene, buffer)
        payloads[path] = buffer.getvalue()
    payloads[markdown] = ("\n".join(out) + "\n").encode()
    make_folders(*payloads)
    write_together(payloads)
    return list(payloads)


@dataclass
class RunPlan:
    """What `run` will do, known before it starts: its scenes (those the truth can be built
    for here), settings, backends and the Embree grid; the scenes left out and why; and its
    work at worst (`marchlab.accuracy.sweep_ray_steps`)."""
    scenes: dict[str, Scene]
    grid: dict[str, dict]
    pairs: list[tuple[str, str]]
    resolution: int
    skipped: dict[str, str]
    ray_steps: int

    @property
    def configurations(self) -> int:
        """Rows of the report: scenes x settings x backends."""
        return len(self.scenes) * len(self.grid) * len(self.pairs)


def plan_run(size=(160, 120), repeat=3, quick=False) -> RunPlan:
    """The `RunPlan` of ``run(size=size, repeat=repeat, quick=quick)`` on this machine."""
    scenes = sweep_scenes()
    grid = settings_grid()
    resolution = TRUTH_RESOLUTION
    if quick:                       # a smoke run: two settings, one scene of each truth
        scenes = {k: scenes[k] for k in ("classroom", "csg")}
        grid = {k: grid[k] for k in ("plain, eps 0.001", "auto, eps 0.001")}
        resolution = 32
    problem = embree_problem()
    skipped = {} if problem is None else {k: problem for k, s in scenes.items()
                                           if truth_method(s) == "embree"}
    scenes = {k: s for k, s in scenes.items() if k not in skipped}
    pairs = backends_present()
    return RunPlan(scenes, grid, pairs, resolution, skipped,
                   sweep_ray_steps(scenes, grid, pairs, size, repeat))


def run(markdown="out/speed-vs-error.md", image_dir="out/images", size=(160, 120), repeat=3,
        command="marchlab bench accuracy", quick=False, echo=print, progress=None,
        allow_large=False, plan: RunPlan | None = None) -> list:
    """The whole report: build each scene's truth, sweep, compare the uber shader if the gpu
    backend runs, write.

    ``echo`` gets a line for each truth built and for the scenes left out; ``progress`` is
    called as ``progress(rows done, rows)`` after each configuration. The run is refused
    beyond `marchlab.budget.MAX_BENCH_RAY_STEPS` unless ``allow_large``. ``plan`` is
    `plan_run`'s for the same arguments, if the caller has it already.
    """
    plan = plan or plan_run(size, repeat, quick)
    check(plan.ray_steps, MAX_BENCH_RAY_STEPS, f"the benchmark at {size[0]}x{size[1]}",
          "ray steps at worst", allow_large)
    scenes, grid, pairs, resolution, skipped = (plan.scenes, plan.grid, plan.pairs,
                                                plan.resolution, plan.skipped)
    if skipped:
        echo(f"left out {', '.join(skipped)}: {next(iter(skipped.values()))}")
    truths: dict[str, SceneTruth] = {}
    for name, scene in scenes.items():
        truths[name] = scene_truth(scene, *size, resolution=resolution)
        own = truths[name].errors()
        echo(f"truth of {name}: {truths[name].label()} in {truths[name].seconds:.1f} s, its own "
             f"|Δt| p99 {format_number(own['depth_p99'])}, normal p99 "
             f"{format_number(own['normal_p99_deg'])}°")
    done = []

    def row_done(row):
        done.append(row)
        if progress is not None:
            progress(len(done), plan.configurations)

    rows = sweep(scenes, size, repeat, grid, pairs, row_done, truths, resolution,
                 allow_large=True)                                  # checked above
    uber, devices = None, {"numpy": "NumPy on the CPU"}
    if any(b == "opencl" for b, _ in pairs):
        from gpu_shader.opencl import device_name
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
    return write_report(rows, markdown, image_dir, command, size, repeat, uber, devices,
                        truths, skipped)
