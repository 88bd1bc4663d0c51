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

To check many functions at once, a test lists them as `Case` rows (library, name, argument
and result kinds, a function that draws the inputs) and hands them to `TwinCases`, which
writes both kernels itself, calling every function on its own input columns, and builds and
runs them once per precision (`TwinCases.run`, `TwinCases.results`).

The inputs are seeded random rows with the hard cases mixed in, drawn with `mix` (row by
row, or packet by packet, one of several arrays), `per_packet` (a parameter, the same for
the LANES rows of a packet), `pick`, `units`, `normalised` and `near` (just beside a
value); each test file keeps its own seed and sizes. `assert_bits_equal`, `need_precision`,
`assert_twin_names` and `TwinCases.assert_checks_all` are the checks the test files share.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest

from gpu_shader.dialects import PACKET_LANES, dialect
from gpu_shader.library import load_library
from gpu_shader.opencl import build_options

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
    device : gpu_shader.opencl.Device
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


# --- Inputs: seeded random rows, with the hard cases mixed in -----------------------------

def mix(rng, *options) -> np.ndarray:
    """Entry by entry along the first axis, one of ``options`` at random.

    Parameters
    ----------
    rng : numpy.random.Generator
    *options : array_like
        Broadcast to one shape (n, ...): rows of inputs, or (blocks, ...) values of a
        parameter to choose packet by packet. At least one must have that shape.

    Returns
    -------
    (n, ...) ndarray
    """
    shape = np.broadcast_shapes(*map(np.shape, options))
    stacked = np.stack([np.broadcast_to(o, shape) for o in options])
    return stacked[rng.integers(len(options), size=shape[0]), np.arange(shape[0])]


def per_packet(values) -> np.ndarray:
    """One value (or row of k values) per packet, repeated for the LANES rows of its packet.

    Parameters
    ----------
    values : (blocks,) or (blocks, k) array_like

    Returns
    -------
    (blocks * LANES, k) ndarray
    """
    values = np.asarray(values, float)
    return np.repeat(values.reshape(len(values), -1), LANES, axis=0)


def pick(rng, choices, shape) -> np.ndarray:
    """An array of ``shape`` values drawn from ``choices``, each equally likely."""
    return np.asarray(choices, float)[rng.integers(len(choices), size=shape)]


def units(rng, n: int) -> np.ndarray:
    """(n, 3) random unit vectors, uniform over the sphere."""
    return normalised(rng.normal(size=(n, 3)))


def normalised(v) -> np.ndarray:
    """``v`` divided by its length along the last axis."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def near(rng, values, exponents: tuple) -> np.ndarray:
    """``values`` a relative 10**e off, either way, for e uniform in ``exponents``.

    Parameters
    ----------
    rng : numpy.random.Generator
    values : (n, ...) ndarray
    exponents : (low, high)
        E.g. (-7, -2): from 1e-7 to 1e-2 off, just inside to well outside a surface.

    Returns
    -------
    (n, ...) ndarray
        One offset per entry along the first axis (per row).
    """
    shape = (len(values),) + (1,) * (np.ndim(values) - 1)
    offset = rng.choice([-1.0, 1.0], size=shape) * 10.0 ** rng.uniform(*exponents, size=shape)
    return values * (1.0 + offset)


# --- Many functions in one kernel ---------------------------------------------------------

# Argument kinds: per-ray values (a packet in the twin) or parameters (scalar in both), and
# how many input columns each takes.
WIDTHS = {"packet": 1, "vec3p": 3, "ipacket": 1, "upacket": 1, "real": 1, "vec2": 2,
          "vec3": 3, "vec4": 4}
PER_RAY = {"packet", "vec3p", "ipacket", "upacket"}
# How a column of reals becomes an argument: scalar form, packet form.
CONVERSIONS = {"ipacket": ("(int)({})", "convert_ipacket({})"),
               "upacket": ("(uint)({})", "convert_upacket({})")}
# Result kinds and how many output columns each fills. A "mask" is a bool in the scalar form
# and a -1/0 mask in the packet form; a LightSample is to_light, distance, radiance.
RESULT_WIDTHS = {"packet": 1, "vec3p": 3, "upacket": 1, "mask": 1, "LightSample": 7}


@dataclass(frozen=True)
class Case:
    """One function of a scalar library (and, by the same name, of its packet twin).

    Parameters
    ----------
    library : str
        The scalar library, e.g. "sdf"; the twin is `twin_library` of it.
    name : str
    arguments : tuple of str
        The kinds of its arguments (keys of WIDTHS).
    result : str
        The kind of its result (a key of RESULT_WIDTHS).
    inputs : callable
        rng -> one (rows, WIDTHS[kind]) array per argument.
    """

    library: str
    name: str
    arguments: tuple[str, ...]
    result: str
    inputs: Callable


def twin_library(library: str) -> str:
    """The name of the packet twin of the scalar library ``library``."""
    return library + "_packet"


def _argument(kind: str, reads: list, packet: bool) -> str:
    """An argument of ``kind`` made of the input columns ``reads`` (``IN(c)`` each)."""
    if packet and kind not in PER_RAY:
        reads = [f"{r}[0]" for r in reads]              # a parameter: the same in every lane
    if kind == "vec3p":
        return f"{'pack3' if packet else 'vec3'}({', '.join(reads)})"
    if kind in ("vec2", "vec3", "vec4"):
        return f"{kind}({', '.join(reads)})"
    if kind in CONVERSIONS:
        return CONVERSIONS[kind][packet].format(reads[0])
    return reads[0]


def _writes(result: str, call: str, out: int, packet: bool) -> list:
    """The lines that write the ``result`` of ``call`` to the output columns from ``out``."""
    xyz = list(enumerate("xyz"))
    if result == "vec3p":
        return [f"    {{ {'vec3p' if packet else 'vec3'} v = {call};",
                *[f"      OUT({out + i}, v.{c});" for i, c in xyz], "    }"]
    if result == "LightSample":
        return [f"    {{ LightSample s = {call};",
                *[f"      OUT({out + i}, s.to_light.{c});" for i, c in xyz],
                f"      OUT({out + 3}, s.distance);",
                *[f"      OUT({out + 4 + i}, s.radiance.{c});" for i, c in xyz], "    }"]
    if result == "mask" and not packet:
        return [f"    OUT({out}, {call} ? -1.0 : 0.0);"]     # a bool here: write the -1/0 mask
    if result == "upacket" and not packet:
        return [f"    OUT({out}, (real)({call}));"]
    return [f"    OUT({out}, {call});"]


class TwinCases:
    """Cases built into one kernel ``twin`` per form, run once per precision.

    Parameters
    ----------
    cases : list of Case
        Each calls its function on its own input columns and writes its own output columns,
        in this order.
    seed : int
        Seeds the one generator that each case's ``inputs`` draws from in turn.
    rows : int
        The number of rows each case's ``inputs`` returns.
    defines : dict, optional
        ``#define`` lines for both programs, as in `run_twins`.
    structs : bool
        Whether the programs declare the dialect's structs (Hit, LightSample, ...).
    """

    def __init__(self, cases: list, seed: int, rows: int, defines: dict | None = None,
                 structs: bool = False):
        self.cases, self.seed, self.rows = cases, seed, rows
        self.defines, self.structs = defines, structs
        self._runs: dict = {}

    def kernel(self, form: str) -> str:
        """The kernel that calls every case's function once per row (``form`` "scalar")
        or once per packet of rows (``form`` "packet")."""
        packet = form == "packet"
        lines, column, out = [], 0, 0
        for case in self.cases:
            arguments = []
            for kind in case.arguments:
                reads = [f"IN({column + i})" for i in range(WIDTHS[kind])]
                arguments.append(_argument(kind, reads, packet))
                column += WIDTHS[kind]
            lines += _writes(case.result, f"{case.name}({', '.join(arguments)})", out, packet)
            out += RESULT_WIDTHS[case.result]
        return "\n".join(["__kernel void twin(__global const real* in, __global real* out)",
                          "{", *lines, "}", ""])

    def sources(self, form: str, precision: str) -> str:
        """The program of ``form`` ("scalar" or "packet"): the cases' functions (and all they
        call) from their libraries, and the kernel."""
        names: dict = {}
        for case in self.cases:
            names.setdefault(case.library, []).append(case.name)
        packet = form == "packet"
        blocks = [load_library(twin_library(library) if packet else library).select(wanted)
                  for library, wanted in names.items()]
        if self.structs:
            blocks.insert(0, dialect("opencl-packets" if packet else "opencl",
                                     precision).structs())
        return "\n".join([*blocks, self.kernel(form)])

    def inputs(self) -> tuple[np.ndarray, dict]:
        """All cases' input columns side by side, and each case's output columns.

        Returns
        -------
        rows : (rows, K) ndarray
        outputs : dict
            Case name -> slice of its output columns.
        """
        rng = np.random.default_rng(self.seed)
        columns, outputs, out = [], {}, 0
        for case in self.cases:
            arrays = [np.asarray(a, float) for a in case.inputs(rng)]
            shapes = [(self.rows, WIDTHS[kind]) for kind in case.arguments]
            assert [a.shape for a in arrays] == shapes, case
            columns += arrays
            outputs[case.name] = slice(out, out + RESULT_WIDTHS[case.result])
            out += RESULT_WIDTHS[case.result]
        return np.hstack(columns), outputs

    def run(self, device, precision: str) -> tuple[np.ndarray, np.ndarray, dict]:
        """The scalar and packet outputs of every case, and each case's output columns
        (built and run once per precision)."""
        if precision not in self._runs:
            rows, outputs = self.inputs()
            width = sum(RESULT_WIDTHS[case.result] for case in self.cases)
            scalar, packet = run_twins(device, precision, self.sources("scalar", precision),
                                       self.sources("packet", precision), rows,
                                       outputs=width, defines=self.defines)
            self._runs[precision] = scalar, packet, outputs
        return self._runs[precision]

    def results(self, device, precision: str, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The scalar and the packet outputs of the case ``name``, (rows, width) each."""
        scalar, packet, outputs = self.run(device, precision)
        return scalar[:, outputs[name]], packet[:, outputs[name]]

    def assert_checks_all(self, library: str):
        """Every function of ``library`` (so of its twin) is one of the cases."""
        checked = sorted(case.name for case in self.cases if case.library == library)
        names = sorted(load_library(library).names())
        assert checked == names, f"{library}: cases {checked}, functions {names}"


# --- Checks -------------------------------------------------------------------------------

def assert_twin_names(library: str):
    """The twin of ``library`` defines the same functions, by name, in the same order."""
    scalar = load_library(library).names()
    packet = load_library(twin_library(library)).names()
    assert packet == scalar, f"{twin_library(library)}: {packet}, {library}: {scalar}"


def need_precision(device, precision: str):
    """Skip the calling test where ``device`` has no ``precision``."""
    if precision == "float64" and not device.fp64:
        pytest.skip(f"{device.label} has no float64")


def assert_bits_equal(got, expected, what: str):
    """``got`` equals ``expected`` to the bit: also in the sign of zero and NaN payloads."""
    np.testing.assert_array_equal(got, expected, err_msg=what)
    bits = np.uint32 if expected.dtype == np.float32 else np.uint64
    np.testing.assert_array_equal(got.view(bits), expected.view(bits),
                                  err_msg=f"{what}: same values, different bits")
