"""The NumPy rasteriser one triangle at a time (the textbook loops) against many at once
(the batched paths), on the bundled museum scene, stage by stage.

    python benchmarks/bench_numpy_raster.py [--scene museum] [--size 640x480] [--repeat 3]

Both draw the same frame through the numpy-raster backend's pipeline
(`reference_cpu.raster_render.draw`): the first hits (`rasterise`), each light's shadow
volumes (`stencil_counts`), the mirror (`planar_reflection`, which rasterises again) and the
transparent fragments (`transparent_fragments`), then the shading and path labels that are
not timed apart ("the rest"). The textbook run swaps the batched functions for the loops
(`rasterise_one_by_one`, `stencil_counts_one_by_one`, `transparent_fragments_one_by_one`)
for its duration, and the two frames are compared bit for bit.

Seconds are medians of ``--repeat`` frames after one warm-up (the textbook path: one frame,
no warm-up, unless ``--repeat-textbook`` says more). Machines are shared and noisy: compare
the two columns of one run.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import sys
import time
from dataclasses import replace
from unittest import mock

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import reference_cpu.rasterise as rasterise_module  # noqa: E402
import reference_cpu.shadow_volumes as shadow_module  # noqa: E402
import reference_cpu.transparency as transparency_module  # noqa: E402
from marchlab import load_scene  # noqa: E402
from marchlab.cli import parse_size  # noqa: E402
from reference_cpu.raster_render import NUMPY_RASTER, draw  # noqa: E402

STAGES = ("first_hits", "visibility", "reflection", "transparency")
LABELS = {"first_hits": "rasterise (first hits)", "visibility": "shadow volumes (all lights)",
          "reflection": "mirror (rasterise + shade)",
          "transparency": "transparency (fragments + blend)"}


@contextlib.contextmanager
def textbook_paths():
    """Every batched function replaced by its one-triangle-at-a-time twin."""
    with mock.patch.object(rasterise_module, "rasterise_batched",
                           rasterise_module.rasterise_one_by_one), \
         mock.patch.object(shadow_module, "stencil_counts_batched",
                           shadow_module.stencil_counts_one_by_one), \
         mock.patch.object(transparency_module, "transparent_fragments_batched",
                           transparency_module.transparent_fragments_one_by_one):
        yield


def timed_frame(scene, width, height):
    """One frame through `draw`, and the seconds spent in each stage of ``STAGES`` and in
    all (``"total"``)."""
    seconds = dict.fromkeys(STAGES, 0.0)

    def timed(stage, function):
        def run(*args, **kwargs):
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                seconds[stage] += time.perf_counter() - start
        return run

    finder = replace(NUMPY_RASTER, **{s: timed(s, getattr(NUMPY_RASTER, s)) for s in STAGES})
    start = time.perf_counter()
    frame = draw(scene, width, height, finder)
    seconds["total"] = time.perf_counter() - start
    seconds["rest"] = seconds["total"] - sum(seconds[s] for s in STAGES)
    return frame, seconds


def median_frame(scene, width, height, repeat, warm_up):
    if warm_up:
        timed_frame(scene, width, height)
    runs = [timed_frame(scene, width, height) for _ in range(repeat)]
    return runs[0][0], {key: statistics.median(r[1][key] for r in runs) for key in runs[0][1]}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="museum")
    parser.add_argument("--size", default="640x480", type=parse_size)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--repeat-textbook", type=int, default=1)
    args = parser.parse_args(argv)
    width, height = args.size
    scene = load_scene(args.scene)
    with textbook_paths():
        loop_frame, loop = median_frame(scene, width, height, args.repeat_textbook, False)
    fast_frame, fast = median_frame(scene, width, height, args.repeat, True)
    same = all(np.asarray(getattr(loop_frame, name)).tobytes()
               == np.asarray(getattr(fast_frame, name)).tobytes()
               for name in ("color", "depth", "normal", "object_id", "path"))
    print(f"{args.scene} at {width}x{height}, numpy-raster backend "
          f"(median of {args.repeat_textbook} textbook and {args.repeat} batched frames)")
    print(f"{'stage':36s} {'textbook s':>11s} {'batched s':>10s} {'speed-up':>9s}")
    for key in STAGES + ("rest", "total"):
        label = LABELS.get(key, key)
        ratio = loop[key] / fast[key] if fast[key] > 0 else float("nan")
        print(f"{label:36s} {loop[key]:11.3f} {fast[key]:10.3f} {ratio:8.1f}x")
    print("frames identical bit for bit (colour, depth, normal, object, path):", same)


if __name__ == "__main__":
    main()
