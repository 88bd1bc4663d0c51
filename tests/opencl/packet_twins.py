"""Run a building block and its packet twin on the same inputs, to check they agree to the bit.

Every function of the one-ray OpenCL program (``glsl/*.glsl``) has a twin in the packet
program (``glsl/*_packet.cl``) that computes the same thing for LANES rays at once. A test
writes a small kernel ``twin`` twice, once over scalars and once over packets, around the
functions it checks; `run_twins` builds each with its dialect's prelude, feeds both the same
rows of inputs and returns both outputs.

The scalar kernel runs one work-item per input row and reads its inputs as ``IN(c)`` (column
c of its row) and writes ``OUT(c, value)``. The packet kernel runs one work-item per LANES
rows and reads ``IN(c)`` as a packet (column c of its LANES rows) and writes ``OUT(c, v)``
from a packet. So the two kernels read alike::

    scalar:  OUT(0, sdf_sphere(vec3(IN(0), IN(1), IN(2)), IN(3)));
    packet:  OUT(0, sdf_sphere(pack3(IN(0), IN(1), IN(2)), IN(3)[0]));

``defines`` become ``#define`` lines in both programs, for the constants the blocks read
(EPSILON, MAX_STEPS, ...), which the real program takes from its parameter block.
"""

from __future__ import annotations

import numpy as np

from gpu_shader.dialects import PACKET_LANES, dialect
from reference_cpu.opencl import build_options

LANES = PACKET_LANES

_SCALAR_ACCESS = """\
#define IN(c) in[get_global_id(0) * IN_COLUMNS + (c)]
#define OUT(c, value) out[get_global_id(0) * OUT_COLUMNS + (c)] = (value)
"""

# Column c of the work-item's LANES rows, gathered into one packet (and scattered back).
_PACKET_ACCESS = """\
packet in_column(__global const real* in, int c)
{
    real lanes[LANES];
    for (int k = 0; k < LANES; k++) {
        lanes[k] = in[(get_global_id(0) * LANES + k) * IN_COLUMNS + c];
    }
    return vload_packet(0, lanes);
}

void out_column(__global real* out, int c, packet value)
{
    real lanes[LANES];
    vstore_packet(value, 0, lanes);
    for (int k = 0; k < LANES; k++) {
        out[(get_global_id(0) * LANES + k) * OUT_COLUMNS + c] = lanes[k];
    }
}

#define IN(c) in_column(in, (c))
#define OUT(c, value) out_column(out, (c), convert_packet(value))
"""


def _program(prelude: str, access: str, source: str, defines: dict, columns: tuple) -> str:
    lines = [f"#define {name} {value}" for name, value in defines.items()]
    lines += [f"#define IN_COLUMNS {columns[0]}", f"#define OUT_COLUMNS {columns[1]}"]
    return "\n".join([prelude, *lines, access, source])


def run_twins(device, precision: str, scalar_source: str, packet_source: str,
              inputs: np.ndarray, outputs: int, defines: dict | None = None):
    """Outputs of the scalar and the packet kernel ``twin`` over the rows of ``inputs``.

    Parameters
    ----------
    device : reference_cpu.opencl.Device
    precision : {"float32", "float64"}
    scalar_source, packet_source : str
        The functions under test and a kernel
        ``__kernel void twin(__global const real* in, __global real* out)`` in each form.
    inputs : (N, K) array
        One row per ray; N need not be a multiple of LANES (the last packet is padded by
        repeating the last row).
    outputs : int
        M, the number of output columns.

    Returns
    -------
    scalar, packet : (N, M) ndarrays in the precision's dtype
    """
    import pyopencl as cl

    dtype = np.dtype(np.float32 if precision == "float32" else np.float64)
    rows = np.asarray(inputs, dtype=dtype)
    n = len(rows)
    padded = -(-n // LANES) * LANES
    rows = np.concatenate([rows, np.repeat(rows[-1:], padded - n, axis=0)])
    columns = (rows.shape[1], outputs)
    defines = defines or {}
    results = []
    for prelude, access, source, work_items in (
            (dialect("opencl", precision).prelude, _SCALAR_ACCESS, scalar_source, padded),
            (dialect("opencl-packets", precision).prelude, _PACKET_ACCESS, packet_source,
             padded // LANES)):
        text = _program(prelude, access, source, defines, columns)
        program = cl.Program(device.context, text).build(
            options=build_options(cl, device, precision))
        flags = cl.mem_flags
        in_buffer = cl.Buffer(device.context, flags.READ_ONLY | flags.COPY_HOST_PTR,
                              hostbuf=np.ascontiguousarray(rows))
        out = np.zeros((padded, outputs), dtype)
        out_buffer = cl.Buffer(device.context, flags.WRITE_ONLY, out.nbytes)
        program.twin(device.queue, (work_items,), None, in_buffer, out_buffer)
        cl.enqueue_copy(device.queue, out, out_buffer)
        device.queue.finish()
        results.append(out[:n])
    return results[0], results[1]
