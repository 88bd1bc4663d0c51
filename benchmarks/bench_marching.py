"""Each faster-marching setting on every backend, side by side in one run.

    python benchmarks/bench_marching.py [--scene classroom] [--size 640x480]

Renders the scene with plain sphere tracing, automatic over-relaxation, bounding spheres and
both, on gpu, opencl and numpy at each precision. Prints the median and best time per frame
and the mean steps per pixel of each, then the ratios docs/performance.md sets targets for:
opencl against numpy at the same precision, and opencl against gpu. Results and the command are in
docs/performance.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time

import marchlab
from marchlab.cli import parse_size
from marchlab.render import backend_problem

SETTINGS = {
    "plain": {},
    "auto": dict(relaxation="auto"),
    "auto+spheres": dict(relaxation="auto", bounding_spheres=True),
    "plain+spheres": dict(bounding_spheres=True),
}
RUNS = [("gpu", "float32"), ("opencl", "float32"), ("opencl", "float64"),
        ("numpy", "float32"), ("numpy", "float64")]


def timed(scene, width, height, backend, precision, repeat):
    """(median s, best s, frame) of ``repeat`` renders after an untimed (compiling) one."""
    frame = marchlab.render(scene, width, height, backend=backend, precision=precision)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        frame = marchlab.render(scene, width, height, backend=backend, precision=precision)
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), frame


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="classroom")
    parser.add_argument("--size", type=parse_size, default=(640, 480))
    args = parser.parse_args(argv)
    scene = marchlab.load_scene(args.scene)
    runs = [(b, p) for b, p in RUNS if backend_problem(b) is None]
    median = {}
    for name, change in SETTINGS.items():
        configured = dataclasses.replace(scene, render=dataclasses.replace(scene.render, **change))
        for backend, precision in runs:
            repeat = 3 if backend == "numpy" else 7
            mid, best, frame = timed(configured, *args.size, backend, precision, repeat)
            median[name, backend, precision] = mid
            print(f"{name:14s} {backend:6s} {precision}  median {1000 * mid:7.1f} ms  "
                  f"best {1000 * best:7.1f}  steps {frame.steps.mean():.1f}", flush=True)
    for name in SETTINGS:
        for precision in ("float32", "float64"):
            opencl, numpy = median.get((name, "opencl", precision)), median.get((name, "numpy", precision))
            gpu = median.get((name, "gpu", "float32"))
            if opencl and numpy and gpu:
                print(f"{name:14s} {precision}: opencl vs numpy {numpy / opencl:.1f}x, "
                      f"opencl/gpu {opencl / gpu:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
