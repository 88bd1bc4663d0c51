"""The small table of what differs between the C-like shading languages marchlab generates.

The building blocks (``glsl/*.glsl``) and the generated code are written in a common subset:
types ``real`` and ``vec3``, constructors ``vec3(...)``, no ``out`` parameters, structs only
declared here. A dialect says how to spell the few things that differ: the prelude that gives
``real`` and ``vec3`` their meaning, struct declarations, number literals, conversions and the
parameter array. GLSL is the only dialect so far; OpenCL C is meant to be one more entry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

# Structs shared by every dialect: name -> ((type, field), ...).
STRUCTS = {
    "Hit": (("real", "t"), ("int", "steps"), ("int", "hit")),
    "LightSample": (("vec3", "to_light"), ("real", "distance"), ("vec3", "radiance")),
}


@dataclass(frozen=True)
class Dialect:
    """How one language spells the parts that differ."""
    name: str
    prelude: str                                  # first lines of every program
    struct: Callable[[str, tuple], str]           # a struct declaration
    to_real: Callable[[str], str]                 # int expression -> real
    to_int: Callable[[str], str]                  # real expression -> int
    declare_parameters: Callable[[int, int], str] # how the program receives U and P
    real_dtype: np.dtype                          # precision of `real`

    def literal(self, value: float) -> str:
        """A number literal that reads back as exactly ``value`` rounded to `real`."""
        return np.format_float_positional(self.real_dtype.type(value), unique=True, trim="0")

    def structs(self) -> str:
        return "\n".join(self.struct(name, fields) for name, fields in STRUCTS.items())


def _glsl_struct(name: str, fields) -> str:
    body = "".join(f"    {type_} {field};\n" for type_, field in fields)
    return f"struct {name}\n{{\n{body}}};\n"


# Above this many rows a per-pixel copy would cost more than it saves (and a GPU would spill
# the array out of its registers): large scenes read everything from the uniform buffer.
MAX_PRIVATE_ROWS = 256


def _glsl_parameters(rows: int, fixed: int) -> str:
    if fixed > MAX_PRIVATE_ROWS:
        return f"""\
layout(std140) uniform Parameters
{{
    vec4 U[{rows}];
}};

// {fixed} rows are read with fixed indices: too many to copy per pixel (more than
// {MAX_PRIVATE_ROWS}), so P is the uniform buffer itself.
#define P U

void load_parameters()
{{
}}
"""
    return f"""\
layout(std140) uniform Parameters
{{
    vec4 U[{rows}];
}};

// The first {fixed} rows, read with fixed indices (camera, settings, SDF tree, lights), are
// copied once per pixel into the private array P. llvmpipe re-reads and bounds-checks a
// uniform buffer at every use, which made the march loop three times slower; a GPU keeps
// a private array read with constant indices in registers. Materials, read by object id,
// stay in U.
vec4 P[{fixed}];

void load_parameters()
{{
    for (int i = 0; i < {fixed}; i++) {{
        P[i] = U[i];
    }}
}}
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
""",
    struct=_glsl_struct,
    to_real=lambda expr: f"float({expr})",
    to_int=lambda expr: f"int({expr})",
    declare_parameters=lambda rows, fixed: _glsl_parameters(rows, fixed),
    real_dtype=np.dtype(np.float32),
)

DIALECTS = {"glsl": GLSL}
