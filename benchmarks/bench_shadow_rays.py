"""Hard shadow rays that leave out their own convex object (``render.shadow_skip_own``): SDF
evaluations per shadow ray without and with it on every bundled SDF scene with hard shadows,
and each backend's time per frame, side by side in one run.

    python benchmarks/bench_shadow_rays.py [--size 640x480] [--repeat 7] [--backends gpu,opencl]

Two Markdown tables, for docs/performance.md:

1. per scene, the shadow rays the NumPy reference casts at 320x240 in float32 (one per lit
   point and light it faces, mirror bounces included), the mean SDF evaluations per ray
   marching every object and leaving out the ray's own convex object, their ratio, and the
   pixels whose colour or path label (which lights a hard shadow blocked) differs. The
   counts are exact and the same from run to run: every shadow march of the reference goes
   through `reference_cpu.shadows.march`, which this script wraps to add up its steps.
2. per scene and backend, the median wall time per frame (the gpu backend: its draws and the
   read-back of every buffer) without and with it, and their ratio. The two settings
   alternate, so a busy moment of this shared machine hits both. Every frame uses the cone
   pre-pass, the fastest setting of docs/performance.md.
"""

from __future__ import annotations

import argparse

import numpy as np

import marchlab
import reference_cpu.shadows
from bench_prepass import alternating_times, with_settings
from marchlab.cli import parse_size
from marchlab.render import backend_problem
from scene_model.scene import rendered_scene
from scene_model.scenefile import bundled_scene_names, load_scene

TIMED = {"gpu": "float32", "opencl float32": "float32", "opencl float64": "float64"}
COUNT_SIZE = (320, 240)


class StepCounter:
    """Wraps `reference_cpu.shadows.march`, adding up the rays and steps of shadow marches."""

    def __init__(self):
        self.rays = self.steps = 0
        self.march = reference_cpu.shadows.march

    def __call__(self, origins, *args, **kwargs):
        t, steps, hit = self.march(origins, *args, **kwargs)
        self.rays += len(steps)
        self.steps += int(steps.sum())
        return t, steps, hit

    def __enter__(self):
        reference_cpu.shadows.march = self
        return self

    def __exit__(self, *exc):
        reference_cpu.shadows.march = self.march


def steps_row(name, scene) -> str:
    counts, frames = [], []
    for skip in (False, True):
        with StepCounter() as counter:
            frames.append(marchlab.render(with_settings(scene, shadow_skip_own=skip),
                                          *COUNT_SIZE, backend="numpy", precision="float32",
                                          path_labels=True))
        counts.append(counter)
    plain, skipping = frames
    differing = np.count_nonzero(np.any(plain.color != skipping.color, axis=-1)
                                 | (plain.path != skipping.path))
    before, after = (c.steps / max(c.rays, 1) for c in counts)
    return (f"| {name} | {counts[0].rays:,} | {before:.2f} | {after:.2f} | "
            f"**{after / before:.2f}** | {differing} |")


def times(scene, width, height, backend, precision, repeat):
    """Median seconds per frame without and with the setting, alternating."""
    variants = [with_settings(scene, shadow_skip_own=skip) for skip in (False, True)]
    return alternating_times(variants, width, height, backend, precision, repeat)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=parse_size, default=(640, 480))
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--backends", default="gpu,opencl")
    args = parser.parse_args()
    names = [n for n in bundled_scene_names(meshes=False)
             if load_scene(n).render.shadows == "hard" and load_scene(n).lights]
    scenes = {n: with_settings(rendered_scene(load_scene(n)), prepass="cone") for n in names}

    print(f"Shadow rays at {COUNT_SIZE[0]}x{COUNT_SIZE[1]} (NumPy float32; SDF evaluations "
          "per ray):\n")
    print("| scene | shadow rays | every object | own object left out | ratio "
          "| pixels that differ |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, scene in scenes.items():
        print(steps_row(name, scene))

    wanted = args.backends.split(",")
    columns = [c for c in TIMED if c.split()[0] in wanted
               and backend_problem(c.split()[0]) is None]
    width, height = args.size
    print(f"\nTime per frame at {width}x{height}, ms (median of {args.repeat}; "
          "every object / own object left out = ratio):\n")
    print("| scene | " + " | ".join(columns) + " |")
    print("|---|" + "---|" * len(columns))
    for name, scene in scenes.items():
        cells = []
        for column in columns:
            before, after = times(scene, width, height, column.split()[0], TIMED[column],
                                  args.repeat)
            cells.append(f"{1000 * before:.1f} / {1000 * after:.1f} = {after / before:.2f}")
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
