"""What anti-aliasing costs on every backend: time per frame with 1, 2 x 2 and 3 x 3 samples
a pixel (``render.samples``), side by side in one run.

    python benchmarks/bench_samples.py [--scene classroom] [--size 320x240] [--repeat 3]
                                       [--samples 1,2,3] [--pattern rotated]

One Markdown table, for docs/performance.md: per backend, the median wall time per frame at
each sample count and its ratio to one sample, with the primary rays a pixel shoots
(`scene_model.sampling.rays_per_pixel`: n^2, plus the centre for even n) in the header, and
the mean SDF evaluations of a pixel's primary rays (the steps buffer, counted by the NumPy
reference in float32). The sample counts alternate within each round, so a busy moment of
this shared machine hits all of them.
"""

from __future__ import annotations

import argparse
import dataclasses

import marchlab
from bench_prepass import alternating_times   # the same alternating timing
from marchlab.cli import parse_size
from marchlab.render import backend_problem
from scene_model.sampling import rays_per_pixel
from scene_model.scene import rendered_scene
from scene_model.scenefile import load_scene

TIMED = {"numpy float64": "float64", "numpy float32": "float32", "gpu": "float32",
         "opencl float32": "float32", "opencl float64": "float64"}


def with_samples(scene, n: int, pattern: str):
    return dataclasses.replace(scene, render=dataclasses.replace(
        scene.render, samples=n, sample_pattern=pattern))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="classroom")
    parser.add_argument("--size", default="320x240", type=parse_size)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--samples", default="1,2,3")
    parser.add_argument("--pattern", default="rotated", choices=["regular", "rotated"])
    parser.add_argument("--backends", default=",".join(TIMED))
    args = parser.parse_args()
    width, height = args.size
    counts = [int(n) for n in args.samples.split(",")]
    scene = rendered_scene(load_scene(args.scene))
    variants = [with_samples(scene, n, args.pattern) for n in counts]
    backends = [b for b in args.backends.split(",")
                if backend_problem(b.split()[0]) is None]
    steps = [marchlab.render(v, width, height, backend="numpy", precision="float32").steps.mean()
             for v in variants]
    print(f"Scene `{args.scene}` at {width}x{height}, {args.pattern} grid; ms per frame "
          f"(median of {args.repeat}; ratio to one sample):\n")
    rays = [rays_per_pixel(n) for n in counts]
    print("| backend | " + " | ".join(f"{n}x{n} ({r} ray{'s' * (r > 1)})"
                                     for n, r in zip(counts, rays)) + " |")
    print("|---|" + "---|" * len(counts))
    print("| primary steps a pixel | " + " | ".join(f"{s:.1f}" for s in steps) + " |")
    for label in backends:
        median = alternating_times(variants, width, height, label.split()[0], TIMED[label],
                                   args.repeat)
        print(f"| {label} | " + " | ".join(f"{1000 * t:.1f} ({t / median[0]:.2f}x)"
                                           for t in median) + " |")
    if "gpu" in backends:
        from gpu_shader.render import device_name
        print(f"\ngpu: {device_name()}")


if __name__ == "__main__":
    main()
