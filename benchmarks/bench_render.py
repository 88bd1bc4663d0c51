"""Time every backend and precision on one scene, side by side in one run.

    python benchmarks/bench_render.py [--scene classroom] [--size 640x480] [--repeat 5]

Prints a Markdown table (for docs/performance.md): median and best wall time per frame, CPU
time, the ratio to the NumPy float64 reference, and mean steps per pixel; once for the scene as
it is and once for primary rays alone (no shadows, reflections or lighting). Machines are shared
and noisy, so compare ratios from the same run, not absolute times across runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import statistics
import sys
import time

import numpy as np

import marchlab
from marchlab.cli import parse_size
from marchlab.render import PRECISIONS


def primary_rays_only(scene):
    """The same scene and camera with shading reduced to the primary march (depth shading)."""
    settings = dataclasses.replace(scene.render, shading="depth", shadows="none",
                                   reflection_depth=0)
    return dataclasses.replace(scene, render=settings)


def time_render(scene, width, height, backend, precision, repeat):
    """(median wall s, best wall s, median CPU s, frame) over ``repeat`` renders after a warm-up."""
    frame = marchlab.render(scene, width, height, backend=backend, precision=precision)
    walls, cpus = [], []
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        frame = marchlab.render(scene, width, height, backend=backend, precision=precision)
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), min(walls), statistics.median(cpus), frame


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="classroom")
    parser.add_argument("--size", type=parse_size, default=(640, 480))
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--backend", action="append", choices=list(marchlab.BACKENDS),
                        help="backends to time (default: all)")
    args = parser.parse_args(argv)
    width, height = args.size
    scene = marchlab.load_scene(args.scene)

    print(f"Scene `{args.scene}` at {width}x{height}, {args.repeat} timed renders after one "
          f"warm-up; {cpu_name()}, {os.cpu_count()} cores; Python "
          f"{platform.python_version()}, NumPy {np.__version__}.\n")
    print("| workload | backend | precision | median ms | best ms | CPU ms | vs numpy float64 "
          "| mean steps/px |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for label, variant in (("full scene", scene), ("primary rays", primary_rays_only(scene))):
        reference = None
        for backend in args.backend or list(marchlab.BACKENDS):
            for precision in reversed(PRECISIONS):
                median, best, cpu, frame = time_render(variant, width, height, backend,
                                                       precision, args.repeat)
                reference = reference or median
                print(f"| {label} | {backend} | {precision} | {median * 1e3:.0f} | "
                      f"{best * 1e3:.0f} | {cpu * 1e3:.0f} | {reference / median:.2f}x | "
                      f"{frame.steps.mean():.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
