"""Time every backend and precision on one scene, side by side in one run.

    python benchmarks/bench_render.py [--scene classroom] [--size 640x480] [--repeat 5]

Prints a Markdown table (for docs/performance.md): median and best wall time per frame (for
the gpu backend: draw and read-back of every buffer), CPU time, the speed-up over the NumPy
reference at float64 and at float32, frames per second and mean steps per pixel; once for the
scene as it is and once for primary rays alone (no shadows, reflections or lighting), and the
device each backend ran on. Machines are shared and noisy, so compare ratios from the same
run, not absolute times across runs.
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
from marchlab.render import BACKENDS, backend_problem


def primary_rays_only(scene):
    """The same scene and camera with shading reduced to the primary march (depth shading)."""
    settings = dataclasses.replace(scene.render, shading="depth", shadows="none",
                                   reflection_depth=0)
    return dataclasses.replace(scene, render=settings)


def render_with(backend: str):
    """A function (scene, width, height, precision) -> Frame for a row of the table.

    "opencl one-ray" is the opencl backend's one-ray program (`gpu_shader.opencl.render`
    with packets=False), timed beside the packet program it ships with."""
    if backend == ONE_RAY:
        from gpu_shader import opencl
        return lambda scene, w, h, precision: opencl.render(scene, w, h, precision,
                                                            packets=False)
    return lambda scene, w, h, precision: marchlab.render(scene, w, h, backend=backend,
                                                          precision=precision)


ONE_RAY = "opencl one-ray"


def time_render(scene, width, height, backend, precision, repeat):
    """(median wall s, best wall s, median CPU s, frame) over ``repeat`` renders after a warm-up."""
    render = render_with(backend)
    frame = render(scene, width, height, precision)
    walls, cpus = [], []
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        frame = render(scene, width, height, precision)
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

    backends = []
    for backend in args.backend or list(BACKENDS):
        problem = backend_problem(backend)
        if problem:
            print(f"- {backend}: skipped ({problem})")
        else:
            backends.append(backend)
    print(f"Scene `{args.scene}` at {width}x{height}, {args.repeat} timed renders after one "
          f"warm-up; {cpu_name()}, {os.cpu_count()} cores; Python "
          f"{platform.python_version()}, NumPy {np.__version__}.")
    for backend in backends:
        print(f"- {backend}: {device(backend)}")
    if "opencl" in backends:
        backends.insert(backends.index("opencl") + 1, ONE_RAY)
    print("\n| workload | backend | precision | median ms | best ms | CPU ms | vs numpy float64 "
          "| vs numpy float32 | vs gpu | frames/s | mean steps/px |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    # numpy and gpu go first, so the ratios against them are there for the rows after.
    backends.sort(key=lambda b: {"numpy": 0, "gpu": 1}.get(b, 2))
    for label, variant in (("full scene", scene), ("primary rays", primary_rays_only(scene))):
        times = {}
        for backend in backends:
            precisions = BACKENDS["opencl" if backend == ONE_RAY else backend].precisions
            for precision in sorted(precisions, reverse=True):
                median, best, cpu, frame = time_render(variant, width, height, backend,
                                                       precision, args.repeat)
                if backend in ("numpy", "gpu"):
                    times[backend, precision] = median
                ratios = [f"{times[key] / median:.2f}x" if key in times else "-"
                          for key in (("numpy", "float64"), ("numpy", "float32"),
                                      ("gpu", "float32"))]
                print(f"| {label} | {backend} | {precision} | {median * 1e3:.1f} | "
                      f"{best * 1e3:.1f} | {cpu * 1e3:.0f} | {' | '.join(ratios)} | "
                      f"{1 / median:.1f} | {frame.steps.mean():.1f} |", flush=True)
    return 0


def device(backend: str) -> str:
    """What a backend runs on: the CPU, or the OpenGL renderer."""
    if backend == "gpu":
        from gpu_shader.render import device_name
        return f"OpenGL renderer {device_name()}"
    if backend in ("opencl", ONE_RAY):
        from gpu_shader.opencl import device_name
        return f"OpenCL device {device_name()}"
    return cpu_name()


if __name__ == "__main__":
    sys.exit(main())
