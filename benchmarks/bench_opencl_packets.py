"""Why the opencl backend is slow on a CPU, and what would make it fast (issue 4).

    python benchmarks/bench_opencl_packets.py [--size 640x480] [--lanes 8] [--repeat 7]

Marches the classroom scene's primary rays three ways on the OpenCL device marchlab picks,
side by side in one run, at float32 and float64 (benchmarks/opencl_packets.cl):

1. one ray per work-item, as the generated kernel does;
2. ``--lanes`` rays per work-item stepped in lock-step with the scalar scene_sdf;
3. ``--lanes`` rays per work-item as one packet of vectors (structure of arrays).

Prints milliseconds per frame, the speed-up over 1, and whether t and the step counts agree
with 1 to the bit (they must: the same operations in the same order, lane by lane).
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import marchlab
from marchlab.cli import parse_size
from gpu_shader.generate import generate
from reference_cpu import opencl

HERE = Path(__file__).resolve().parent

# The rows the hand-written scene_sdf_packet reads; the generated scene_sdf must read the same.
CLASSROOM_ROWS = ("sdf_plane(p, P[9].xyz, P[9].w)", "op_translate(p, P[10].xyz)",
                  "sdf_sphere(p4, P[11].x)", "op_translate(p, P[12].xyz)",
                  "sdf_sphere(p6, P[13].x)", "op_translate(p, P[14].xyz)",
                  "sdf_sphere(p8, P[15].x)")


def program_source(width: int, height: int, precision: str, lanes: int):
    """The generated program up to its march, followed by the three kernels; and P."""
    program = generate(marchlab.load_scene("classroom"), width, height, dialect="opencl",
                       precision=precision)
    missing = [row for row in CLASSROOM_ROWS if row not in program.source]
    if missing:
        sys.exit(f"the classroom scene_sdf no longer reads {missing[0]!r}: "
                 "update scene_sdf_packet in benchmarks/opencl_packets.cl")
    head = program.source[:program.source.index("// ---- sphere tracing")]
    scalar, integer = ("float", "int") if precision == "float32" else ("double", "long")
    defines = f"#define LANES {lanes}\n#define SCALAR {scalar}\n#define INT_OF_REAL {integer}\n"
    return head + defines + (HERE / "opencl_packets.cl").read_text(), program.parameters


def time_kernel(cl, dev, kernel, global_size, buffers, repeat):
    """Median seconds per launch of ``kernel`` over ``repeat`` launches after an untimed one."""
    kernel.set_args(*buffers)
    times = []
    for _ in range(repeat + 1):
        start = time.perf_counter()
        cl.enqueue_nd_range_kernel(dev.queue, kernel, global_size, None)
        dev.queue.finish()
        times.append(time.perf_counter() - start)
    return statistics.median(times[1:])


def march_three_ways(width: int, height: int, precision: str, lanes: int, repeat: int) -> dict:
    """Each kernel's median seconds, t (height * width,) and steps (height * width,), by name."""
    cl = opencl._import_pyopencl()
    dev = opencl.device()
    dtype = np.float32 if precision == "float32" else np.float64
    source, parameters = program_source(width, height, precision, lanes)
    built = cl.Program(dev.context, source).build(options=opencl.build_options(cl, dev, precision))
    flags = cl.mem_flags
    p = cl.Buffer(dev.context, flags.READ_ONLY | flags.COPY_HOST_PTR,
                  hostbuf=np.ascontiguousarray(parameters, dtype))
    results = {}
    for name, columns in (("one_ray", width), ("interleaved", width // lanes),
                          ("packets", width // lanes)):
        t = np.empty(width * height, dtype)
        steps = np.empty(width * height, np.int32)
        out = [cl.Buffer(dev.context, flags.WRITE_ONLY, a.nbytes) for a in (t, steps)]
        seconds = time_kernel(cl, dev, getattr(built, name), (columns, height), [p, *out], repeat)
        for array, buffer in zip((t, steps), out):
            cl.enqueue_copy(dev.queue, array, buffer)
        dev.queue.finish()
        results[name] = (seconds, t, steps)
    return results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=parse_size, default=(640, 480))
    parser.add_argument("--lanes", type=int, choices=(2, 4, 8, 16), default=8)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)
    width, height = args.size
    if width % args.lanes:
        parser.error(f"--size: the width must be a multiple of --lanes ({args.lanes})")
    print(f"Device: {opencl.device().label}; classroom primary rays at {width}x{height}, "
          f"{args.lanes} lanes, median of {args.repeat}\n")
    print("| precision | kernel | ms | vs one ray | same t and steps |")
    print("| --- | --- | ---: | ---: | --- |")
    for precision in ("float32", "float64"):
        results = march_three_ways(width, height, precision, args.lanes, args.repeat)
        base, t0, steps0 = results["one_ray"]
        for name, (seconds, t, steps) in results.items():
            same = np.array_equal(t, t0) and np.array_equal(steps, steps0)
            print(f"| {precision} | {name} | {1000 * seconds:.1f} | {base / seconds:.1f}x | "
                  f"{'yes' if same else 'NO'} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
