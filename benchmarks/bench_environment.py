"""What an environment map costs on every backend: time per frame of a mirror scene with the
sky gradient, the studio cube map and a panorama of it, side by side in one run.

    python benchmarks/bench_environment.py [--scene environment] [--size 320x240] [--repeat 3]

Two Markdown tables, for docs/performance.md: per backend, the median wall time per frame
with each background and its ratio to the sky, for the scene and then for its background
alone (no objects: every pixel one look-up, what a look-up costs); each says how many
background look-ups a pixel makes on average (its misses, the camera ray's and every mirror
ray's, counted by the NumPy reference in float32). The backgrounds alternate within each
round, so a busy moment of this shared machine hits all of them. The panorama (256 x 128,
float32) is written to a temporary folder.
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

import numpy as np

import marchlab
from bench_prepass import alternating_times   # the same alternating timing
from marchlab.cli import parse_size
from marchlab.render import backend_problem
from scene_model.environment import equirect_directions, studio_radiance
from scene_model.scene import (EquirectBackground, SkyBackground, StudioBackground,
                               rendered_scene)
from scene_model.scenefile import load_scene

TIMED = {"numpy float64": "float64", "numpy float32": "float32", "gpu": "float32",
         "opencl float32": "float32", "opencl float64": "float64"}


def with_background(scene, background):
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render,
                                                                 background=background))


def panorama(folder: Path, width: int = 256, height: int = 128) -> str:
    """The studio as an equirectangular .npy of width x height, in ``folder``."""
    pixels = studio_radiance(equirect_directions(width, height).reshape(-1, 3))
    path = folder / "studio.npy"
    np.save(path, pixels.reshape(height, width, 3).astype(np.float32))
    return str(path)


def lookups(scene, width, height) -> float:
    """Background look-ups a pixel (its misses: the camera ray's and every mirror ray's),
    counted by the NumPy reference in float32 through a wrapped `shading.background`."""
    from reference_cpu import shading
    seen, original = 0, shading.background

    def counting(direction, background):
        nonlocal seen
        seen += len(direction)
        return original(direction, background)

    shading.background = counting
    try:
        marchlab.render(scene, width, height, backend="numpy", precision="float32")
    finally:
        shading.background = original
    return seen / (width * height)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="environment")
    parser.add_argument("--size", default="320x240", type=parse_size)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--backends", default=",".join(TIMED))
    args = parser.parse_args()
    width, height = args.size
    scene = rendered_scene(load_scene(args.scene))
    backends = [b for b in args.backends.split(",") if backend_problem(b.split()[0]) is None]
    with tempfile.TemporaryDirectory() as folder:
        backgrounds = {"sky": SkyBackground(), "studio cube map (64^2 x 6)": StudioBackground(),
                       "panorama (256 x 128)": EquirectBackground(panorama(Path(folder)))}
        # the scene, then nothing but its background: every pixel one look-up
        for shown, objects in ((f"Scene `{args.scene}`", scene.objects),
                               ("Its background alone", ())):
            base = dataclasses.replace(scene, objects=objects)
            variants = [with_background(base, b) for b in backgrounds.values()]
            print(f"{shown} at {width}x{height}; ms per frame (median of {args.repeat}; "
                  f"ratio to the sky); {lookups(base, width, height):.2f} background "
                  "look-ups a pixel:\n")
            print("| backend | " + " | ".join(backgrounds) + " |")
            print("|---|" + "---|" * len(backgrounds))
            for label in backends:
                median = alternating_times(variants, width, height, label.split()[0],
                                           TIMED[label], args.repeat)
                print(f"| {label} | " + " | ".join(f"{1000 * t:.1f} ({t / median[0]:.2f}x)"
                                                   for t in median) + " |")
            print()
    if "gpu" in backends:
        from gpu_shader.render import device_name
        print(f"\ngpu: {device_name()}")


if __name__ == "__main__":
    main()
