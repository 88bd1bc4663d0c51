"""Where the GPU physics step's time goes, dispatch by dispatch, beside the CPU step.

    python benchmarks/bench_physics_stages.py [--count 10000] [--steps 10] [--storage-reads]

The world of bench_physics.py (spheres in a box, float32, simultaneous solver) after the
same 0.25 s warm-up, stepped ``--steps`` times by gpu_shader.physics with every dispatch
followed by ``ctx.finish()`` and timed (the waits add a little to the whole), then by the CPU
step on a copy of the same world. Prints a Markdown table of milliseconds per step by stage
(glsl/physics_step.glsl), the largest first.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_physics import box_of_spheres  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=10000)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--storage-reads", action="store_true",
                        help="read storage buffers, not buffer textures (TEXEL_READS 0)")
    args = parser.parse_args()
    from gpu_shader.context import gl_context, renderer_name
    from gpu_shader.physics import GpuStepper

    world = box_of_spheres(args.count, "simultaneous").copy(dtype="float32")
    warm_up = int(round(0.25 / world.dt))
    stepper = GpuStepper(world, texel_reads=False if args.storage_reads else None)
    stepper(warm_up)
    seconds, dispatches = collections.Counter(), collections.Counter()
    dispatch = stepper._dispatch

    def timed(stage, *args_, **kwargs):
        stepper.ctx.finish()
        start = time.perf_counter()
        dispatch(stage, *args_, **kwargs)
        stepper.ctx.finish()
        seconds[stage] += time.perf_counter() - start
        dispatches[stage] += 1

    stepper._dispatch = timed
    start = time.perf_counter()
    stepper(args.steps)
    gpu = (time.perf_counter() - start) / args.steps

    cpu_world = box_of_spheres(args.count, "simultaneous").copy(dtype="float32")
    for _ in range(warm_up):
        cpu_world.step()
    start = time.perf_counter()
    for _ in range(args.steps):
        cpu_world.step()
    cpu = (time.perf_counter() - start) / args.steps

    reads = "buffer textures" if stepper.texel_reads else "storage buffers"
    print(f"{args.count:,} spheres on {renderer_name(gl_context())}, reads through {reads}: "
          f"GPU {1e3 * gpu:.1f} ms a step (dispatches timed one by one), CPU float32 "
          f"{1e3 * cpu:.1f} ms\n")
    print("| stage | ms per step | dispatches per step |\n|---|---:|---:|")
    for stage, s in seconds.most_common():
        print(f"| {stage} | {1e3 * s / args.steps:.1f} | {dispatches[stage] // args.steps} |")


if __name__ == "__main__":
    main()
