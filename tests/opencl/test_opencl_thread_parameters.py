"""`thread_parameters` (`gpu_shader.dialects`): the parameter buffer ``P`` passed to its readers.

OpenCL C 1.2 has no program-scope variables, so the rewrite adds ``PARAMETERS`` to every
function that reads ``P`` or ``U`` (directly, through a macro, or by calling such a function)
and passes ``P`` at each of its calls; pure functions, kernels and comments are left alone.
Checked on small hand-written sources and on the whole generated classroom program (plain
Python, never skipped).
"""

from __future__ import annotations

import re

import pytest

from gpu_shader.dialects import thread_parameters
from gpu_shader.generate import generate
import marchlab


def function(source: str, name: str) -> str:
    """The definition of ``name`` in ``source``, from its first line to its closing brace."""
    match = re.search(rf"^\w+ {name}\(.*?^\}}", source, re.M | re.S)
    assert match, f"no definition of {name} in:\n{source}"
    return match.group(0)


# eps reads P directly; scaled calls eps; shade calls scaled (two levels up). sdf_sphere is
# pure, and `render` is a kernel that declares PARAMETERS itself.
CHAIN = """\
real eps()
{
    return P[5].x;
}

real scaled(real x)
{
    return x * eps();
}

vec3 shade(vec3 p, real d)
{
    return p * scaled(d);
}

// Sphere: distance to the centre minus the radius.
real sdf_sphere(vec3 p, real radius)
{
    return length(p) - radius;
}

__kernel void render(PARAMETERS, __global vec4* restrict out)
{
    real d = sdf_sphere(vec3(0.0), 1.0);
    out[0] = vec4(shade(vec3(1.0), d), eps());
}
"""


def test_macro_reading_P_through_another_macro_counts_as_reading_P():
    source = """\
#define EPSILON P[5].x
#define TWO_EPSILON (2.0 * EPSILON)
real tolerance(real t)
{
    return TWO_EPSILON * t;
}
"""
    assert "real tolerance(PARAMETERS, real t)" in thread_parameters(source)


def test_function_reading_P_and_its_callers_transitively_get_PARAMETERS():
    threaded = thread_parameters(CHAIN)
    assert function(threaded, "eps").startswith("real eps(PARAMETERS)\n")
    assert function(threaded, "scaled").startswith("real scaled(PARAMETERS, real x)\n")
    assert function(threaded, "shade").startswith("vec3 shade(PARAMETERS, vec3 p, real d)\n")
    assert "return x * eps(P);" in threaded
    assert "return p * scaled(P, d);" in threaded


def test_pure_function_and_its_calls_are_unchanged():
    threaded = thread_parameters(CHAIN)
    assert function(threaded, "sdf_sphere") == function(CHAIN, "sdf_sphere")
    assert "real d = sdf_sphere(vec3(0.0), 1.0);" in threaded
    assert "PARAMETERS, vec3 p, real radius" not in threaded


def test_kernel_definition_is_kept_and_its_calls_pass_P():
    threaded = thread_parameters(CHAIN)
    kernel = threaded[threaded.index("__kernel"):]
    assert kernel.splitlines()[0] == "__kernel void render(PARAMETERS, __global vec4* restrict out)"
    assert "out[0] = vec4(shade(P, vec3(1.0), d), eps(P));" in kernel


@pytest.mark.parametrize("call", ["eps()", "eps( )"])
def test_call_of_a_zero_argument_function_becomes_f_of_P(call):
    source = CHAIN.replace("return x * eps();", f"return x * {call};")
    threaded = thread_parameters(source)
    assert "return x * eps(P);" in threaded
    assert "eps(P, " not in threaded


def test_macro_reading_P_makes_its_user_a_reader():
    """``#define EPSILON P[5].x``: a function that writes EPSILON reads P."""
    source = """\
#define EPSILON P[5].x
#define MATERIAL(id, row) U[40 + 3 * (id) + (row)]

int converged(real d)
{
    return d < EPSILON;
}

vec3 albedo(int id)
{
    return MATERIAL(id, 0).xyz;
}

int keep_going(real d)
{
    return !converged(d);
}

real twice(real x)
{
    return 2.0 * x;
}
"""
    threaded = thread_parameters(source)
    assert function(threaded, "converged").startswith("int converged(PARAMETERS, real d)\n")
    assert function(threaded, "albedo").startswith("vec3 albedo(PARAMETERS, int id)\n")
    assert "return !converged(P, d);" in threaded
    assert function(threaded, "twice") == function(source, "twice")
    assert threaded.startswith("#define EPSILON P[5].x\n#define MATERIAL(id, row) U[40")


def test_function_reading_U_gets_PARAMETERS():
    source = "vec3 albedo(int id)\n{\n    return U[40 + id].xyz;\n}\n"
    assert thread_parameters(source) == source.replace("(int id)", "(PARAMETERS, int id)")


def test_comments_mentioning_calls_are_unchanged():
    source = CHAIN.replace(
        "// Sphere: distance to the centre minus the radius.",
        "// Sphere: march( stops near it; see eps() and scaled(x).").replace(
        "return p * scaled(d);", "return p * scaled(d);  // like march(p, d) or eps()")
    threaded = thread_parameters(source)
    assert "// Sphere: march( stops near it; see eps() and scaled(x)." in threaded
    assert "return p * scaled(P, d);  // like march(p, d) or eps()" in threaded


def test_source_that_never_reads_P_is_returned_unchanged():
    source = function(CHAIN, "sdf_sphere") + "\n\nreal twice(real x)\n{\n    return 2.0 * x;\n}\n"
    assert thread_parameters(source) == source


def test_comment_naming_a_parameter_does_not_make_a_pure_function_read_P():
    source = """\
#define EPSILON P[5].x

real sdf_sphere(vec3 p, real radius)
{
    // The march stops within EPSILON of this surface, see converged().
    return length(p) - radius;
}
"""
    assert thread_parameters(source) == source


def test_call_with_a_space_before_the_parenthesis_passes_P():
    source = CHAIN.replace("return x * eps();", "return x * eps ();")
    threaded = thread_parameters(source)
    assert "real scaled(PARAMETERS, real x)" in threaded
    assert re.search(r"eps\s*\(P\)", threaded)


def test_generated_opencl_threads_P_through_every_reader():
    """In the whole classroom program, every function that names P or a P macro takes it."""
    program = generate(marchlab.load_scene("classroom"), 32, 24, dialect="opencl")
    source = program.source
    macros = set(re.findall(r"^#define\s+(\w+)(?:\([^)]*\))?\s+.*\bP\[", source, re.M))
    reads = re.compile(r"\bP\[|" + "|".join(rf"\b{m}\b" for m in macros))
    definitions = re.finditer(r"^(\w+) (\w+)\(([^)]*)\)\n\{\n(.*?)^\}", source, re.M | re.S)
    checked = 0
    for match in definitions:
        body = "\n".join(line.partition("//")[0] for line in match.group(4).splitlines())
        if reads.search(body):
            assert match.group(3).startswith("PARAMETERS"), match.group(2)
            checked += 1
    assert checked >= 5 and "__kernel void render(PARAMETERS," in source
