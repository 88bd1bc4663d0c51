"""The OpenCL float64 packet program against the gpu backend (llvmpipe), scene by scene.

    python benchmarks/bench_opencl_ratio.py [--size 640x480] [--repeat 5] [--scenes a b ...]
                                            [--prepass cone] [--relaxation auto]

Issue 24 asks for the float64 packet program within 2x of llvmpipe's frame, with the same
settings: each scene as bundled, or with ``--prepass`` and ``--relaxation`` set on every
scene (the render settings of issue 24, docs/sphere-tracing.md). For every bundled SDF scene
(or ``--scenes``), both backends draw it through `marchlab.render` (programs compiled once,
read-back and the `Frame` included), the two frames alternating ``--repeat`` times after a
warm-up frame each; the table gives each median in ms and opencl float64 over gpu. Machines
are shared and noisy: compare the ratios of one run.
"""

from __future__ import annotations

import argparse
import functools
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_prepass import alternating_medians, parse_size, with_settings  # noqa: E402
from bench_render import cpu_name  # noqa: E402
import marchlab  # noqa: E402
from scene_model.scenefile import bundled_scene_names, load_scene  # noqa: E402

BACKENDS = (("gpu", "float32"), ("opencl", "float64"))


def frame_times(scene, width, height, repeat) -> list[float]:
    """Median seconds per frame of each of BACKENDS on ``scene``, rendered in turn."""
    return alternating_medians(
        [functools.partial(marchlab.render, scene, width, height, backend=backend,
                           precision=precision) for backend, precision in BACKENDS], repeat)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480", type=parse_size)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--scenes", nargs="+", default=None)
    parser.add_argument("--prepass", choices=("none", "cone"), default=None,
                        help="render.prepass for every scene (default: as bundled)")
    parser.add_argument("--relaxation", choices=("none", "fixed", "auto"), default=None,
                        help="render.relaxation for every scene (default: as bundled)")
    args = parser.parse_args()
    changes = {key: value for key, value in (("prepass", args.prepass),
                                             ("relaxation", args.relaxation)) if value}
    from gpu_shader.context import gl_context, renderer_name
    from gpu_shader.opencl import device_name
    width, height = args.size
    names = args.scenes or bundled_scene_names(meshes=False)
    print(f"# {width}x{height}, median of {args.repeat}; gpu: {renderer_name(gl_context())}; "
          f"opencl: {device_name()}; {cpu_name()}; settings: {changes or 'as bundled'}\n")
    print("| scene | gpu float32 (ms) | opencl float64 (ms) | opencl64 / gpu |")
    print("|---|---:|---:|---:|")
    for name in names:
        scene = load_scene(name)
        if changes:
            scene = with_settings(scene, **changes)
        gpu, opencl = frame_times(scene, width, height, args.repeat)
        print(f"| {name} | {1e3 * gpu:.1f} | {1e3 * opencl:.1f} | {opencl / gpu:.2f} |",
              flush=True)


if __name__ == "__main__":
    main()
