"""The translator that derives the packet program keeps every lane equal to the one-ray program.

gpu_shader/vectorise.py rewrites a one-ray function for LANES rays at once (whole-function
vectorisation: Karrenberg and Hack, "Whole-function vectorization", CGO 2011). Each device
test here writes a small one-ray function around one construct the translation must get
right (a return under an ``if`` whose condition differs from ray to ray, a loop that rays
leave at different steps, ``continue`` and ``return`` inside a loop, a parameter row read
with a per-ray index), runs it and its derived packet form on the same seeded inputs
(tests/opencl/packet_twins.py) and checks every lane against the one-ray result, to the bit.
The tests without a device check what stays scalar, which functions take the mask ``live``,
that a construct outside the subset is named in its error, and that writing a program read
from text gives text that reads back the same.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from packet_twins import LANES, assert_bits_equal, derive, need_precision, run_twins

import marchlab
from gpu_shader.dialects import dialect
from gpu_shader.generate import scalar_program
from gpu_shader.library import GLSL_DIR
from gpu_shader.packets import LIVE_ROOTS, ROOTS, packet_source, program_structs
from gpu_shader.subset import SubsetError, format_program
from gpu_shader.subset_reader import parse, preprocess
from gpu_shader.vectorise import vectorise
from scene_model.scene import rendered_scene

SEED = 20240614
PRECISIONS = ["float32", "float64"]
ROWS = 64 * LANES


# How the calls of `twins` spell what differs between the kernels: a conversion to int, and
# the mask `live` (every lane) that a packet function with a loop rays leave takes.
SPELLING = {"scalar": {"int": "(int)", "live": ""},
            "packet": {"int": "convert_ipacket", "live": ", (ipacket)(-1)"}}


def twins(device, precision, functions: str, roots: dict, calls: list, inputs, **options):
    """Scalar and packet outputs of ``calls`` (one expression per output column, written
    over ``IN(c)`` with ``{int}`` and ``{live}`` for what `SPELLING` spells per kernel)
    around ``functions`` and their packet form."""
    need_precision(device, precision)
    packet_functions, _ = derive(functions, roots)
    head = "__kernel void twin({}__global const real* in, __global real* out)\n{{\n".format(
        "PARAMETERS, " if "parameters" in options else "")
    kernels = {form: head + "".join(f"    OUT({k}, {call.format(**spelling)});\n"
                                    for k, call in enumerate(calls)) + "}\n"
               for form, spelling in SPELLING.items()}
    return run_twins(device, precision, f"{functions}\n{kernels['scalar']}",
                     f"{packet_functions}\n{kernels['packet']}", inputs, len(calls), **options)


# --- A return under a varying if --------------------------------------------------------------

PIECEWISE = """
real piecewise(real x)
{
    if (x < -1.0) {
        return -x * 2.0;
    }
    real y = x * x;
    if (y > 0.25) {
        if (x > 0.0) {
            return sqrt(y) + 1.0;
        }
        y = y * 3.0;
    } else {
        y = -y;
    }
    return y + x;
}
"""


def piecewise_path(x):
    """Which of the four ways out of `piecewise` each x takes (as NumPy computes it)."""
    return np.select([x < -1.0, (x * x > 0.25) & (x > 0.0), x * x > 0.25], [0, 1, 2], 3)


@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_return_under_a_varying_if_gives_every_lane_its_scalar_result(opencl_device,
                                                                         precision):
    rng = np.random.default_rng(SEED)
    x = np.where(rng.random(ROWS) < 0.8, rng.uniform(-3, 3, ROWS),
                 rng.choice([-1.0, -0.5, 0.0, 0.5, 1.0], ROWS))
    scalar, packet = twins(opencl_device, precision, PIECEWISE, {"piecewise": (True,)},
                           ["piecewise(IN(0))"], x[:, None])
    paths = piecewise_path(x).reshape(-1, LANES)
    assert set(np.unique(paths)) == {0, 1, 2, 3}
    assert (paths.min(axis=1) != paths.max(axis=1)).mean() > 0.9     # mixed in a packet
    assert_bits_equal(packet, scalar, "piecewise")


# --- A loop that lanes leave at different steps ----------------------------------------------

LEAVE = """
// Grow x until it passes 10: how many steps that took (60 if it never did), and x then.
vec2 leave(real x, real growth)
{
    int n;
    for (n = 0; n < 60; n++) {
        if (x > 10.0) {
            break;
        }
        x = x * growth + 0.25;
    }
    return vec2(real(n), x);
}
"""


@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_loop_with_a_varying_break_stops_each_lane_at_its_own_step(opencl_device,
                                                                     precision):
    rng = np.random.default_rng(SEED + 1)
    x = rng.uniform(0.01, 12.0, ROWS)
    growth = np.where(rng.random(ROWS) < 0.9, rng.uniform(1.01, 3.0, ROWS),
                      rng.uniform(0.5, 1.0, ROWS))                    # some never leave
    scalar, packet = twins(opencl_device, precision, LEAVE + "\n", {"leave": (True, True)},
                           ["leave(IN(0), IN(1){live}).x", "leave(IN(0), IN(1){live}).y"],
                           np.stack([x, growth], 1))
    steps = scalar[:, 0]
    assert len(np.unique(steps)) > 20 and (steps == 0).any() and (steps == 60).any()
    per_packet = steps.reshape(-1, LANES)
    assert (per_packet.min(axis=1) != per_packet.max(axis=1)).all()
    assert_bits_equal(packet, scalar, "leave")


CONTINUE_RETURN = """
// Sum the positive values of a sequence, folding negative ones back (continue), until one
// passes 50 (return, the sum with it) or 40 steps went by.
real sum_until(real x, real scale)
{
    real total = 0.0;
    for (int k = 0; k < 40; k++) {
        x = x * scale - 0.7;
        if (x < 0.0) {
            x = -x;
            continue;
        }
        if (x > 50.0) {
            return total + x;
        }
        total = total + x;
    }
    return total;
}
"""


@pytest.mark.parametrize("precision", PRECISIONS)
def test_continue_and_return_in_a_loop_act_lane_by_lane(opencl_device, precision):
    rng = np.random.default_rng(SEED + 2)
    rows = np.stack([rng.uniform(-2, 2, ROWS), rng.uniform(0.5, 1.6, ROWS)], 1)
    scalar, packet = twins(opencl_device, precision, CONTINUE_RETURN,
                           {"sum_until": (True, True)}, ["sum_until(IN(0), IN(1){live})"], rows)
    sums = scalar[:, 0].reshape(-1, LANES)
    assert (sums.min(axis=1) != sums.max(axis=1)).all() and (scalar > 50).any()
    assert_bits_equal(packet, scalar, "sum_until")


# --- Rows of the parameters read per lane --------------------------------------------------------

GATHER = """
#define ROW(id, k) U[2 + 2 * (id) + (k)]

real row_value(int id)
{
    return ROW(id, 1).y + ROW(id, 0).w * ROW(id, 1).x;
}
"""


@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_varying_row_index_reads_each_lanes_row(opencl_device, precision):
    rng = np.random.default_rng(SEED + 3)
    table = rng.normal(size=(2 + 2 * 7, 4))
    ids = rng.integers(0, 7, ROWS).astype(float)
    scalar, packet = twins(opencl_device, precision, GATHER, {"row_value": (True,)},
                           ["row_value({int}(IN(0)))"], ids[:, None], parameters=table)
    assert len(np.unique(scalar)) == 7
    assert_bits_equal(packet, scalar, "row_value")


@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_lane_whose_row_is_outside_the_table_reads_the_nearest_row(opencl_device,
                                                                     precision):
    """A ray that hit nothing has object id -1; its lane's gather must not read outside
    the buffer (it reads the first or last row, and the program never uses the value)."""
    need_precision(opencl_device, precision)
    rng = np.random.default_rng(SEED + 4)
    table = rng.normal(size=(6, 4))
    ids = rng.choice([-5, -2, -1, 0, 1, 2, 40], ROWS).astype(float)
    packet_functions, _ = derive(GATHER, {"row_value": (True,)})
    kernel = ("__kernel void twin(PARAMETERS, __global const real* in, __global real* out)\n"
              "{\n    OUT(0, %s);\n}\n")
    _, packet = run_twins(opencl_device, precision, kernel % "0.0",
                          packet_functions + kernel % "row_value(convert_ipacket(IN(0)))",
                          ids[:, None], 1, parameters=table)
    row = lambda k: table[np.clip(2 + 2 * ids.astype(int) + k, 0, len(table) - 1)]  # noqa: E731
    dtype = packet.dtype
    expected = (row(1)[:, 1].astype(dtype) + row(0)[:, 3].astype(dtype)
                * row(1)[:, 0].astype(dtype))
    assert_bits_equal(packet[:, 0], expected, "clamped rows")


# --- What the translation keeps scalar, and who takes `live` ----------------------------------

@pytest.fixture(scope="module")
def classroom():
    """The classroom scene's one-ray program, its packet form (text) and the analysis."""
    scalar = scalar_program(rendered_scene(marchlab.load_scene("classroom")), 64, 48,
                            path_labels=True)
    structs = program_structs(True)
    program = parse(scalar.defines + scalar.functions, structs)
    _, analysis = vectorise(program, structs, ROOTS, LIVE_ROOTS)
    return packet_source(scalar, dialect("opencl-packets", "float32")), analysis


def function_text(source: str, name: str) -> str:
    match = re.search(rf"^\w+ {name}\(.*?^}}", source, re.M | re.S)
    assert match, name
    return match.group()


def test_values_the_same_for_every_ray_stay_scalar(classroom):
    source, analysis = classroom
    assert "packet sdf_sphere(vec3p p, real radius)" in source
    assert "    vec3 n = normal / sqrt(dot(normal, normal));" in function_text(source, "sdf_plane")
    assert "    real h = NORMAL_STEP;" in function_text(source, "estimate_normal")
    trace = function_text(source, "trace")
    assert "for (int bounce = 0; bounce <= REFLECTION_DEPTH && any(looping" in trace
    assert re.search(r"if \(bounce == 0\) \{", trace)                 # a plain branch
    assert re.search(r"ipacket then\d+ = looping\d+ & \(h\.hit == 0\);", trace)  # a mask
    light = analysis.functions["light_point"]
    assert [p.varying for p in light.parameters] == [True, False, False, False]


def test_functions_that_loop_until_each_ray_is_done_take_the_mask_live(classroom):
    source, analysis = classroom
    takes_live = {name for name, info in analysis.functions.items() if info.needs_live}
    assert {"march", "shade_phong", "trace"} <= takes_live
    assert not {"scene_sdf", "sdf_sphere", "estimate_normal", "camera_ray",
                "surface_albedo"} & takes_live
    for name in takes_live:
        assert re.search(rf"^\w+ {name}\([^)]*ipacket live\)", source, re.M), name


def test_a_row_gathered_more_than_once_is_read_once(classroom):
    shade = function_text(classroom[0], "shade_phong")
    assert shade.count("MATERIAL(id, 1)") == 1
    assert shade.count("material_id_1.") == 3                          # kd, ks, shininess


# --- The subset: errors and round trips ------------------------------------------------------------

@pytest.mark.parametrize("source, construct", [
    ("real f(real x)\n{\n    while (x > 1.0) {\n        x = x / 2.0;\n    }\n    return x;\n}\n",
     "while"),
    ("real f(real x)\n{\n    real a[4];\n    return x;\n}\n", "arrays"),
    ("real f(real x)\n{\n    g(x);\n    return x;\n}\n", "declare or assign"),
])
def test_a_construct_outside_the_subset_is_an_error_naming_it_and_its_line(source, construct):
    with pytest.raises(SubsetError, match=rf"line [34]: .*{construct}"):
        parse(source)


def test_a_function_no_root_reaches_is_left_out_with_its_comment():
    """Its packet form would be derived from no call: a scalar function the packet prelude
    cannot compile (reflect of a vec3) is not written at all."""
    program = parse("// Called by f.\nreal g(real x)\n{\n    return x * 2.0;\n}\n\n"
                    "// Called by nobody.\nvec3 h(vec3 d, vec3 n)\n{\n    return reflect(d, n);\n}\n\n"
                    "real f(real x)\n{\n    return g(x);\n}\n")
    text = format_program(vectorise(program, {}, {"f": (True,)})[0])
    assert "packet g(packet x)" in text and "// Called by f." in text
    assert "h(" not in text and "Called by nobody" not in text


def test_a_call_of_an_unknown_function_is_an_error_naming_it():
    program = parse("real f(real x)\n{\n    return mystery(x);\n}\n")
    with pytest.raises(SubsetError, match="unknown function 'mystery'"):
        vectorise(program, {}, {"f": (True,)})


LIBRARIES = ["sdf", "culling", "camera", "march", "lights", "shading", "shadow_pair", "texture",
             "environment"]


@pytest.mark.parametrize("name", LIBRARIES + ["relaxed", "classroom", "environment-scene",
                                               "textures-scene"])
def test_a_program_written_back_reads_back_the_same(name):
    if name.endswith("-scene"):           # their texture atlas read through TEXEL
        scalar = scalar_program(marchlab.load_scene(name[:-len("-scene")]), 64, 48)
        text = scalar.defines + scalar.functions
    elif name == "classroom":
        scalar = scalar_program(rendered_scene(marchlab.load_scene(name)), 64, 48)
        text = scalar.defines + scalar.functions
    else:
        text = (GLSL_DIR / f"{name}.glsl").read_text()
        text = "#define RELAXATION_AUTO 1\n" + text if name == "relaxed" else text
    structs = program_structs(False)
    once = format_program(parse(text, structs))
    assert format_program(parse(once, structs)) == once
    functions = re.findall(r"^\w+ (\w+)\(", text, re.M)
    assert re.findall(r"^\w+ (\w+)\(", once, re.M) == functions
    words = lambda t: re.findall(r"\w+", re.sub(r"//[^\n]*", "", t))   # noqa: E731
    assert words(once) == words(preprocess(text))        # only layout and parentheses change
