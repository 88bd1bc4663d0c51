"""The derived packet forms of the lights and the shading functions compute what the scalar ones do.

The packet program derives its functions from the one-ray program's (gpu_shader/
vectorise.py). Here every function of lights.glsl and shading.glsl and its packet form run
on the same inputs (tests/opencl/packet_twins.py) and must give the same bits, at both
precisions; tests/opencl/test_packet_march.py does the same for the marches and shadows.

The inputs are seeded random rows with the hard cases mixed in: light directions grazing a
surface and behind it, view directions on and near the mirror direction (R.V and N.H at 1),
shininess from 1 to 200, toon inputs on and beside the band edges, checker points on cell
boundaries, object ids -1..5 and path labels up to 2^24 - 1, points near a light and on its
cone's edges. What a scene fixes (a light's position, the number of toon bands) is a scalar
in the packet program, so those columns are the same for the LANES rows of a packet.

All functions go into one kernel per precision (one build for each form); each test checks
its function's columns of the shared run.
"""

from __future__ import annotations

import numpy as np
import pytest

# tests/opencl, on the path as the tests' folder
from packet_twins import LANES, Case, TwinCases, assert_bits_equal, need_precision
from twin_inputs import mix, near, normalised, per_packet, pick, units

SEED = 20240613
BLOCKS = 96                  # packets of LANES rows; the parameters change from one to the next
ROWS = BLOCKS * LANES
PRECISIONS = ["float32", "float64"]
MAX_DISTANCE = 50.0
NEAR = (-7, -3)              # `near`: a relative 1e-7..1e-3 off

# the scalar libraries whose packet forms are checked here (those of march, relaxed and
# shadow_pair by test_packet_march.py)
CHECKED = ["lights", "shading", "glass"]


# --- Inputs --------------------------------------------------------------------------------

def column(values) -> np.ndarray:
    return np.asarray(values, float).reshape(ROWS, 1)


def colours(rng) -> np.ndarray:
    return rng.uniform(0, 1, (ROWS, 3))


def surface_case(rng):
    """n, l, v: l random, grazing (within 1e-2 rad of the tangent plane, or in it), behind
    the surface; v random, on the mirror direction of l (R.V = 1, and H = N), or near it."""
    n = units(rng, ROWS)
    tangent = normalised(np.cross(n, units(rng, ROWS)))
    angle = rng.choice([-1.0, 1.0], (ROWS, 1)) * 10.0 ** rng.uniform(-6, -2, (ROWS, 1))
    grazing = normalised(tangent * np.cos(angle) + n * np.sin(angle))
    behind = normalised(-n + 0.5 * units(rng, ROWS))
    l = mix(rng, units(rng, ROWS), grazing, tangent, behind, n)
    mirror = 2.0 * (n * l).sum(axis=1, keepdims=True) * n - l
    v = mix(rng, units(rng, ROWS), mirror, normalised(mirror + 0.1 * units(rng, ROWS)),
            normalised(mirror + 1e-3 * units(rng, ROWS)),
            normalised(mirror + 1e-6 * units(rng, ROWS)),
            n, -l)                                          # -l: L + V = 0, no half vector
    return n, l, v


def diffuse_case(rng):
    n, l, _ = surface_case(rng)
    return [n, l]


def specular_case(rng):
    shininess = mix(rng, rng.uniform(1, 200, ROWS), rng.integers(1, 201, ROWS), 1.0, 200.0)
    return [*surface_case(rng), column(shininess)]


def toon_case(rng):
    bands = per_packet(pick(rng, [2.0, 3.0, 4.0, 5.0, 8.0], BLOCKS))
    k = rng.integers(0, 9, size=(ROWS, 1))
    edges = mix(rng, k / bands, (k + 0.9) / bands, (k + 1.0) / bands)   # q - level = 0, 0.9, 1
    x = mix(rng, rng.uniform(0, 1, (ROWS, 1)), edges, near(rng, edges, NEAR), 0.0, 1.0)
    return [np.clip(x, 0.0, 1.0), bands]


def interface_case(rng):
    """cos_i, eta, cos_t at a glass surface, entering and leaving: head-on, grazing (cos_i
    down to 0), at and near the critical angle (k = 0), and total reflection (cos_t 0)."""
    eta = mix(rng, rng.choice([1 / 1.5, 1.5, 1 / 1.33, 1.33, 1.0, 1 / 2.4], (ROWS, 1)),
              1 / 1.5, 1.5)
    critical = np.sqrt(np.clip(1 - 1 / eta ** 2, 0, 1))     # cos i where k = 0 (eta > 1)
    cos_i = mix(rng, rng.uniform(0, 1, (ROWS, 1)), critical, near(rng, critical, NEAR),
                1.0, 1e-6, 0.0)
    k = 1 - eta * eta * (1 - cos_i * cos_i)
    return cos_i, eta, np.sqrt(np.maximum(k, 0))


def refract_k_case(rng):
    cos_i, eta, _ = interface_case(rng)
    return [cos_i, eta]


def refract_direction_case(rng):
    cos_i, eta, cos_t = interface_case(rng)
    n = units(rng, ROWS)
    tangent = normalised(np.cross(n, units(rng, ROWS)))
    d = -cos_i * n + np.sqrt(1 - cos_i ** 2) * tangent       # meets n at cos_i
    return [d, n, cos_i, eta, cos_t]


def fresnel_case(rng):
    cos_i, eta, cos_t = interface_case(rng)
    n1 = mix(rng, rng.uniform(1, 2.5, (ROWS, 1)), 1.0, 1.5)
    # the 0 / 0 of cos_i = cos_t = 0 is the caller's to avoid (total reflection: F = 1)
    cos_i = np.where((cos_i == 0) & (cos_t == 0), 1e-3, cos_i)
    return [cos_i, cos_t, n1, n1 / eta]


def beer_lambert_case(rng):
    absorption = mix(rng, rng.uniform(0, 5, (ROWS, 3)), 0.0, rng.uniform(0, 1e3, (ROWS, 3)))
    distance = mix(rng, rng.uniform(0, 3, (ROWS, 1)), 0.0, MAX_DISTANCE)
    return [absorption, distance]


def checker_points(rng):
    scale = column(mix(rng, rng.uniform(0.2, 3.0, ROWS), 0.5, 1.0, 2.0, 0.3))
    p = rng.uniform(-10, 10, (ROWS, 3))
    on = rng.integers(-8, 9, size=(ROWS, 3)) * scale          # on cell boundaries
    p = mix(rng, p, on, near(rng, on, NEAR), np.zeros(3), -on)
    return p, scale


def checker_parity_case(rng):
    return list(checker_points(rng))


def checker_case(rng):
    p, scale = checker_points(rng)
    return [p, colours(rng), colours(rng), scale]


def path_case(rng):
    top = 2 ** 24 - 1
    path = mix(rng, rng.integers(0, top + 1, ROWS), 0, top)
    ids = rng.integers(-1, 6, ROWS)
    features = mix(rng, rng.integers(0, 64, ROWS), rng.integers(0, top + 1, ROWS), 0, top)
    return [column(path), column(ids), column(features)]


def normals_case(rng):
    n = units(rng, ROWS)
    axis = np.eye(3)[rng.integers(3, size=ROWS)] * rng.choice([-1.0, 1.0], (ROWS, 1))
    return [mix(rng, n, axis, np.zeros(3), -n * 0.0)]


def depth_case(rng):
    max_distance = per_packet(pick(rng, [MAX_DISTANCE, 20.0, 100.0], BLOCKS))
    t = mix(rng, rng.uniform(0, 120, (ROWS, 1)), -1.0, 0.0, max_distance,
            near(rng, max_distance, NEAR))
    return [t, max_distance]


def fog_case(rng):
    fog = per_packet(rng.uniform(0, 1, (BLOCKS, 3)))
    density = per_packet(pick(rng, [0.0, 0.01, 0.05, 0.2, 1.0], BLOCKS))
    t = mix(rng, rng.uniform(0, 100, (ROWS, 1)), rng.uniform(0, 1, (ROWS, 1)), 0.0, 1e3)
    return [colours(rng), t, fog, density]


def background_solid_case(rng):
    return [units(rng, ROWS), per_packet(rng.uniform(0, 1, (BLOCKS, 3)))]


def background_sky_case(rng):
    up = np.eye(3)[1] * rng.choice([-1.0, 1.0], (ROWS, 1))
    direction = mix(rng, units(rng, ROWS), up, normalised(units(rng, ROWS) * [1, 0, 1]))
    return [direction, per_packet(rng.uniform(0, 1, (BLOCKS, 3))),
            per_packet(rng.uniform(0, 1, (BLOCKS, 3)))]


def attenuation_k(rng) -> np.ndarray:
    k = np.stack([np.ones(BLOCKS), rng.uniform(0, 0.5, BLOCKS), rng.uniform(0, 0.1, BLOCKS)], 1)
    k[rng.integers(3, size=BLOCKS) == 0] = [1.0, 0.09, 0.032]
    k[rng.integers(4, size=BLOCKS) == 0] = [1.0, 0.0, 0.0]
    return per_packet(k)


def attenuation_case(rng):
    distance = mix(rng, rng.uniform(0, 100, (ROWS, 1)), rng.uniform(0, 1, (ROWS, 1)), 0.0)
    return [distance, attenuation_k(rng)]


def cones(rng) -> np.ndarray:
    """(cos outer, cos inner - cos outer) per packet, as the generator writes them."""
    outer = rng.uniform(10, 60, BLOCKS)
    inner = outer * rng.uniform(0.3, 0.95, BLOCKS)
    cos_outer, cos_inner = np.cos(np.radians(outer)), np.cos(np.radians(inner))
    return per_packet(np.stack([cos_outer, cos_inner - cos_outer], 1))


def spot_cone_case(rng):
    cone = cones(rng)
    edges = mix(rng, cone[:, :1], cone[:, :1] + cone[:, 1:])
    cos_theta = mix(rng, rng.uniform(-1, 1, (ROWS, 1)), edges, near(rng, edges, NEAR), 1.0)
    return [cos_theta, cone]


def light_directional_case(rng):
    return [per_packet(normalised(rng.normal(size=(BLOCKS, 3)))),
            per_packet(rng.uniform(0, 2, (BLOCKS, 3)))]


def light_points(rng):
    position = per_packet(rng.uniform(-5, 5, (BLOCKS, 3)))
    p = mix(rng, rng.uniform(-8, 8, (ROWS, 3)), position + 1e-3 * units(rng, ROWS),
            position + rng.uniform(10, 60, (ROWS, 1)) * units(rng, ROWS))
    return p, position, per_packet(rng.uniform(0, 2, (BLOCKS, 3))), attenuation_k(rng)


def light_point_case(rng):
    return list(light_points(rng))


def light_spot_case(rng):
    p, position, radiance, k = light_points(rng)
    axis = per_packet(normalised(rng.normal(size=(BLOCKS, 3))))
    cone = cones(rng)
    # points on the cone's edges: at angle theta from the axis, cos theta = cone x or x + y
    cos_edge = mix(rng, cone[:, :1], cone[:, :1] + cone[:, 1:])
    side = normalised(np.cross(axis, units(rng, ROWS)))
    sin_edge = np.sqrt(1.0 - cos_edge ** 2)
    on_edge = position + rng.uniform(0.5, 20, (ROWS, 1)) * (cos_edge * axis + sin_edge * side)
    p = mix(rng, p, on_edge, position + 3.0 * axis)
    return [p, position, radiance, k, axis, cone]


# --- The functions and how each is called ------------------------------------------------

CASES = [
    Case("lights", "attenuation", ("packet", "vec3"), "packet", attenuation_case),
    Case("lights", "spot_cone", ("packet", "vec2"), "packet", spot_cone_case),
    Case("lights", "light_directional", ("vec3", "vec3"), "LightSample",
         light_directional_case),
    Case("lights", "light_point", ("vec3p", "vec3", "vec3", "vec3"), "LightSample",
         light_point_case),
    Case("lights", "light_spot", ("vec3p", "vec3", "vec3", "vec3", "vec3", "vec2"),
         "LightSample", light_spot_case),
    Case("shading", "diffuse", ("vec3p", "vec3p"), "packet", diffuse_case),
    Case("shading", "specular_phong", ("vec3p", "vec3p", "vec3p", "packet"), "packet",
         specular_case),
    Case("shading", "specular_blinn_phong", ("vec3p", "vec3p", "vec3p", "packet"), "packet",
         specular_case),
    Case("shading", "toon_band", ("packet", "real"), "packet", toon_case),
    Case("shading", "stripes_band", ("packet", "real"), "packet", toon_case),
    Case("shading", "checker_parity", ("vec3p", "packet"), "packet", checker_parity_case),
    Case("shading", "checker", ("vec3p", "vec3p", "vec3p", "packet"), "vec3p", checker_case),
    Case("shading", "path_step", ("upacket", "ipacket", "upacket"), "upacket", path_case),
    Case("shading", "shade_normals", ("vec3p",), "vec3p", normals_case),
    Case("shading", "shade_depth", ("packet", "real"), "vec3p", depth_case),
    Case("shading", "apply_fog", ("vec3p", "packet", "vec3", "real"), "vec3p", fog_case),
    Case("shading", "background_solid", ("vec3p", "vec3"), "vec3p", background_solid_case),
    Case("shading", "background_sky", ("vec3p", "vec3", "vec3"), "vec3p",
         background_sky_case),
    Case("glass", "refract_k", ("packet", "packet"), "packet", refract_k_case),
    Case("glass", "refract_direction", ("vec3p", "vec3p", "packet", "packet", "packet"),
         "vec3p", refract_direction_case),
    Case("glass", "fresnel_exact", ("packet", "packet", "packet", "packet"), "packet",
         fresnel_case),
    Case("glass", "fresnel_schlick", ("packet", "packet", "packet", "packet"), "packet",
         fresnel_case),
    Case("glass", "beer_lambert", ("vec3p", "packet"), "vec3p", beer_lambert_case),
]
CASE_IDS = [case.name for case in CASES]

TWINS = TwinCases(CASES, SEED, ROWS, defines={"MAX_DISTANCE": MAX_DISTANCE}, structs=True)


# --- Tests --------------------------------------------------------------------------------

@pytest.mark.parametrize("library", CHECKED)
def test_every_function_of_the_library_is_checked_here(library):
    TWINS.assert_checks_all(library)


# Where the packet program calls a vector math function, PoCL's vector code is not its
# scalar code, and the two may round differently. Measured on PoCL 3.1 (pthread, AVX-512),
# on these inputs and on 64000 random (x, y) pairs more:
#
# - pow in float32, taken 4 lanes at a time (`power` in glsl/packet.cl says why): the same
#   bits, except where the result is subnormal (below 1.2e-38): there it may be one subnormal
#   step off (1.4e-45): 15 of the 64000 pairs, none of the rows here;
# - pow in float64, taken as 2^(y log2 x) (`power` again: PoCL's pow is seven times slower):
#   within 4.7e-14 of the scalar pow, relative, on the rows here, down to results of 4e-322,
#   and 0 exactly where pow is 0 (POW_RELATIVE_64 allows 1e-13);
# - exp, at every vector width: up to 1 ulp off in 0.5-8% of the cases, so apply_fog's
#   colour differs by up to 4 ulps in under 1% of its values, at most 6.0e-8 in float32
#   and 1.1e-16 in float64 (half an ulp of 1.0).
#
# Both are far below the colour gate the equivalence suite applies (1e-3 in float32), and
# neither touches what must agree exactly (hit masks, depths, path labels, shadow states).
POW = {"specular_phong", "specular_blinn_phong"}
EXP = {"apply_fog", "beer_lambert"}


POW_RELATIVE_64 = 1e-13


def assert_pow_close(got, expected, what):
    """float32: bit-equal where the scalar result is 0 or normal, one subnormal step off
    below. float64: 0 where it is 0, else within POW_RELATIVE_64 of it (relative)."""
    finfo = np.finfo(expected.dtype)
    if expected.dtype == np.float64:
        zero = expected == 0
        assert_bits_equal(got[zero], expected[zero], what)
        bound = POW_RELATIVE_64 * np.abs(expected) + finfo.smallest_subnormal
        assert (np.abs(got - expected) <= bound).all(), what
        return
    exact = (np.abs(expected) >= finfo.smallest_normal) | (expected == 0)
    assert_bits_equal(got[exact], expected[exact], what)
    assert np.abs(got - expected).max() <= finfo.smallest_subnormal, what


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
@pytest.mark.parametrize("precision", PRECISIONS)
def test_derived_packet_form_equals_scalar_function_to_the_bit(opencl_device, precision, case):
    need_precision(opencl_device, precision)
    expected, got = TWINS.results(opencl_device, precision, case.name)
    # the inputs reach more than one result (a constant would hide a wrong packet form), except
    # where a function's result is a parameter (light_directional: only the distance)
    varied = [len(np.unique(c)) > 1 for c in expected.T]
    assert all(varied) or case.name == "light_directional", case.name
    if case.name in POW:
        assert_pow_close(got, expected, case.name)
    elif case.name in EXP:
        # measured above: a few ulps of a colour in [0, 1], so within one ulp of 1.0
        assert np.abs(got - expected).max() <= np.finfo(expected.dtype).eps, case.name
        assert (got != expected).mean() < 0.05, case.name
    else:
        assert_bits_equal(got, expected, case.name)


@pytest.mark.parametrize("precision", PRECISIONS)
def test_the_specular_inputs_reach_the_hard_cases(opencl_device, precision):
    """Highlights at full strength, lights grazing or behind the surface (0), and values
    between: else a wrong power or a wrong N.L test could pass unnoticed."""
    need_precision(opencl_device, precision)
    for name in sorted(POW):
        values = TWINS.results(opencl_device, precision, name)[0][:, 0]
        assert (values == 0).mean() > 0.2, name
        assert (values > 0.99).sum() > 50, name
        assert ((values > 1e-3) & (values < 0.9)).sum() > 50, name
