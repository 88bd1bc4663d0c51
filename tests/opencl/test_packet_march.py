"""The derived packet marches and shadow rays compute what the scalar ones do, ray by ray, to the bit.

The packet program derives its march from glsl/march.glsl (or relaxed.glsl) and its shadow
rays from march.glsl and shadow_pair.glsl (gpu_shader/vectorise.py): the LANES rays of a
packet step together, and a ray that stops (hit, escaped, out of steps) leaves the mask of
the lanes still in the loop instead of the loop. Each ray must still go through exactly the
scalar sequence of points, so t, the step count, the hit flag and the shadow visibility must
equal the scalar program's at both precisions (tests/opencl/packet_twins.py runs both).

The scene is a sphere resting on a tilted plane beside a thin box (a relaxed step can jump
into or through it, so the march has to step back), written with the scalar building blocks
of glsl/sdf.glsl; its packet form is derived like the rest. The rays are seeded random rows
with the hard cases mixed in: grazing rays over the plane and past the sphere, rays starting
inside the solids, rays that run out of MAX_STEPS (far targets, 64 steps), rays that escape
at a small limit, hits just before and just after the limit, shadow rays from surface
points toward lights, and lanes outside the mask `live`, which the packet march must leave
alone. Every march runs once more with only 5 steps, so that most rays stop in mid-march,
after whatever kind of step came last.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.dialects import dialect
from gpu_shader.library import load_library
from reference_cpu.relaxation import SLOPE_WEIGHT

# tests/opencl, on the path as the tests' folder
from packet_twins import LANES, assert_bits_equal, derive, need_precision, run_twins
from twin_inputs import normalised, units

SEED = 20240612
PRECISIONS = ["float32", "float64"]
MAX_STEPS = 64
EPSILON = 1e-3
MAX_DISTANCE = 50.0
PENUMBRA_K = 8.0

# The scene: a unit sphere at (0, 1, 0) on the plane n . p = OFFSET (n = NORMAL normalised),
# and a thin box (half-extents BOX_SIZE) at BOX_CENTRE.
SPHERE_CENTRE, SPHERE_RADIUS = np.array([0.0, 1.0, 0.0]), 1.0
NORMAL, OFFSET = np.array([0.1, 1.0, 0.05]), -0.1
BOX_CENTRE, BOX_SIZE = np.array([2.5, 0.5, 0.0]), np.array([0.05, 1.0, 1.5])


def vec3(v) -> str:
    return "vec3({!r}, {!r}, {!r})".format(*map(float, v))


SCENE = f"""\
#define SPHERE_CENTRE {vec3(SPHERE_CENTRE)}
#define SPHERE_RADIUS {SPHERE_RADIUS!r}
#define NORMAL {vec3(NORMAL)}
#define OFFSET {OFFSET!r}
#define BOX_CENTRE {vec3(BOX_CENTRE)}
#define BOX_SIZE {vec3(BOX_SIZE)}
"""

SCALAR_SCENE = SCENE + """
real scene_sdf(vec3 p)
{
    real d = op_union(sdf_sphere(op_translate(p, SPHERE_CENTRE), SPHERE_RADIUS),
                      sdf_plane(p, NORMAL, OFFSET));
    return op_union(d, sdf_box(op_translate(p, BOX_CENTRE), BOX_SIZE));
}

// No culling in these tests: every ray sees every object.
uint ray_objects(vec3 origin, vec3 direction)
{
    return 0u;
}

real march_sdf(vec3 p, uint objects)
{
    return scene_sdf(p);
}
"""

# Columns: origin (3), direction (3), limit, live, then a second ray from the same origin for
# the shadow rays in pairs: direction (3), limit, and whether each ray of the pair is needed.
# The shadow functions take the first ray as (origin, to_light, light_distance). Outputs: t,
# steps, hit, hard, soft, and the two visibilities of hard_shadow_pair.
SCALAR_KERNEL = """
__kernel void twin(__global const real* in, __global real* out)
{
    vec3 origin = vec3(IN(0), IN(1), IN(2));
    vec3 direction = vec3(IN(3), IN(4), IN(5));
    real limit = IN(6);
    // A start that differs from ray to ray, as the cone pre-pass's do (glsl/cone.glsl).
    Hit hit = march(origin, direction, 0.05 * limit, limit, 0u);
    OUT(0, hit.t);
    OUT(1, (real)(hit.steps));
    OUT(2, (real)(hit.hit));
    OUT(3, hard_shadow(origin, direction, limit, 0u));
    OUT(4, soft_shadow(origin, direction, limit));
    vec2 pair = hard_shadow_pair(origin, direction, limit, IN(12) != 0.0,
                                 vec3(IN(8), IN(9), IN(10)), IN(11), IN(13) != 0.0, 0u);
    OUT(5, pair.x);
    OUT(6, pair.y);
}
"""

PACKET_KERNEL = """
__kernel void twin(__global const real* in, __global real* out)
{
    vec3p origin = pack3(IN(0), IN(1), IN(2));
    vec3p direction = pack3(IN(3), IN(4), IN(5));
    packet limit = IN(6);
    ipacket live = IN(7) != 0.0;
    Hit hit = march(origin, direction, 0.05 * limit, limit, 0u, live);
    OUT(0, hit.t);
    OUT(1, hit.steps);
    OUT(2, hit.hit);
    OUT(3, hard_shadow(origin, direction, limit, 0u, live));
    OUT(4, soft_shadow(origin, direction, limit, live));
    vec2p pair = hard_shadow_pair(origin, direction, limit, IN(12) != 0.0,
                                  pack3(IN(8), IN(9), IN(10)), IN(11), IN(13) != 0.0, 0u,
                                  live);
    OUT(5, pair.x);
    OUT(6, pair.y);
}
"""
OUTPUTS = 7
# The functions the kernels call, every argument varying (one value per ray), and the mask
# `live` that the packet forms take (they hold loops that rays leave at different times).
# The objects a ray leaves out (0u here: these scenes have no object bits) are one value.
ROOTS = {"march": (True,) * 4 + (False,), "hard_shadow": (True,) * 3 + (False,),
         "soft_shadow": (True,) * 3, "hard_shadow_pair": (True,) * 7 + (False,)}

# "plain": glsl/march.glsl; the relaxed marches replace its march and keep its shadow
# functions, as the generator puts them together (gpu_shader/generate.py, march_parts).
# Each runs with MAX_STEPS steps, and once more with SHORT steps, where most rays stop in
# mid-march: whatever kind of step (a relaxed one, one taken back, a plain one) came last.
VARIANTS = {
    "plain": ("march", {}),
    "relaxed-fixed": ("relaxed", {"RELAXATION_AUTO": 0, "OMEGA": 1.5}),
    "relaxed-auto": ("relaxed", {"RELAXATION_AUTO": 1, "SLOPE_WEIGHT": None}),
}
SHORT = 5
RUNS = [(variant, steps) for steps in (MAX_STEPS, SHORT) for variant in VARIANTS]
RUN_IDS = [f"{variant}-{steps}-steps" for variant, steps in RUNS]


def sources(variant: str, precision: str, packet: bool) -> str:
    """The scalar program of a variant, or its derived packet form, with its kernel."""
    library, _ = VARIANTS[variant]
    functions = "\n".join([
        load_library("sdf").select(["sdf_sphere", "sdf_plane", "sdf_box", "op_translate",
                                    "op_union"]),
        SCALAR_SCENE,
        load_library(library).select(["march"]),
        load_library("march").select(["hard_shadow", "soft_shadow"], provided={"march"}),
        load_library("shadow_pair").select(["hard_shadow_pair"])])
    if packet:
        functions, _ = derive(functions, ROOTS, defines=defines(variant, MAX_STEPS, precision))
    blocks = [dialect("opencl-packets" if packet else "opencl", precision).structs(), functions]
    return "\n".join(blocks + [PACKET_KERNEL if packet else SCALAR_KERNEL])


def defines(variant: str, max_steps: int, precision: str) -> dict:
    values = {"MAX_STEPS": max_steps, "EPSILON": EPSILON, "MAX_DISTANCE": MAX_DISTANCE,
              "PENUMBRA_K": PENUMBRA_K}
    for name, value in VARIANTS[variant][1].items():
        if name == "SLOPE_WEIGHT":
            value = dialect("opencl", precision).literal(SLOPE_WEIGHT)
        values[name] = value
    return values


# --- Rays ---------------------------------------------------------------------------------

def plane_distance(p) -> np.ndarray:
    return p @ (NORMAL / np.linalg.norm(NORMAL)) - OFFSET


def rays(rng, n=96) -> np.ndarray:
    """Rows (origin, direction, limit, live, direction_b, limit_b, need_a, need_b) of every
    kind, about n of each, shuffled; the second ray of a pair is another row's."""
    kinds = []
    uniform = lambda low, high: rng.uniform(low, high, (n, 3))          # noqa: E731
    # anywhere above the plane, in any direction
    origin = uniform([-6, 0.2, -6], [6, 4, 6])
    kinds.append((origin, units(rng, n), rng.uniform(1, 70, n)))
    # at the sphere, from afar: through it, and tangent to within +-2% of its radius
    origin = SPHERE_CENTRE + units(rng, n) * rng.uniform(3, 10, (n, 1))
    origin[:, 1] = np.abs(origin[:, 1]) + 0.5
    target = SPHERE_CENTRE + units(rng, n) * SPHERE_RADIUS
    miss = rng.uniform(-0.02, 0.02, (n, 1)) * normalised(target - SPHERE_CENTRE)
    kinds.append((origin, normalised(target + miss - origin), np.full(n, 40.0)))
    # at the thin box, edge-on and face-on: the relaxed march crosses it and steps back
    origin = uniform([-3, 0.2, -3], [-0.5, 2.5, 3])
    target = BOX_CENTRE + rng.uniform(-1, 1, (n, 3)) * BOX_SIZE * 1.05
    kinds.append((origin, normalised(target - origin), np.full(n, 30.0)))
    # grazing the plane toward far targets: slow convergence, many run out of MAX_STEPS
    origin = uniform([-5, 0.02, -5], [5, 0.5, 5])
    horizontal = normalised(np.hstack([rng.normal(size=(n, 1)), np.zeros((n, 1)),
                                       rng.normal(size=(n, 1))]))
    horizontal[:, 1] = -10.0 ** rng.uniform(-4, -1.5, n)
    kinds.append((origin, normalised(horizontal), np.full(n, 1e3)))
    # parallel to the plane, well above it, far target: steps of ~0.3-1, out of steps
    origin = uniform([-5, 0.3, 5], [5, 1.0, 8])
    direction = np.tile([0.0, 0.0, 1.0], (n, 1)) + rng.normal(size=(n, 3)) * [0.1, 0, 0.1]
    kinds.append((origin, normalised(direction) * [1, 0, 1] + [0, 0.01, 0], np.full(n, 1e3)))
    # starting inside the sphere, the box, or under the plane
    inside_sphere = SPHERE_CENTRE + units(rng, n) * rng.uniform(0, 0.95, (n, 1))
    inside_box = BOX_CENTRE + rng.uniform(-0.9, 0.9, (n, 3)) * BOX_SIZE
    under = uniform([-5, -1, -5], [5, -0.15, 5])
    origin = np.where(rng.integers(3, size=(n, 1)) == 0, inside_sphere,
                      np.where(rng.integers(2, size=(n, 1)) == 0, inside_box, under))
    kinds.append((origin, units(rng, n), rng.uniform(1, 60, n)))
    # upward, small limits: escape
    origin = uniform([-4, 2.5, -4], [4, 4, 4])
    direction = normalised(rng.normal(size=(n, 3)) * [1, 0.2, 1] + [0, 1, 0])
    kinds.append((origin, direction, rng.uniform(0.05, 5, n)))
    # straight at the plane, hit within a hair of the limit, before or after it
    origin = uniform([-6, 0.5, 3], [6, 5, 6])
    down = -NORMAL / np.linalg.norm(NORMAL)
    reach = plane_distance(origin)
    limit = reach * (1.0 + rng.choice([-1, 1], n) * 10.0 ** rng.uniform(-7, -3, n))
    kinds.append((origin, np.tile(down, (n, 1)), limit))
    # shadow rays: from plane and sphere points pushed off by 2 EPSILON, toward a light
    on_plane = uniform([-5, 0, -5], [5, 0, 5])
    on_plane -= (plane_distance(on_plane) - 2 * EPSILON)[:, None] * normalised(NORMAL[None])
    outward = units(rng, n)
    on_sphere = SPHERE_CENTRE + outward * (SPHERE_RADIUS + 2 * EPSILON)
    origin = np.where(rng.integers(2, size=(n, 1)) == 0, on_plane, on_sphere)
    light = uniform([-4, 3, -4], [4, 8, 4]) * rng.choice([1.0, 10.0], (n, 1))
    offset = light - origin
    distance = np.linalg.norm(offset, axis=1)
    kinds.append((origin, offset / distance[:, None], distance))

    rows = np.vstack([np.hstack([o, d, limit[:, None]]) for o, d, limit in kinds])
    rows = rows[rng.permutation(len(rows))]
    live = (rng.random(len(rows)) > 0.15).astype(float)
    live[:LANES] = 0.0                            # a whole packet off: the loop never runs
    live[LANES:2 * LANES] = 1.0
    other = rows[rng.permutation(len(rows))]
    needs = (rng.random((len(rows), 2)) > 0.2).astype(float)
    rows = np.hstack([rows, live[:, None], other[:, 3:7], needs])
    return rows[:len(rows) // LANES * LANES]


_RUNS: dict = {}


def run(device, variant: str, max_steps: int, precision: str):
    """Rows, scalar outputs and packet outputs of one march variant (built once per run)."""
    key = variant, max_steps, precision
    if key not in _RUNS:
        rows = rays(np.random.default_rng(SEED))
        scalar, packet = run_twins(device, precision, sources(variant, precision, False),
                                   sources(variant, precision, True), rows, outputs=OUTPUTS,
                                   defines=defines(variant, max_steps, precision))
        _RUNS[key] = rows, scalar, packet
    return _RUNS[key]


def each_run(test):
    """Parametrise ``test`` over every precision and every run (variant, max_steps)."""
    test = pytest.mark.parametrize("precision", PRECISIONS)(test)
    return pytest.mark.parametrize(("variant", "max_steps"), RUNS, ids=RUN_IDS)(test)


def live_run(device, precision: str, variant: str, max_steps: int):
    """Which rows are live, and the scalar and packet outputs of a run; skips the test
    where the device has no ``precision``."""
    need_precision(device, precision)
    rows, scalar, packet = run(device, variant, max_steps, precision)
    return rows[:, 7] != 0, scalar, packet


# --- Tests --------------------------------------------------------------------------------

@each_run
def test_packet_march_equals_scalar_march_to_the_bit_in_every_live_lane(
        opencl_device, precision, variant, max_steps):
    live, scalar, packet = live_run(opencl_device, precision, variant, max_steps)
    t, steps, hit = scalar[:, 0], scalar[:, 1], scalar[:, 2]
    # the rays reach every outcome: hits, escapes, out of steps, and long marches
    ran_out = live & (hit == 0) & (steps == max_steps)
    assert (live & (hit == 1)).sum() > 50
    assert (live & (hit == 0) & (steps < max_steps)).sum() > 50
    assert ran_out.sum() > (10 if max_steps == MAX_STEPS else 200)
    assert np.median(steps[live]) > (5 if max_steps == MAX_STEPS else 2)
    what = f"{variant}, {max_steps} steps"
    assert_bits_equal(packet[live, 0], t[live], f"{what}: t")
    np.testing.assert_array_equal(packet[live, 1], steps[live], err_msg=f"{what}: steps")
    np.testing.assert_array_equal(packet[live, 2], hit[live], err_msg=f"{what}: hit")


@each_run
def test_packet_shadows_equal_scalar_shadows_to_the_bit_in_every_live_lane(
        opencl_device, precision, variant, max_steps):
    live, scalar, packet = live_run(opencl_device, precision, variant, max_steps)
    hard, soft = scalar[:, 3], scalar[:, 4]
    assert (live & (hard == 0)).sum() > 50 and (live & (hard == 1)).sum() > 50
    assert (live & (soft > 0) & (soft < 1)).sum() > 50      # penumbrae, not just 0 and 1
    what = f"{variant}, {max_steps} steps"
    assert_bits_equal(packet[live, 3], hard[live], f"{what}: hard_shadow")
    assert_bits_equal(packet[live, 4], soft[live], f"{what}: soft_shadow")


@each_run
def test_shadow_rays_in_pairs_equal_their_scalar_form_in_every_live_lane(
        opencl_device, precision, variant, max_steps):
    live, scalar, packet = live_run(opencl_device, precision, variant, max_steps)
    pair = scalar[:, 5:7]
    for k in range(2):                  # each ray of the pair is blocked and visible somewhere
        assert (live & (pair[:, k] == 0)).sum() > 50 and (live & (pair[:, k] == 1)).sum() > 50
    assert_bits_equal(packet[live, 5:7], pair[live], f"{variant}, {max_steps} steps: pairs")


@each_run
def test_lanes_outside_live_are_never_stepped(opencl_device, precision, variant, max_steps):
    """The march leaves a lane outside its mask as the loop found it: t still at its start
    (the kernels start each ray at 0.05 of its limit, column 6) and the step counter at its
    first value, 1 (what the rest of the march makes of those is never read: callers take
    only their live lanes)."""
    need_precision(opencl_device, precision)
    rows, _, packet = run(opencl_device, variant, max_steps, precision)
    live = rows[:, 7] != 0
    off = ~live
    assert off.sum() > LANES                      # a whole packet, and lanes among live ones
    dtype = np.dtype(precision)
    start = dtype.type(0.05) * rows[off, 6].astype(dtype)
    np.testing.assert_array_equal(packet[off, 0], start)
    np.testing.assert_array_equal(packet[off, 1], 1.0)
    assert (packet[live, 0] != 0).mean() > 0.9


def test_relaxed_marches_take_other_steps_than_the_plain_one(opencl_device):
    """The relaxed variants are really relaxed here (else the tests above would check the
    plain loop three times): other step counts for many rays, fewer on average."""
    precision = "float64" if opencl_device.fp64 else "float32"
    rows, plain, _ = run(opencl_device, "plain", MAX_STEPS, precision)
    live = rows[:, 7] != 0
    for variant in ("relaxed-fixed", "relaxed-auto"):
        _, relaxed, _ = run(opencl_device, variant, MAX_STEPS, precision)
        assert (relaxed[live, 1] != plain[live, 1]).mean() > 0.3, variant
        assert relaxed[live, 1].mean() < plain[live, 1].mean(), variant
