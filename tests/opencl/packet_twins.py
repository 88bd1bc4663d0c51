"""Run building blocks and their derived packet forms on the same inputs, to check they agree to the bit.

The packet program is derived from the one-ray program (gpu_shader/vectorise.py): every
function of the building blocks (``glsl/*.glsl``) gets a packet form that computes the same
thing for LANES rays at once. A test writes a small kernel ``twin`` twice, once over scalars
and once over packets, around the functions it checks; `derive` writes the packet form of
the functions as the packet program does, `run_twins` builds each program with its
dialect's prelude, feeds both the same rows of inputs and returns both outputs.

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
writes both kernels itself, calling every function on its own input columns, derives the
packet forms with each case's arguments varying as its kinds say (a parameter the same in
every lane stays scalar), and builds and runs them once per precision (`TwinCases.run`,
`TwinCases.results`).

The inputs are seeded random rows with the hard cases mixed in (tests/opencl/twin_inputs.py).
`assert_bits_equal`, `need_precision` and `TwinCases.assert_checks_all` are the checks the
test files share.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest

from gpu_shader.dialects import PACKET_LANES, dialect, thread_parameters
from gpu_shader.library import load_library
from gpu_shader.opencl import build_options
from gpu_shader.packets import choose_functions, program_structs
from gpu_shader.subset import Define, Program, format_program
from gpu_shader.subset_reader import parse
from gpu_shader.vectorise import vectorise

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


def define_lines(defines: dict | None) -> str:
    return "".join(f"#define {name} {value}\n" for name, value in (defines or {}).items())


def derive(functions: str, roots: dict, live_roots=(), defines: dict | None = None,
           structs: bool = False) -> tuple:
    """The packet form of the one-ray ``functions``, as the packet program derives it.

    Parameters
    ----------
    functions : str
        One-ray source: building blocks, a scene's SDF, ...
    roots : dict
        Function name -> whether each of its parameters varies where the test kernel calls
        it (the others are the same in every lane, scalar).
    live_roots : iterable of str
        Functions that take the mask ``live`` whatever they hold.
    defines : dict, optional
        The ``#define`` lines the functions read (and ``#if`` decides on).
    structs : bool
        Whether to start with the packet structs and their ``choose`` (Hit, LightSample...).

    Returns
    -------
    source : str
        The packet functions (without ``defines``: `run_twins` writes those).
    analysis : gpu_shader.varying.Analysis
        What varies, which function takes ``live``.
    """
    table = program_structs(False)
    program = parse(define_lines(defines) + functions, table)
    packet, analysis = vectorise(program, table, roots, live_roots)
    given = set(defines or {})
    text = format_program(Program([i for i in packet.items
                                   if not (isinstance(i, Define) and i.name in given)]))
    return (choose_functions(table) + text) if structs else text, analysis


def _program(prelude: str, access: str, source: str, defines: dict, columns: tuple) -> str:
    lines = [define_lines(defines), f"#define IN_COLUMNS {columns[0]}",
             f"#define OUT_COLUMNS {columns[1]}"]
    return "\n".join([prelude, *lines, access, source])


def run_twins(device, precision: str, scalar_source: str, packet_source: str,
              inputs: np.ndarray, outputs: int, defines: dict | None = None,
              parameters: np.ndarray | None = None):
    """Outputs of the scalar and the packet kernel ``twin`` over the rows of ``inputs``.

    Parameters
    ----------
    device : gpu_shader.opencl.Device
    precision : {"float32", "float64"}
    scalar_source, packet_source : str
        The functions under test and a kernel
        ``__kernel void twin(__global const real* in, __global real* out)`` in each form
        (the packet functions from `derive`).
    inputs : (N, K) array
        One row per ray; N need not be a multiple of LANES (the last packet is padded by
        repeating the last row).
    outputs : int
        M, the number of output columns.
    defines : dict, optional
        ``#define`` lines for both programs.
    parameters : (R, 4) array, optional
        Rows of a parameter block ``P`` (``U``), as the real program receives them: the
        kernels are then ``twin(PARAMETERS, in, out)`` and every function that reads the
        rows gets them passed on (`gpu_shader.dialects.thread_parameters`).

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
        flags = cl.mem_flags
        buffers = []
        if parameters is not None:
            receive = dialect("opencl", precision).declare_parameters(len(parameters), 0, 0)
            source = f"{receive}#define PARAMETER_ROWS {len(parameters)}\n{source}"
            buffers.append(cl.Buffer(device.context, flags.READ_ONLY | flags.COPY_HOST_PTR,
                                     hostbuf=np.ascontiguousarray(parameters, dtype=dtype)))
        text = _program(prelude, access, source, defines, columns)
        if parameters is not None:
            text = thread_parameters(text)
        program = cl.Program(device.context, text).build(
            options=build_options(cl, device, precision))
        buffers.append(cl.Buffer(device.context, flags.READ_ONLY | flags.COPY_HOST_PTR,
                                 hostbuf=np.ascontiguousarray(rows)))
        out = np.zeros((padded, outputs), dtype)
        out_buffer = cl.Buffer(device.context, flags.WRITE_ONLY, out.nbytes)
        program.twin(device.queue, (work_items,), None, *buffers, out_buffer)
        cl.enqueue_copy(device.queue, out, out_buffer)
        device.queue.finish()
        results.append(out[:n])
    return results[0], results[1]


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
    """One function of a scalar library, checked against its derived packet form.

    Parameters
    ----------
    library : str
        The scalar library, e.g. "sdf" (glsl/sdf.glsl).
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

    def kernel(self, form: str, uniform_results=frozenset()) -> str:
        """The kernel that calls every case's function once per row (``form`` "scalar")
        or once per packet of rows (``form`` "packet"). The packet forms of the functions
        named in ``uniform_results`` return one value for every lane (background_solid's
        colour), which the kernel widens to a packet."""
        packet = form == "packet"
        lines, column, out = [], 0, 0
        for case in self.cases:
            arguments = []
            for kind in case.arguments:
                reads = [f"IN({column + i})" for i in range(WIDTHS[kind])]
                arguments.append(_argument(kind, reads, packet))
                column += WIDTHS[kind]
            call = f"{case.name}({', '.join(arguments)})"
            if packet and case.name in uniform_results:
                call = f"splat3({call})" if case.result == "vec3p" else f"(packet)({call})"
            lines += _writes(case.result, call, out, packet)
            out += RESULT_WIDTHS[case.result]
        return "\n".join(["__kernel void twin(__global const real* in, __global real* out)",
                          "{", *lines, "}", ""])

    def scalar_functions(self) -> str:
        """The cases' functions and all they call, from their libraries."""
        names: dict = {}
        for case in self.cases:
            names.setdefault(case.library, []).append(case.name)
        return "\n".join(load_library(library).select(wanted)
                         for library, wanted in names.items())

    def packet_functions(self) -> tuple:
        """The packet form of `scalar_functions`, each case's arguments varying as its kinds
        say (checked), and the names of those whose result is the same in every lane."""
        roots = {case.name: tuple(kind in PER_RAY for kind in case.arguments)
                 for case in self.cases}
        source, analysis = derive(self.scalar_functions(), roots, defines=self.defines,
                                  structs=self.structs)
        for name, flags in roots.items():
            got = tuple(p.varying for p in analysis.functions[name].parameters)
            assert got == flags, f"{name}: parameters vary as {got}, the case says {flags}"
        uniform = {name for name in roots if not analysis.functions[name].returns_varying}
        return source, frozenset(uniform)

    def sources(self, form: str, precision: str) -> str:
        """The program of ``form`` ("scalar" or "packet"): the cases' functions (and all they
        call) in that form, and the kernel."""
        packet = form == "packet"
        functions, uniform = self.packet_functions() if packet else (self.scalar_functions(), ())
        blocks = [functions]
        if self.structs:
            blocks.insert(0, dialect("opencl-packets" if packet else "opencl",
                                     precision).structs())
        return "\n".join([*blocks, self.kernel(form, frozenset(uniform))])

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
        """Every function of ``library`` is one of the cases."""
        checked = sorted(case.name for case in self.cases if case.library == library)
        names = sorted(load_library(library).names())
        assert checked == names, f"{library}: cases {checked}, functions {names}"


# --- Checks -------------------------------------------------------------------------------

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
