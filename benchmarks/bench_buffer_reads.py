"""Storage-buffer loads against buffer-texture fetches of the same words, on this GL context.

    python benchmarks/bench_buffer_reads.py [--invocations 10000] [--rows 8] [--repeat 30]

Each of ``--invocations`` invocations of a compute shader reads ``--rows`` rows of 80 bytes
(five vec4, the size of the physics step's Contact) at scattered places, once through a
storage buffer (``buffer`` block) and once through a buffer texture over the same buffer
(`gpu_shader.buffer_texture`), and sums them. Prints the fastest and median milliseconds of
each and checks that both read the same sums to the bit. This is why the GPU physics step
reads through buffer textures (glsl/physics_step.glsl, TEXEL_READS): llvmpipe loads a storage
buffer one word and one invocation at a time.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

SHADER = """#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Rows {{ vec4 rows[]; }};
layout(std430, binding = 1) buffer Sums {{ vec4 sums[]; }};
layout(std430, binding = 2) buffer Order {{ int order[]; }};
layout(binding = 16) uniform isamplerBuffer texels;
vec4 row_word(int k) {{ return {read}; }}
void main() {{
    int i = int(gl_GlobalInvocationID.x);
    if (i >= {invocations}) return;
    vec4 sum = vec4(0.0);
    int first = order[i] * {rows};
    for (int r = 0; r < {rows}; r++) {{
        int base = 5 * (first + r);
        sum += row_word(base) + row_word(base + 1) + row_word(base + 2) + row_word(base + 3)
             + row_word(base + 4);
    }}
    sums[i] = sum;
}}
"""
READS = {"storage buffer": "rows[k]",
         "buffer texture": "intBitsToFloat(texelFetch(texels, k))"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--invocations", type=int, default=10000)
    parser.add_argument("--rows", type=int, default=8)
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args()
    from gpu_shader.buffer_texture import BufferTexture, available
    from gpu_shader.context import gl_context, renderer_name

    ctx = gl_context()
    rng = np.random.default_rng(0)
    n = args.invocations
    with ctx:
        if not available(ctx):
            raise SystemExit("buffer textures cannot be made on this context")
        rows = ctx.buffer(rng.random(n * args.rows * 20, np.float32).tobytes())
        sums = ctx.buffer(reserve=16 * n)
        order = ctx.buffer(rng.permutation(n).astype(np.int32).tobytes())
        texture = BufferTexture(rows)
        texture.use(16)
        for binding, buffer in enumerate((rows, sums, order)):
            buffer.bind_to_storage_buffer(binding)
        print(f"{n:,} invocations x {args.rows} rows of 5 vec4 on {renderer_name(ctx)}, "
              f"fastest and median of {args.repeat}:\n")
        print("| read through | fastest ms | median ms |\n|---|---:|---:|")
        results = []
        for name, read in READS.items():
            program = ctx.compute_shader(SHADER.format(read=read, invocations=n,
                                                       rows=args.rows))
            times = []
            for _ in range(args.repeat):
                ctx.finish()
                start = time.perf_counter()
                program.run((n + 63) // 64)
                ctx.finish()
                times.append(time.perf_counter() - start)
            results.append(sums.read())
            print(f"| {name} | {1e3 * min(times):.3f} | {1e3 * statistics.median(times):.3f} |")
            program.release()
        print(f"\nthe same sums to the bit: {results[0] == results[1]}")
        for gl_object in (texture, rows, sums, order):
            gl_object.release()


if __name__ == "__main__":
    main()
