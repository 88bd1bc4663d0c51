"""The gpu backend's time per frame at 640x480 on every bundled scene with plain marching,
the cone pre-pass, auto relaxation, and both, side by side in one run (median of 7, the four
variants alternating so a busy moment hits all of them).

    python benchmarks/bench_prepass_settings.py

Prints a Markdown table for docs/performance.md.
"""

from __future__ import annotations

import dataclasses
import statistics
import time

import marchlab
from scene_model.scene import rendered_scene
from scene_model.scenefile import bundled_scene_names, load_scene

VARIANTS = {"plain": {}, "cone": {"prepass": "cone"}, "auto": {"relaxation": "auto"},
            "cone + auto": {"prepass": "cone", "relaxation": "auto"}}
SIZE = (640, 480)
REPEAT = 7


def main() -> None:
    print("| scene | " + " | ".join(VARIANTS) + " |")
    print("|---|" + "---|" * len(VARIANTS))
    for name in bundled_scene_names(meshes=False):
        scene = rendered_scene(load_scene(name))
        variants = [dataclasses.replace(scene, render=dataclasses.replace(scene.render, **c))
                    for c in VARIANTS.values()]
        for variant in variants:                  # warm-up: compile every program
            marchlab.render(variant, *SIZE, backend="gpu")
        seconds = [[] for _ in variants]
        for _ in range(REPEAT):
            for i, variant in enumerate(variants):
                start = time.perf_counter()
                marchlab.render(variant, *SIZE, backend="gpu")
                seconds[i].append(time.perf_counter() - start)
        print(f"| {name} | " + " | ".join(f"{1000 * statistics.median(s):.1f}"
                                          for s in seconds) + " |")


if __name__ == "__main__":
    main()
