"""The cone-marching pre-pass on every backend: SDF evaluations per pixel with and without it
on every bundled scene, and each backend's time per frame, side by side in one run.

    python benchmarks/bench_prepass.py [--size 640x480] [--repeat 5] [--backends gpu,opencl]

Two Markdown tables, for docs/performance.md:

1. per scene, the mean primary-ray steps per pixel marching from the eye, then with the
   pre-pass (``render.prepass = "cone"``, 8-pixel tiles): its primary steps, the pre-pass's
   own evaluations per pixel (each tile's cone steps over its pixels), their sum as a
   fraction of the plain march, and the pixels whose hit or object differs (grazes and rays
   that ran out of steps: docs/sphere-tracing.md). Counted by the NumPy reference in
   float32, whose counts the OpenCL program's equal (tests/equivalence); exact and the same
   from run to run. The same again with relaxed steps (``relaxation = "auto"``) on top.
2. per scene and backend, the median wall time per frame (the gpu backend: both draws and
   the read-back of every buffer) without and with the pre-pass, and their ratio. Plain and
   pre-pass frames alternate, so a busy moment of this shared machine hits both.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import statistics
import time

import numpy as np

import marchlab
from marchlab.accuracy import prepass_share
from marchlab.cli import parse_size
from marchlab.render import backend_problem
from scene_model.scene import rendered_scene
from scene_model.scenefile import bundled_scene_names, load_scene

TIMED = {"gpu": "float32", "opencl float32": "float32", "opencl float64": "float64"}


def with_settings(scene, **changes):
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **changes))


def steps_row(name, scene, width, height) -> str:
    plain = marchlab.render(scene, width, height, backend="numpy", precision="float32")
    cells = [f"{plain.steps.mean():.1f}"]
    for changes in ({"prepass": "cone"}, {"prepass": "cone", "relaxation": "auto"}):
        variant = with_settings(scene, **changes)
        frame = marchlab.render(variant, width, height, backend="numpy", precision="float32")
        share = prepass_share(variant, width, height, "float32").mean()
        total = frame.steps.mean() + share
        differing = np.count_nonzero((plain.hit != frame.hit)
                                     | (plain.object_id != frame.object_id))
        cells.append(f"{frame.steps.mean():.1f} + {share:.2f} = "
                     f"**{total / plain.steps.mean():.2f}**; {differing}")
    return f"| {name} | " + " | ".join(cells) + " |"


def times(scene, width, height, backend, precision, repeat):
    """Median seconds per frame without and with the pre-pass, alternating."""
    variants = [scene, with_settings(scene, prepass="cone")]
    return alternating_times(variants, width, height, backend, precision, repeat)


def alternating_times(variants, width, height, backend, precision, repeat):
    """Median seconds per frame of each scene of ``variants``, rendered in turn ``repeat``
    times after one warm-up frame each (which compiles their programs)."""
    return alternating_medians(
        [functools.partial(marchlab.render, variant, width, height, backend=backend,
                           precision=precision) for variant in variants], repeat)


def alternating_medians(draws, repeat):
    """Median seconds of each call of ``draws`` (callables without arguments), called in
    turn ``repeat`` times after one warm-up call each, so that a busy moment of a shared
    machine hits all of them."""
    seconds = [[] for _ in draws]
    for draw in draws:
        draw()
    for _ in range(repeat):
        for i, draw in enumerate(draws):
            start = time.perf_counter()
            draw()
            seconds[i].append(time.perf_counter() - start)
    return [statistics.median(s) for s in seconds]


def timing_rows(variants, width, height, timed, labels, repeat) -> list[str]:
    """A Markdown row per backend label of ``labels`` ("gpu", "numpy float32", ...; ``timed``
    gives each its precision): the median ms per frame of each of ``variants``
    (`alternating_times`) and its ratio to the first's."""
    rows = []
    for label in labels:
        median = alternating_times(variants, width, height, label.split()[0], timed[label],
                                   repeat)
        rows.append(f"| {label} | " + " | ".join(f"{1000 * t:.1f} ({t / median[0]:.2f}x)"
                                                 for t in median) + " |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480", type=parse_size)
    parser.add_argument("--steps-size", default="320x240", type=parse_size,
                        help="image size of the step counts (the NumPy reference)")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--backends", default=",".join(TIMED))
    args = parser.parse_args()
    names = bundled_scene_names(meshes=False)
    width, height = args.steps_size
    print(f"Steps per pixel at {width}x{height} (NumPy float32; primary + pre-pass = "
          "fraction of plain; pixels whose hit or object differs):\n")
    print("| scene | plain | cone | cone + auto relaxation |")
    print("|---|---|---|---|")
    for name in names:
        print(steps_row(name, rendered_scene(load_scene(name)), width, height))
    width, height = args.size
    backends = [b for b in args.backends.split(",")          # --backends "": counts only
                if b and backend_problem(b.split()[0]) is None]
    if not backends:
        return
    print(f"\nTime per frame at {width}x{height}, ms (median of {args.repeat}; plain / cone "
          "= ratio):\n")
    print("| scene | " + " | ".join(backends) + " |")
    print("|---|" + "---|" * len(backends))
    for name in names:
        scene = rendered_scene(load_scene(name))
        cells = []
        for label in backends:
            plain, cone = times(scene, width, height, label.split()[0], TIMED[label],
                                args.repeat)
            cells.append(f"{1000 * plain:.1f} / {1000 * cone:.1f} = {cone / plain:.2f}")
        print(f"| {name} | " + " | ".join(cells) + " |")
    if "gpu" in backends:
        from gpu_shader.render import device_name
        print(f"\ngpu: {device_name()}")


if __name__ == "__main__":
    main()
