"""Where a gpu frame of the classroom goes, part by part, on this machine's OpenGL.

    python benchmarks/bench_frame_parts.py [--scene classroom] [--size 640x480] [--repeat 7]

The scene is drawn with the cone pre-pass as bundled, then with one thing taken away at a
time (shadows, the mirror bounce, lighting: depth shading), and as a march of one step
(depth shading, ``max_steps = 1``): what any frame costs before a ray marches. The variants
alternate, so a busy moment of this shared machine hits all of them; each cell is the median
wall time of ``marchlab.render`` (drawing and the read-back of every buffer). The one-step
frame is then split into its draw (to ``ctx.finish``), its read-back into a `Frame` and the
rest (writing the program's parameters, Python).

Prints two Markdown tables for docs/performance.md.
"""

from __future__ import annotations

import argparse
import statistics
import time

import marchlab
from bench_prepass import alternating_times, with_settings
from gpu_shader.render import _renderer
from marchlab.cli import parse_size
from scene_model.scene import rendered_scene
from scene_model.scenefile import load_scene

VARIANTS = {
    "as bundled": {},
    "no shadows": {"shadows": "none"},
    "no mirror bounce": {"reflection_depth": 0},
    "neither": {"shadows": "none", "reflection_depth": 0},
    "depth shading (primary rays only)": {"shading": "depth"},
    "one step, depth shading": {"shading": "depth", "max_steps": 1, "prepass": "none"},
}


def median_ms(seconds) -> float:
    return 1000 * statistics.median(seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="classroom")
    parser.add_argument("--size", type=parse_size, default=(640, 480))
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    width, height = args.size
    scene = with_settings(rendered_scene(load_scene(args.scene)), prepass="cone")
    variants = {name: with_settings(scene, **c) for name, c in VARIANTS.items()}
    medians = alternating_times(list(variants.values()), width, height, "gpu", "float32",
                                args.repeat)
    print(f"{args.scene} at {width}x{height}, gpu backend, ms per frame (median of "
          f"{args.repeat}):\n")
    print("| frame | ms |\n|---|---:|")
    for name, median in zip(variants, medians):
        print(f"| {name} | {1000 * median:.1f} |")

    one_step = variants["one step, depth shading"]
    renderer = _renderer()
    program = renderer.generate(one_step, width, height)
    draw, read, whole = [], [], []
    for _ in range(args.repeat):
        with renderer.ctx:
            start = time.perf_counter()
            fbo = renderer._draw_planes(program, width, height, None)
            renderer.ctx.finish()
            draw.append(time.perf_counter() - start)
            start = time.perf_counter()
            renderer.read_frame(fbo, one_step, width, height)
            read.append(time.perf_counter() - start)
        start = time.perf_counter()
        marchlab.render(one_step, width, height, backend="gpu")
        whole.append(time.perf_counter() - start)
    rest = median_ms(whole) - median_ms(draw) - median_ms(read)
    print("\nThe one-step frame:\n")
    print("| part | ms |\n|---|---:|")
    print(f"| draw | {median_ms(draw):.1f} |\n| read-back into a Frame | {median_ms(read):.1f} |\n"
          f"| the rest (parameters, Python) | {rest:.1f} |\n| whole | {median_ms(whole):.1f} |")


if __name__ == "__main__":
    main()
