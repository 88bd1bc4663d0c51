"""What glass costs, and what its accuracy costs, side by side in one run.

1. The bundled `glass` scene on every backend at 320x240: as shipped (ray tree 6 deep),
   with a tree 2 deep, with Schlick's Fresnel, and with its glass made opaque
   (transparency 0: the same geometry, mirrors and lights, no refracted rays). Median of
   REPEAT, the variants alternating so a busy moment hits all of them.
2. Speed against error: the exact-tree scene of tests/truth/test_truth_glass.py (a tinted
   ball and a tilted block, pure dielectrics, 160x120) rendered by the NumPy reference with
   coarser and finer epsilon and surface offset, each frame's largest colour error against
   the exact tree (`reference_cpu.truth.glass`) and its time.

    python benchmarks/bench_glass.py [--repeat 5]

Prints Markdown tables for docs/performance.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np

import marchlab
from reference_cpu.truth.glass import glass_colors
from scene_model.builder import (Camera, Material, RenderSettings, Scene, SkyBackground, box,
                                 sphere)
from scene_model.camera import camera_rays
from scene_model.scene import rendered_scene

SIZE = (320, 240)
BACKENDS = [("numpy", "float32"), ("opencl", "float32"), ("opencl", "float64"),
            ("gpu", "float32")]


def variants(scene: Scene) -> dict[str, Scene]:
    def render(**kw):
        return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **kw))
    opaque = {k: dataclasses.replace(m, transparency=0.0) for k, m in scene.materials.items()}
    return {"glass, depth 6": scene, "depth 2": render(reflection_depth=2),
            "Schlick": render(fresnel="schlick"),
            "opaque": dataclasses.replace(scene, materials=opaque)}


def cost_table(repeat: int) -> None:
    scenes = variants(rendered_scene(marchlab.load_scene("glass")))
    print("| backend | " + " | ".join(f"{name} ms" for name in scenes) + " | glass / opaque |")
    print("|---|" + "---:|" * (len(scenes) + 1))
    for backend, precision in BACKENDS:
        for scene in scenes.values():                      # warm-up: build every program
            marchlab.render(scene, *SIZE, backend=backend, precision=precision)
        seconds = {name: [] for name in scenes}
        for _ in range(repeat):
            for name, scene in scenes.items():
                start = time.perf_counter()
                marchlab.render(scene, *SIZE, backend=backend, precision=precision)
                seconds[name].append(time.perf_counter() - start)
        ms = {name: 1000 * statistics.median(s) for name, s in seconds.items()}
        print(f"| {backend} {precision} | " + " | ".join(f"{v:.1f}" for v in ms.values())
              + f" | {ms['glass, depth 6'] / ms['opaque']:.2f} |")


def truth_scene(epsilon: float, offset: float) -> Scene:
    glass = Material(ka=0.0, kd=0.0, ks=0.0, transparency=1.0, ior=1.5,
                     absorption=(0.4, 0.1, 0.0))
    return Scene(camera=Camera(position=(0, 0.3, 4), look_at=(0, 0, 0), fov=40),
                 render=RenderSettings(epsilon=epsilon, surface_offset=offset, normal_step=1e-5,
                                       reflection_depth=6, max_steps=2000, shadows="none",
                                       background=SkyBackground(bottom=(0.9, 0.2, 0.1),
                                                                top=(0.1, 0.3, 1.0))),
                 materials={"default": glass},
                 objects=(sphere(1.0), box(0.6, 0.3, 0.1).rotate(10, 30, 0).at(1.0, 0.8, -1.0)))


def error_table(repeat: int) -> None:
    width, height = 160, 120
    print("| epsilon | surface offset | precision | ms | max colour error | 99th percentile |")
    print("|---:|---:|---|---:|---:|---:|")
    for epsilon, offset in [(1e-3, 1e-2), (1e-4, 1e-3), (1e-5, 1e-4), (1e-7, 1e-6)]:
        scene = truth_scene(epsilon, offset)
        origin, d = camera_rays(scene.camera, width, height, np.float64)
        exact = np.clip(glass_colors(scene, origin, d.reshape(-1, 3)), 0, 1)
        exact = exact.reshape(height, width, 3)
        for precision in ("float32", "float64"):
            if precision == "float32" and epsilon < 1e-5:
                continue                     # below float32's resolution at t ~ 4
            times = []
            for _ in range(repeat):
                start = time.perf_counter()
                frame = marchlab.render(scene, width, height, precision=precision)
                times.append(time.perf_counter() - start)
            error = np.abs(frame.color - exact).max(axis=-1)
            print(f"| {epsilon:g} | {offset:g} | {precision} | "
                  f"{1000 * statistics.median(times):.0f} | {error.max():.2g} | "
                  f"{np.quantile(error, 0.99):.2g} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    cost_table(args.repeat)
    print()
    error_table(max(1, args.repeat // 2))


if __name__ == "__main__":
    main()
