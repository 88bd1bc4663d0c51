"""The small table of what differs between the C-like languages marchlab generates.

The building blocks (``glsl/*.glsl``) and the generated code are written in a common subset:
types ``real``, ``vec3`` and ``vec4``, constructors ``vec3(...)``, conversions ``uint(...)``,
no ``out`` parameters, structs only declared here, ``abs``/``min``/``max``/``clamp``/``floor``/
``reflect`` and the other functions both languages know. A dialect says how to spell the few
things that differ: the prelude that gives the types and functions their meaning, struct
declarations, number literals, conversions, how the program receives its parameters and
which entry point file ends it. The dialects: GLSL as a fragment shader and GLSL as a
compute shader (the gpu backend draws with either: `gpu_shader.render`), and OpenCL C (the
opencl backend, float32 or float64; one ray or one packet of rays per work-item).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .library import glsl_file, load_library

# Structs shared by every dialect: name -> ((type, field), ...).
STRUCTS = {
    "Hit": (("real", "t"), ("int", "steps"), ("int", "hit")),
    "LightSample": (("vec3", "to_light"), ("real", "distance"), ("vec3", "radiance")),
    # What a pixel's trace returns: its colour, and the primary ray's march, normal and object
    # id (the Frame's other buffers).
    "Pixel": (("vec3", "color"), ("Hit", "primary"), ("vec3", "normal"), ("int", "id")),
}
# With path labels, a pixel also carries its label (24 bits, exact in a float).
PATH_FIELD = ("real", "path")
# A ray of the glass tree (glsl/pipeline/trace_glass.glsl), declared where a scene has glass;
# with path labels it carries its branch's label.
RAY_STRUCT = (("vec3", "origin"), ("vec3", "direction"), ("vec3", "weight"),
              ("vec3", "absorption"), ("int", "depth"))
RAY_LABEL = ("real", "label")


def program_structs(path_labels: bool, glass: bool = False) -> dict:
    """The structs of a program: `STRUCTS`, a ``path`` field in Pixel with ``path_labels``,
    and the glass tree's Ray with ``glass``."""
    structs = dict(STRUCTS, Pixel=STRUCTS["Pixel"] + (PATH_FIELD,) * path_labels)
    if glass:
        structs["Ray"] = RAY_STRUCT + (RAY_LABEL,) * path_labels
    return structs


@dataclass(frozen=True)
class Dialect:
    """How one language spells the parts that differ."""
    name: str
    prelude: str                                  # first lines of every program
    struct: Callable[[str, tuple], str]           # a struct declaration
    to_int: Callable[[str], str]                  # real expression -> int
    declare_parameters: Callable[[int, int, int], str]  # how the program receives U and P
    real_dtype: np.dtype                          # precision of `real`
    entry: str                                    # the entry point file in glsl/
    finish: Callable[[str], str] = lambda source: source   # last rewrite of the whole text
    packets: bool = False                         # one packet of rays per work-item?
    # The entry point of the cone pre-pass's own program, where it is one ("" where the
    # entry point file holds the pre-pass's kernel too).
    prepass_entry: str = ""
    # The vertex shader that goes with the program (GLSL), given the same three numbers as
    # declare_parameters; "" for the plain full-screen triangle or no vertex stage.
    vertex_shader: Callable[[int, int, int], str] = lambda rows, fixed, flat_rows: ""
    # How the program reads its texture atlas (glsl/texture.glsl), given the number of
    # parameter rows and the atlas's width: TEXEL(column, row) and what it reads from.
    texels: Callable[[int, int], str] = lambda first, width: ""
    compute: bool = False                         # GLSL: a compute shader (else fragment)

    def library(self, name: str):
        """The building blocks ``glsl/<name>.glsl`` (a packet program derives its own from
        them: gpu_shader/packets.py)."""
        return load_library(name)

    def literal(self, value: float) -> str:
        """A number literal that reads back as exactly ``value`` rounded to `real`."""
        return np.format_float_positional(self.real_dtype.type(value), unique=True, trim="0")

    def structs(self, path_labels: bool = False, glass: bool = False) -> str:
        """The struct declarations (`program_structs`)."""
        structs = program_structs(path_labels, glass)
        return "\n".join(self.struct(name, fields) for name, fields in structs.items())


def _glsl_struct(name: str, fields) -> str:
    body = "".join(f"    {type_} {field};\n" for type_, field in fields)
    return f"struct {name}\n{{\n{body}}};\n"


# Above this many rows a per-pixel copy would cost more than it saves: larger scenes read
# everything from the uniform buffer. On llvmpipe the copy is the faster draw at every size
# measured (spheres over a floor at 320x240, 2026-11-26: 1,016 rows 552 against 1,938 ms,
# 2,016 rows 1.3 against 6.6 s, 4,016 rows 3.3 against 27.6 s), but its compile takes longer
# (15 against 10 s at 1,016 rows, 73 against 36 s at 2,016): 1,024 rows keeps the compile
# within 1.5x. A GPU draws with the compute stage, where P is always U (`_glsl_compute_parameters`).
MAX_PRIVATE_ROWS = 1024

# Up to this many fixed rows reach the fragment shader as flat varyings: GL_MAX_VARYING_VECTORS
# of llvmpipe and of NVIDIA's driver (the renderer lowers it where its context allows fewer).
MAX_FLAT_ROWS = 32

_UNIFORM_BLOCK = """\
layout(std140) uniform Parameters
{{
    vec4 U[{rows}];
}};
"""


def _glsl_parameters(rows: int, fixed: int, flat_rows: int) -> str:
    """The uniform block U and, for the first ``fixed`` rows, P: flat varyings (up to
    ``flat_rows`` rows), a private copy, or U itself."""
    block = _UNIFORM_BLOCK.format(rows=rows)
    if fixed <= flat_rows:
        return block + f"""
// The first {fixed} rows, read with fixed indices (camera, settings, SDF tree, lights), reach
// every pixel as flat varyings that the vertex shader copies from U (glsl/fullscreen.vert).
// llvmpipe reads a uniform buffer lane by lane, one bounds-checked load per pixel of its
// 8-wide vectors, even at a fixed index; a flat input costs one load per block of pixels.
// Copying the rows per pixel into a private array (what larger scenes do) made the
// classroom scene's draw a fifth slower. Materials, read by object id, stay in U.
flat in vec4 P[{fixed}];

void load_parameters()
{{
}}
"""
    if fixed > MAX_PRIVATE_ROWS:
        return block + f"""
// {fixed} rows are read with fixed indices: too many to copy per pixel (more than
// {MAX_PRIVATE_ROWS}), so P is the uniform buffer itself.
#define P U

void load_parameters()
{{
}}
"""
    return block + f"""
// The first {fixed} rows, read with fixed indices (camera, settings, SDF tree, lights), are
// more than fit in flat varyings ({flat_rows}), so they are copied once per pixel into the
// private array P. llvmpipe re-reads and bounds-checks a uniform buffer at every use,
// which made the march loop three times slower; a GPU keeps a private array read with
// constant indices in registers. Materials, read by object id, stay in U.
vec4 P[{fixed}];

void load_parameters()
{{
    for (int i = 0; i < {fixed}; i++) {{
        P[i] = U[i];
    }}
}}
"""


def glsl_vertex_shader(rows: int, fixed: int, flat_rows: int) -> str:
    """The vertex shader for a fragment shader from `_glsl_parameters`: the full-screen
    triangle, copying the first ``fixed`` of ``rows`` rows into flat varyings when they fit
    (``fixed <= flat_rows``); "" (the plain triangle) otherwise."""
    if fixed > flat_rows:
        return ""
    version, rest = glsl_file("fullscreen.vert").split("\n", 1)
    return f"{version}\n#define ROWS {rows}\n#define FLAT_ROWS {fixed}\n{rest}"


_GLSL_TEXELS = """\
// The texture atlas (glsl/texture.glsl): an RGBA32F texture, GL row r the atlas's row r,
// read texel by texel with texelFetch; the program filters it itself, the driver's sampler
// never does.
uniform sampler2D texels;
#define TEXEL(column, row) texelFetch(texels, ivec2(column, row), 0)
"""


GLSL = Dialect(
    name="glsl",
    prelude="""\
#version 330 core
// `precise` (GLSL 4.00, or ARB_gpu_shader5 on 3.3) forbids fusing a * b + c into one FMA
// rounding where the reference rounds twice.
#extension GL_ARB_gpu_shader5 : enable
#ifndef GL_ARB_gpu_shader5
#define precise
#endif
#define real float
// The depth of a miss, as in the reference; GLSL has no literal for it.
#define INFINITY uintBitsToFloat(0x7F800000u)
// C's atan2(y, x) is GLSL's atan(y, x) (GLSL spec 8.1).
#define atan2(y, x) atan(y, x)
""",
    struct=_glsl_struct,
    to_int=lambda expr: f"int({expr})",
    declare_parameters=_glsl_parameters,
    vertex_shader=glsl_vertex_shader,
    texels=lambda first, width: _GLSL_TEXELS,
    real_dtype=np.dtype(np.float32),
    entry="main.frag",
    prepass_entry="prepass.frag",
)


# The work group of the compute entry points (glsl/main.comp, glsl/prepass.comp): 8 x 8
# pixels, as llvmpipe's fragment stage shades 8 x 8 blocks and a GPU schedules 32 or 64 lanes.
GROUP_SIZE = 8


def _glsl_compute_parameters(rows: int, fixed: int, flat_rows: int) -> str:
    """The uniform block U, which is P too: a compute shader has no flat varyings."""
    return _UNIFORM_BLOCK.format(rows=rows) + f"""
// The first {fixed} rows are read with fixed indices (camera, settings, SDF tree, lights),
// straight from the uniform block: a GPU reads it with constant indices from its constant
// cache, one value for all the lanes. (A copy into the work group's shared memory needs a
// barrier, which made llvmpipe's compute shader 25 times slower; llvmpipe draws fragments,
// `gpu_shader.render.default_stage`.)
#define P U

void load_parameters()
{{
}}
"""


# The same GLSL as a compute shader (OpenGL 4.3): one invocation per pixel, writing the three
# planes as images. On a GPU whose graphics units are few (an NVIDIA H100 shades fragments on
# a handful of its 132 multiprocessors) it runs on all of them; docs/performance.md measures
# both stages.
GLSL_COMPUTE = dataclasses.replace(
    GLSL,
    name="glsl-compute",
    prelude=GLSL.prelude.replace("#version 330 core", "#version 430 core")
    .replace("#define real float\n",
             f"#define real float\n#define GROUP_SIZE {GROUP_SIZE}\n"),
    declare_parameters=_glsl_compute_parameters,
    vertex_shader=lambda rows, fixed, flat_rows: "",
    entry="main.comp",
    prepass_entry="prepass.comp",
    compute=True,
)


# --- OpenCL C ------------------------------------------------------------------------------

def _opencl_struct(name: str, fields) -> str:
    body = "".join(f"    {type_} {field};\n" for type_, field in fields)
    return f"typedef struct\n{{\n{body}}} {name};\n"


def _opencl_prelude(real: str) -> str:
    fp64 = "#pragma OPENCL EXTENSION cl_khr_fp64 : enable\n" if real == "double" else ""
    return f"""\
// OpenCL C 1.2, generated from the same building blocks as the GLSL shader.
{fp64}// Never contract a * b + c into one FMA rounding: the reference rounds twice (GLSL marks
// the expressions where it matters `precise`; here it holds everywhere).
#pragma OPENCL FP_CONTRACT OFF
#define precise
typedef {real} real;
typedef {real}2 vec2;
typedef {real}3 vec3;
typedef {real}4 vec4;
// GLSL's constructors and conversions, as OpenCL vector literals and casts. A function-like
// macro only expands before "(", so `vec3 p` still names the type.
#define vec2(...) ((vec2)(__VA_ARGS__))
#define vec3(...) ((vec3)(__VA_ARGS__))
#define vec4(...) ((vec4)(__VA_ARGS__))
#define real(x) ((real)(x))
#define uint(x) ((uint)(x))
#define int(x) ((int)(x))
// OpenCL's abs is for integers.
#undef abs
#define abs fabs
"""


# The one-ray program's reflect and normalize (the packet program has its own, in
# glsl/packet.cl).
_OPENCL_VECTORS = """\
// GLSL's reflect has no OpenCL twin (GLSL spec 8.5).
vec3 reflect(vec3 i, vec3 n)
{
    return i - 2.0 * dot(n, i) * n;
}
// normalize as the reference computes it, v / sqrt(v . v) (scene_model.geometry.normalize):
// PoCL's builtin multiplies by rsqrt, which rounds differently a quarter of the time.
#undef normalize
#define normalize(v) ((v) / sqrt(dot((v), (v))))
"""


# The integer types of the same width as each real, for masks and ids in packets.
_PACKET_TYPES = {"float": ("int", "uint"), "double": ("long", "ulong")}
PACKET_LANES = 16


def _opencl_packet_prelude(real: str) -> str:
    """The OpenCL prelude, then the packet types and helpers of glsl/packet.cl."""
    integer, unsigned = _PACKET_TYPES[real]
    n = PACKET_LANES
    types = f"""\
// Packets: {n} rays per work-item, one vector lane each (glsl/packet.cl says how).
#define LANES {n}
#define PACKET_DOUBLE {int(real == "double")}
typedef {real}{n} packet;
typedef {integer}{n} ipacket;
typedef {unsigned}{n} upacket;
#define vload_packet vload{n}
#define vstore_packet vstore{n}
#define convert_packet convert_{real}{n}
#define convert_ipacket convert_{integer}{n}
#define convert_upacket convert_{unsigned}{n}
// Lane k of a packet holds the ray of the k-th pixel of the work-item's run.
#define LANE_INDEX ((ipacket)({", ".join(str(k) for k in range(n))}))
"""
    library = glsl_file("packet.cl")
    return _opencl_prelude(real) + types + "\n" + library


# Struct fields in a packet program: one value per ray.
_PACKET_FIELD_TYPES = {"real": "packet", "int": "ipacket", "uint": "upacket", "bool": "ipacket",
                       "vec2": "vec2p", "vec3": "vec3p", "vec4": "vec4p"}


def _opencl_packet_struct(name: str, fields) -> str:
    return _opencl_struct(name, [(_PACKET_FIELD_TYPES.get(t, t), f) for t, f in fields])


# OpenCL C 1.2 has no program-scope variables but compile-time constants, so the parameters
# cannot be a global as in GLSL: the kernel receives them as a buffer and passes the pointer
# on, as a first argument, to every function that reads them (directly or through a callee).
_OPENCL_PARAMETERS = """\
// The parameters arrive as the kernel's buffer P and are passed on to every function that
// reads them (PARAMETERS in its signature): OpenCL C 1.2 has no global variables.
#define PARAMETERS __global const vec4* restrict P
#define U P
"""

_FUNCTION = re.compile(r"^(?!__kernel)(\w+)\s+(\w+)\s*\(([^)]*)\)\s*\n\{\n(.*?)^\}", re.M | re.S)
_MACRO = re.compile(r"^#define\s+(\w+)(?:\([^)]*\))?[ \t]+(.*)$", re.M)
_COMMENT = re.compile(r"//[^\n]*")


def thread_parameters(source: str) -> str:
    """Give every function that reads ``P`` or ``U`` (or calls one that does) a first
    argument ``PARAMETERS``, and pass ``P`` at each call. Comments are left as they are."""
    code = _COMMENT.sub("", source)
    macros: set[str] = set()
    while True:                      # macros that read P, directly or through another macro
        reads = re.compile(r"\b(?:P|U)\[" + "".join(rf"|\b{m}\b" for m in sorted(macros)))
        found = {m.group(1) for m in _MACRO.finditer(code) if reads.search(m.group(2))}
        if found <= macros:
            break
        macros |= found
    functions = {m.group(2): m.group(4) for m in _FUNCTION.finditer(code)}
    needs = {name for name, body in functions.items() if reads.search(body)}
    while needs:                     # callers of functions that need P need it too
        calls = re.compile(r"\b(?:" + "|".join(sorted(needs)) + r")\s*\(")
        more = {n for n, body in functions.items() if n not in needs and calls.search(body)}
        if not more:
            break
        needs |= more
    if not needs:
        return source
    call = re.compile(r"\b(" + "|".join(sorted(needs)) + r")\s*\(\s*(\)?)")
    definition = re.compile(r"^(\w+\s+)(" + "|".join(sorted(needs)) + r")\(P(, |\))", re.M)
    lines = []
    for line in source.split("\n"):
        text, slashes, comment = line.partition("//")
        text = call.sub(lambda m: f"{m.group(1)}(P{')' if m.group(2) else ', '}", text)
        lines.append(text + slashes + comment)
    return definition.sub(lambda m: f"{m.group(1)}{m.group(2)}(PARAMETERS{m.group(3)}",
                          "\n".join(lines))


def _opencl_texels(first: int, width: int) -> str:
    """TEXEL(column, row) of the texture atlas, which OpenCL appends to the parameter
    buffer: a texel a row of P, after the `first` rows of parameters."""
    return f"""\
// The texture atlas (glsl/texture.glsl) follows the {first} rows of parameters in P, one texel
// a row, {width} texels an atlas row (gpu_shader/opencl.py, parameter_buffer).
#define TEXEL(column, row) U[{first} + {width} * (row) + (column)]
"""


def _opencl(real: str, dtype, packets: bool = False) -> Dialect:
    """OpenCL C over `real`: one ray per work-item, or one packet of rays (``packets``)."""
    return Dialect(
        name="opencl-packets" if packets else "opencl",
        prelude=(_opencl_packet_prelude(real) if packets
                 else _opencl_prelude(real) + _OPENCL_VECTORS),
        struct=_opencl_packet_struct if packets else _opencl_struct,
        to_int=lambda expr: f"(int)({expr})",
        declare_parameters=lambda rows, fixed, flat_rows: _OPENCL_PARAMETERS,
        texels=_opencl_texels,
        real_dtype=np.dtype(dtype),
        entry="main_packet.cl" if packets else "main.cl",
        finish=thread_parameters,
        packets=packets,
    )


OPENCL = {"float32": _opencl("float", np.float32), "float64": _opencl("double", np.float64)}

OPENCL_PACKETS = {"float32": _opencl("float", np.float32, packets=True),
                  "float64": _opencl("double", np.float64, packets=True)}

DIALECTS = {"glsl": {"float32": GLSL}, "glsl-compute": {"float32": GLSL_COMPUTE},
            "opencl": OPENCL, "opencl-packets": OPENCL_PACKETS}


def dialect(name: str, precision: str = "float32") -> Dialect:
    """The dialect ``name`` (a key of `DIALECTS`) at ``precision`` ("float32", "float64")."""
    if name not in DIALECTS:
        raise KeyError(f"unknown shader dialect {name!r} (one of: {', '.join(DIALECTS)})")
    if precision not in DIALECTS[name]:
        raise KeyError(f"the {name} dialect has no {precision} version "
                       f"(one of: {', '.join(DIALECTS[name])})")
    return DIALECTS[name][precision]
