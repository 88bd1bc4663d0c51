"""The packet program of a scene: its one-ray program, vectorised, around a packet entry point.

The opencl backend runs by default a program that traces LANES neighbouring pixels of a row
per work-item, every per-ray value an OpenCL vector (glsl/packet.cl says why). Nothing of it
is written twice: `gpu_shader.generate.scalar_program` writes the one-ray program of the
scene, `gpu_shader.vectorise` derives its packet form function by function, and this module
puts the program together in the order a reader meets it:

1. the packet prelude (the dialect's, with glsl/packet.cl), the parameters and their names;
2. the structs with a field per lane, and ``choose`` for each of them;
3. the vectorised functions, with the one-ray program's comments and section titles;
4. the entry point glsl/main_packet.cl, which calls the packet ``trace`` (with
   anti-aliasing, ``supersample``) with the mask of the lanes inside the image.
"""

from __future__ import annotations

from functools import lru_cache

from .dialects import Dialect, program_structs
from .library import fill_template
from .subset import format_program
from .subset_reader import parse
from .vectorise import vectorise

# How the packet entry point calls into the program: every argument a packet, and trace
# with the mask of the lanes inside the image.
ROOTS = {"trace": (True, True, True), "camera_ray": (True, True)}
LIVE_ROOTS = {"trace"}
# With the cone pre-pass, its kernel calls tile_start with a packet of tiles.
PREPASS_ROOTS = {"tile_start": (True, True)}
# With anti-aliasing the entry point calls supersample(x, y, start) instead of trace.
SAMPLES_ROOTS = {"supersample": (True, True, True)}
# A struct field of these types is picked lane by lane with `?:`; others with choose().
_NATIVE = {"real", "int", "uint", "bool"}


def packet_source(scalar, language: Dialect) -> str:
    """The whole packet program of ``scalar``.

    Parameters
    ----------
    scalar : gpu_shader.generate.ScalarProgram
        The one-ray program of the scene (its defines and functions).
    language : gpu_shader.dialects.Dialect
        The packet dialect ("opencl-packets") at the program's precision.

    Returns
    -------
    str
        OpenCL C, with the parameter buffer passed on to every function that reads it.
    """
    # The text depends only on the scene's structure, and a frame asks for it again: keep
    # it, as gpu_shader.opencl keeps the programs built from it.
    return _packet_source(scalar.defines, scalar.functions, scalar.path_labels,
                          max(1, len(scalar.parameters)) + _texel_rows(scalar), language,
                          bool(scalar.prepass_tile),
                          "glass" in scalar.features, scalar.supersampled)


@lru_cache(maxsize=32)
def _packet_source(defines: str, functions: str, path_labels: bool, rows: int,
                   language: Dialect, prepass: bool = False, glass: bool = False,
                   supersampled: bool = False) -> str:
    structs = program_structs(path_labels, glass)
    program = parse(defines + "\n" + functions, structs)
    roots = dict(ROOTS, **(PREPASS_ROOTS if prepass else {}),
                 **(SAMPLES_ROOTS if supersampled else {}))
    packet, _ = vectorise(program, structs, roots,
                          LIVE_ROOTS | (set(SAMPLES_ROOTS) if supersampled else set()))
    parts = [
        language.prelude,
        _banner("parameters: one vec4 row each, set per frame")
        + language.declare_parameters(rows, rows, 0)
        + "// How many rows P has: a lane's gather() never reads past them (glsl/packet.cl).\n"
        + f"#define PARAMETER_ROWS {rows}\n",
        _banner("structs: one value per lane in every field") + language.structs(
            path_labels, glass) + "\n" + choose_functions(structs),
        _banner("the one-ray program, vectorised (gpu_shader/vectorise.py)")
        + format_program(packet),
        _banner("the entry point (glsl/main_packet.cl)")
        + fill_template("main_packet.cl", path_labels=path_labels, prepass=prepass,
                        samples=supersampled),
    ]
    return language.finish("\n".join(parts))


def _texel_rows(scalar) -> int:
    """The rows of P after the parameters: the texture atlas's texels, which a lane's
    gather() may read too."""
    return 0 if scalar.texels is None else scalar.texels.shape[0] * scalar.texels.shape[1]


def choose_functions(structs: dict) -> str:
    """``choose(mask, a, b)`` for each struct: lane by lane, field by field."""
    functions = ["// Lane by lane: a where the mask is set, b elsewhere, field by field."]
    for name, fields in structs.items():
        lines = [f"{name} OVERLOAD choose(ipacket mask, {name} a, {name} b)", "{",
                 f"    {name} r;"]
        for type_, field in fields:
            pick = (f"mask ? a.{field} : b.{field}" if type_ in _NATIVE
                    else f"choose(mask, a.{field}, b.{field})")
            lines.append(f"    r.{field} = {pick};")
        functions.append("\n".join(lines + ["    return r;", "}", ""]))
    return "\n".join(functions)


def _banner(title: str) -> str:
    return f"// ---- {title} " + "-" * max(4, 86 - len(title)) + "\n\n"
