"""The cone-marching pre-pass in the NumPy reference: SDF evaluations per pixel with and
without it, on every bundled scene, and the reference's render time side by side.

    python benchmarks/bench_prepass.py [--size 320x240] [--tiles 4,8] [--repeat 3]

Per scene: the mean primary-ray steps per pixel marching from the eye, then for each tile
size the mean primary steps per pixel marching from the pre-pass's start, the pre-pass's own
evaluations per pixel (each tile's cone steps over its pixels), their sum as a fraction of
the plain march, and the pixels whose hit or object differs (grazes and rays that ran out of
steps, `reference_cpu.cone_prepass`). Step counts are exact and repeat from run to run; the
times (median of ``--repeat`` renders of the whole frame, float64) are this machine's, side
by side in one run. Markdown, for docs/performance.md.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from reference_cpu.cone_prepass import start_distances
from reference_cpu.render import render
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.scene import rendered_scene
from scene_model.scenefile import bundled_scene_names, load_scene


def timed(scene, width, height, repeat, tile=None):
    seconds, frame = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        frame = render(scene, width, height, prepass_tile=tile)
        seconds.append(time.perf_counter() - start)
    return frame, statistics.median(seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="320x240")
    parser.add_argument("--tiles", default="4,8")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    tiles = [int(t) for t in args.tiles.split(",")]
    print("| scene | plain: steps/px, time | " + " | ".join(
        f"tile {t}: primary + pre-pass steps/px = fraction; pixels differing; time"
        for t in tiles) + " |")
    print("|---|---|" + "---|" * len(tiles))
    for name in bundled_scene_names():
        scene = rendered_scene(load_scene(name))
        r = scene.render
        plain, plain_seconds = timed(scene, width, height, args.repeat)
        cells = [f"{plain.steps.mean():.1f}, {plain_seconds:.2f} s"]
        for tile in tiles:
            frame, seconds = timed(scene, width, height, args.repeat, tile)
            _, cone_steps = start_distances(scene.camera, width, height,
                                            build_scene_sdf(scene.objects, np.float64), tile,
                                            r.max_steps, r.epsilon, r.max_distance)
            prepass = cone_steps.sum() / (width * height)
            total = frame.steps.mean() + prepass
            differing = np.count_nonzero((plain.hit != frame.hit)
                                         | (plain.object_id != frame.object_id))
            cells.append(f"{frame.steps.mean():.1f} + {prepass:.2f} = "
                         f"{total / plain.steps.mean():.2f}; {differing}; {seconds:.2f} s")
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
