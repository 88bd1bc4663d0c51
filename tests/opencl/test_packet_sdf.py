"""The derived packet forms of the distance functions, culling and camera compute what the scalar ones do.

The packet program (docs/opencl-backend.md) traces LANES rays per work-item; its functions
are derived from the one-ray program's (gpu_shader/vectorise.py). A packet image equals the
one-ray image only if each derived function computes, lane by lane, the same operations in
the same order as its scalar function, so here the building blocks of sdf.glsl, culling.glsl
and camera.glsl and their packet forms run on the same inputs (tests/opencl/packet_twins.py)
and must agree to the bit, at both precisions.

The inputs are seeded random rows with the hard cases mixed in: points on and near each
surface, on the axes and coordinate planes, at zero, far away (~1e3); distances that are
equal, opposite, zero or a blend width apart; coordinates on repeat-cell boundaries and
periods of 0. What a scene fixes (a radius, a period) is a scalar in the packet program, so
those columns are the same for the LANES rows of a packet and change from packet to packet.

To keep the file fast, every function goes into one kernel per precision (one build for each
form); each test then checks its function's columns of the shared run.
"""

from __future__ import annotations

import numpy as np
import pytest
from packet_twins import LANES, Case, TwinCases, assert_bits_equal, need_precision
from twin_inputs import mix, near, per_packet, pick, units

from scene_model.builder import Camera
from scene_model.camera import camera_basis

SEED = 20240611
BLOCKS = 128                 # packets of LANES rows; the parameters change from one to the next
ROWS = BLOCKS * LANES
PRECISIONS = ["float32", "float64"]
NEAR = (-7, -2)              # `near`: a relative 1e-7..1e-2 off, just inside and just outside

# the scalar libraries whose packet forms are checked here
LIBRARIES = ["sdf", "culling", "camera"]


# --- Inputs --------------------------------------------------------------------------------

def anywhere(rng, scale=1.0) -> np.ndarray:
    """Points of every kind: random at two scales, far away, zero, on an axis, on a
    coordinate plane, on the half-integer grid (exact cell boundaries of period 1)."""
    normal = rng.normal(size=(ROWS, 3)) * scale
    axis = np.eye(3)[rng.integers(3, size=ROWS)]
    grid = rng.integers(-4, 5, size=(ROWS, 3)) + rng.choice([0.0, 0.5], size=(ROWS, 3))
    return mix(rng, normal, normal * 0.01, rng.uniform(-1e3, 1e3, (ROWS, 3)), np.zeros(3),
               normal * axis, normal * (1.0 - axis), grid * scale, -grid * scale)


def on_surface(rng, anywhere_points, surface_points) -> np.ndarray:
    """Half anywhere, half on the surface or within a hair of it."""
    return mix(rng, anywhere_points, surface_points, near(rng, surface_points, NEAR),
               surface_points, near(rng, surface_points, NEAR))


def distances(rng) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of distances: random, equal, opposite, zero (either sign), far."""
    d1 = mix(rng, rng.normal(size=ROWS), rng.normal(size=ROWS) * 0.01,
             rng.uniform(-1e3, 1e3, ROWS), 0.0, -0.0, 1.0)
    other = rng.normal(size=ROWS)
    d2 = mix(rng, other, d1, -d1, 0.0, -0.0, other * 1e3)
    return d1, d2


def box_faces(rng, b) -> np.ndarray:
    """Points on the faces, edges and corners of the box with half-extents b (per row)."""
    q = rng.uniform(-1, 1, (ROWS, 3)) * b
    face = rng.integers(3, size=ROWS)
    q[np.arange(ROWS), face] = rng.choice([-1.0, 1.0], size=ROWS) * b[np.arange(ROWS), face]
    corners = rng.choice([-1.0, 1.0], size=(ROWS, 3)) * b
    return mix(rng, q, q, corners)


def cell_boundaries(rng, period, count=None) -> np.ndarray:
    """x = period (n + 1/2), where floor(x / period + 1/2) steps, for n inside and beyond
    the limited range -count..count, and cell centres x = period n."""
    n = rng.integers(-6, 6, size=period.shape) if count is None else (
        np.round(count) + rng.integers(-2, 3, size=period.shape))
    n = n * rng.choice([-1.0, 1.0], size=period.shape)
    return mix(rng, period * (n + 0.5), period * n, near(rng, period * (n + 0.5), NEAR))


# --- Each function's inputs: one (ROWS, width) array per argument -----------------------

def sphere_case(rng):
    radius = per_packet(mix(rng, rng.uniform(0.1, 3.0, BLOCKS), 1.0, 0.5))
    p = on_surface(rng, anywhere(rng), units(rng, ROWS) * radius)
    return [p, radius]


def box_case(rng):
    b = per_packet(rng.uniform(0.1, 2.0, (BLOCKS, 3)))
    return [on_surface(rng, anywhere(rng), box_faces(rng, b)), b]


def round_box_case(rng):
    b = rng.uniform(0.1, 2.0, (BLOCKS, 3))
    radius = b.min(axis=1) * mix(rng, rng.uniform(0, 1, BLOCKS), 0.0, 1.0)
    b, radius = per_packet(b), per_packet(radius)
    return [on_surface(rng, anywhere(rng), box_faces(rng, b)), b, radius]


def plane_case(rng):
    axis = np.eye(3)[rng.integers(3, size=BLOCKS)]
    axis = axis * pick(rng, [1.0, 2.0, -1.0], BLOCKS)[:, None]
    normal = mix(rng, rng.normal(size=(BLOCKS, 3)) * 2.0, axis)
    offset = mix(rng, rng.uniform(-2, 2, BLOCKS), 0.0)
    normal, offset = per_packet(normal), per_packet(offset)
    p = anywhere(rng)
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    on = p - ((p * unit).sum(axis=1, keepdims=True) - offset) * unit
    return [on_surface(rng, p, on), normal, offset]


def torus_case(rng):
    major = rng.uniform(0.5, 3.0, BLOCKS)
    minor = major * rng.uniform(0.05, 0.9, BLOCKS)
    major, minor = per_packet(major), per_packet(minor)
    theta, phi = rng.uniform(0, 2 * np.pi, (2, ROWS, 1))
    ring = major + minor * np.cos(phi)
    on = np.hstack([ring * np.cos(theta), minor * np.sin(phi), ring * np.sin(theta)])
    centre_circle = np.hstack([major * np.cos(theta), 0 * theta, major * np.sin(theta)])
    p = mix(rng, on_surface(rng, anywhere(rng), on), centre_circle)
    return [p, major, minor]


def cylinder_case(rng):
    radius = per_packet(rng.uniform(0.1, 2.0, BLOCKS))
    half = per_packet(rng.uniform(0.1, 2.0, BLOCKS))
    theta = rng.uniform(0, 2 * np.pi, (ROWS, 1))
    side = np.hstack([radius * np.cos(theta), rng.uniform(-1, 1, (ROWS, 1)) * half,
                      radius * np.sin(theta)])
    r = radius * rng.uniform(0, 1, (ROWS, 1))
    cap = np.hstack([r * np.cos(theta), rng.choice([-1.0, 1.0], (ROWS, 1)) * half,
                     r * np.sin(theta)])
    rim = np.hstack([radius, rng.choice([-1.0, 1.0], (ROWS, 1)) * half, 0 * radius])
    return [on_surface(rng, anywhere(rng), mix(rng, side, cap, rim)), radius, half]


def capsule_case(rng):
    a = rng.normal(size=(BLOCKS, 3))
    b = mix(rng, rng.normal(size=(BLOCKS, 3)), a + np.eye(3)[1])
    radius = rng.uniform(0.05, 1.0, BLOCKS)
    a, b, radius = per_packet(a), per_packet(b), per_packet(radius)
    t = mix(rng, rng.uniform(-0.5, 1.5, (ROWS, 1)), 0.0, 1.0)
    axis_points = a + t * (b - a)
    on = axis_points + radius * units(rng, ROWS)
    p = mix(rng, on_surface(rng, anywhere(rng), on), axis_points, a, b)
    return [p, a, b, radius]


def cone_case(rng):
    radius = per_packet(rng.uniform(0.2, 2.0, BLOCKS))
    height = per_packet(mix(rng, rng.uniform(0.2, 3.0, BLOCKS), 1.0))
    theta = rng.uniform(0, 2 * np.pi, (ROWS, 1))
    y = height * rng.uniform(0, 1, (ROWS, 1))
    r = radius * (1.0 - y / height)
    slant = np.hstack([r * np.cos(theta), y, r * np.sin(theta)])
    r = radius * rng.uniform(0, 1, (ROWS, 1))
    base = np.hstack([r * np.cos(theta), 0 * r, r * np.sin(theta)])
    apex = np.hstack([0 * height, height, 0 * height])
    on_axis = np.hstack([0 * height, height * rng.uniform(-1, 2, (ROWS, 1)), 0 * height])
    p = mix(rng, on_surface(rng, anywhere(rng), mix(rng, slant, base, apex)), on_axis)
    return [p, radius, height]


def pyramid_case(rng):
    base = per_packet(mix(rng, rng.uniform(0.2, 3.0, BLOCKS), 1.0))
    height = per_packet(mix(rng, rng.uniform(0.05, 3.0, BLOCKS), 1.0))
    s = base / 2
    # The +x face (x = s (1 - v), y = h v, z = s (1 - v) u), its edges and apex, the base and
    # a base corner; then mirrored and swapped onto the other faces.
    u = mix(rng, rng.uniform(-1, 1, (ROWS, 1)), 1.0, -1.0, 0.0)
    v = mix(rng, rng.uniform(0, 1, (ROWS, 1)), 0.0, 1.0)
    face = np.hstack([s * (1 - v), height * v, s * (1 - v) * u])
    bottom = np.hstack([s * rng.uniform(-1, 1, (ROWS, 1)), 0 * s,
                        s * rng.uniform(-1, 1, (ROWS, 1))])
    surface = mix(rng, face, bottom, np.hstack([s, 0 * s, s]))
    surface[:, [0, 2]] *= rng.choice([-1.0, 1.0], (ROWS, 2))
    swap = rng.random(ROWS) < 0.5
    surface[swap] = surface[swap][:, [2, 1, 0]]
    # below the base, where the base square is nearest
    below = np.hstack([s * rng.uniform(-2, 2, (ROWS, 1)), -s * rng.uniform(0, 1, (ROWS, 1)),
                       s * rng.uniform(-2, 2, (ROWS, 1))])
    return [mix(rng, on_surface(rng, anywhere(rng), surface), below), base, height]


def disk_case(rng):
    radius = rng.uniform(0.1, 2.0, BLOCKS)
    thickness = 2 * radius * mix(rng, rng.uniform(0.01, 1, BLOCKS), 1.0)   # 1.0: a sphere
    radius, thickness = per_packet(radius), per_packet(thickness)
    return [disk_points(rng, radius, thickness), radius, thickness]


def disk_points(rng, radius, thickness):
    """Flat faces, the rounded rim, the flat circle's rim and its centre."""
    a, rounding = radius - thickness / 2, thickness / 2
    theta, phi = rng.uniform(0, 2 * np.pi, (2, ROWS, 1))
    phi = (phi - np.pi) / 2                                 # -pi/2..pi/2: the outer half
    rho = a + rounding * np.cos(phi)
    rim = np.hstack([rho * np.cos(theta), rounding * np.sin(phi), rho * np.sin(theta)])
    r = a * rng.uniform(0, 1, (ROWS, 1))
    flat = np.hstack([r * np.cos(theta), rng.choice([-1.0, 1.0], (ROWS, 1)) * rounding,
                      r * np.sin(theta)])
    core = np.hstack([a * np.cos(theta), 0 * a, a * np.sin(theta)])
    return mix(rng, on_surface(rng, anywhere(rng), mix(rng, rim, flat)), core, 0.0)


def hex_prism_case(rng):
    apothem = per_packet(rng.uniform(0.1, 2.0, BLOCKS))
    half_length = per_packet(rng.uniform(0.1, 2.0, BLOCKS))
    # the top side y = apothem, its corners, the caps; turned about z by k 60 degrees
    half_side = apothem / np.sqrt(3)
    top = np.hstack([half_side * mix(rng, rng.uniform(-1, 1, (ROWS, 1)), 1.0, -1.0), apothem,
                     half_length * mix(rng, rng.uniform(-1, 1, (ROWS, 1)), 1.0, -1.0)])
    cap = np.hstack([apothem * rng.uniform(-1, 1, (ROWS, 2)) * 0.8,
                     half_length * rng.choice([-1.0, 1.0], (ROWS, 1))])
    angle = rng.integers(0, 6, (ROWS, 1)) * (np.pi / 3)
    c, s = np.cos(angle), np.sin(angle)
    side = np.hstack([c * top[:, :1] - s * top[:, 1:2], s * top[:, :1] + c * top[:, 1:2],
                      top[:, 2:]])
    return [on_surface(rng, anywhere(rng), mix(rng, side, cap)), apothem, half_length]


def distance_pair_case(rng):
    d1, d2 = distances(rng)
    return [d1[:, None], d2[:, None]]


def smooth_case(rng):
    k = per_packet(mix(rng, rng.uniform(0.05, 1.0, BLOCKS), 0.5, 1.0))
    d1, d2 = distances(rng)
    sign = rng.choice([-1.0, 1.0], size=ROWS)
    # d2 - d1 = +-k and d1 + d2 = +-k: h exactly at 0 or 1, the ends of the blend
    d2 = mix(rng, d2, d1 + sign * k[:, 0], sign * k[:, 0] - d1)
    return [d1[:, None], d2[:, None], k]


def morph_case(rng):
    """t per packet: random in [0, 1], the ends 0 and 1, and 1/2 (the id rule's switch)."""
    t = per_packet(mix(rng, rng.uniform(0.0, 1.0, BLOCKS), 0.0, 1.0, 0.5))
    d1, d2 = distances(rng)
    return [d1[:, None], d2[:, None], t]


def translate_case(rng):
    offset = per_packet(mix(rng, rng.normal(size=(BLOCKS, 3)), 0.0))
    p = anywhere(rng)
    return [mix(rng, p, offset, -offset), offset]


def rotate_case(rng):
    rotations = [np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(BLOCKS)]
    rotations = np.stack(rotations)
    special = rng.integers(3, size=BLOCKS)
    rotations[special == 0] = np.eye(3)
    rotations[special == 1] = np.eye(3)[[1, 2, 0]]
    columns = [per_packet(rotations[:, :, j]) for j in range(3)]
    return [anywhere(rng), *columns]


def scale_case(rng):
    factor = per_packet(mix(rng, rng.uniform(0.1, 5.0, BLOCKS), 1.0, 2.0, 0.5, 3.0))
    return [anywhere(rng), factor]


PERIODS = [0.0, 0.5, 1.0, 2.0, 0.3, 1.7]
COUNTS = [0.0, 1.0, 2.0, 3.0, 5.0]


def periods(rng, shape=BLOCKS) -> np.ndarray:
    """Periods per packet (per axis): 0 (no repetition), exact and inexact binary fractions,
    and random ones."""
    return np.where(rng.random(shape) < 0.75, pick(rng, PERIODS, shape),
                    rng.uniform(0.1, 5.0, shape))


def repeat_axis_case(rng):
    period = per_packet(periods(rng))
    x = mix(rng, rng.normal(size=(ROWS, 1)) * 5, cell_boundaries(rng, period), 0.0,
            rng.uniform(-1e3, 1e3, (ROWS, 1)))
    return [x, period]


def repeat_case(rng):
    period = per_packet(periods(rng, (BLOCKS, 3)))
    p = mix(rng, anywhere(rng), cell_boundaries(rng, period))
    return [p, period]


def repeat_axis_limited_case(rng):
    period = per_packet(periods(rng))
    count = per_packet(pick(rng, COUNTS, BLOCKS))
    x = mix(rng, rng.normal(size=(ROWS, 1)) * 5, cell_boundaries(rng, period, count),
            cell_boundaries(rng, period), 0.0, rng.uniform(-1e3, 1e3, (ROWS, 1)))
    return [x, period, count]


def repeat_limited_case(rng):
    period = per_packet(periods(rng, (BLOCKS, 3)))
    count = per_packet(pick(rng, COUNTS, (BLOCKS, 3)))
    p = mix(rng, anywhere(rng), cell_boundaries(rng, period, count),
            cell_boundaries(rng, period))
    return [p, period, count]


def culling_case(rng):
    centre = mix(rng, rng.normal(size=(BLOCKS, 3)) * 2, 0.0)
    radius = mix(rng, rng.uniform(0.1, 2.0, BLOCKS), 1.0)
    sphere = per_packet(np.hstack([centre, radius[:, None]]))
    centre, radius = sphere[:, :3], sphere[:, 3:]
    u, v = units(rng, ROWS), units(rng, ROWS)
    v = v - (v * u).sum(axis=1, keepdims=True) * u             # v perpendicular to u
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    on = centre + radius * u
    # tangent: from a point of the tangent line through `on`, along v, back or away
    tangent_origin = on + rng.uniform(-3, 3, (ROWS, 1)) * v
    origin = mix(rng, anywhere(rng, 3.0), on, near(rng, on, NEAR), centre,
                 centre + radius * 0.5 * u, tangent_origin)
    towards = centre - origin
    norm = np.linalg.norm(towards, axis=1, keepdims=True)
    towards_unit = np.where(norm > 0, towards / np.where(norm > 0, norm, 1.0),
                            units(rng, ROWS))
    axis = np.eye(3)[rng.integers(3, size=ROWS)] * rng.choice([-1.0, 1.0], (ROWS, 1))
    direction = mix(rng, units(rng, ROWS), towards_unit, -towards_unit, v, -v, axis)
    return [origin, direction, sphere]


# The camera of the camera_ray case: odd sizes, a tilted view, as in the real program the
# basis and half extents are parameters (here macros with the same values in both forms).
CAMERA = Camera(position=(1.0, 2.0, 5.0), look_at=(0.2, -0.3, 0.0), fov=55.0)
CAMERA_SIZE = (33, 21)


def camera_defines() -> dict:
    forward, right, up = camera_basis(CAMERA)
    width, height = CAMERA_SIZE
    half_height = float(np.tan(np.radians(CAMERA.fov) / 2))
    vec = lambda v: "vec3({!r}, {!r}, {!r})".format(*map(float, v))     # noqa: E731
    return {"IMAGE_WIDTH": f"((real)({width}))", "IMAGE_HEIGHT": f"((real)({height}))",
            "HALF_WIDTH": f"((real)({half_height * width / height!r}))",
            "HALF_HEIGHT": f"((real)({half_height!r}))",
            "CAMERA_FORWARD": vec(forward), "CAMERA_RIGHT": vec(right), "CAMERA_UP": vec(up)}


def camera_case(rng):
    width, height = CAMERA_SIZE
    rows, columns = np.mgrid[0:height, 0:width]
    centres = np.stack([columns.ravel() + 0.5, rows.ravel() + 0.5], axis=1)
    anywhere_ = rng.uniform(0, 1, (ROWS, 2)) * [width, height]
    edges = rng.choice([0.0, 1.0], (ROWS, 2)) * [width, height]
    grid = centres[rng.integers(len(centres), size=ROWS)]
    xy = mix(rng, anywhere_, edges, grid)
    xy[:len(centres)] = centres                                  # every pixel centre once
    return [xy[:, :1], xy[:, 1:]]


# --- The functions and how each is called ------------------------------------------------

CASES = [
    Case("sdf", "length2", ("packet", "packet"), "packet", distance_pair_case),
    Case("sdf", "sdf_sphere", ("vec3p", "real"), "packet", sphere_case),
    Case("sdf", "sdf_box", ("vec3p", "vec3"), "packet", box_case),
    Case("sdf", "sdf_round_box", ("vec3p", "vec3", "real"), "packet", round_box_case),
    Case("sdf", "sdf_plane", ("vec3p", "vec3", "real"), "packet", plane_case),
    Case("sdf", "sdf_torus", ("vec3p", "real", "real"), "packet", torus_case),
    Case("sdf", "sdf_capped_cylinder", ("vec3p", "real", "real"), "packet", cylinder_case),
    Case("sdf", "sdf_capsule", ("vec3p", "vec3", "vec3", "real"), "packet", capsule_case),
    Case("sdf", "sdf_cone", ("vec3p", "real", "real"), "packet", cone_case),
    Case("sdf", "sdf_pyramid", ("vec3p", "real", "real"), "packet", pyramid_case),
    Case("sdf", "sdf_disk", ("vec3p", "real", "real"), "packet", disk_case),
    Case("sdf", "sdf_hex_prism", ("vec3p", "real", "real"), "packet", hex_prism_case),
    *[Case("sdf", name, ("packet", "packet"), "packet", distance_pair_case)
      for name in ("op_union", "op_intersection", "op_subtraction")],
    *[Case("sdf", name, ("packet", "packet", "real"), "packet", smooth_case)
      for name in ("op_smooth_union", "op_smooth_subtraction", "op_smooth_intersection")],
    Case("sdf", "op_morph", ("packet", "packet", "real"), "packet", morph_case),
    Case("sdf", "op_translate", ("vec3p", "vec3"), "vec3p", translate_case),
    Case("sdf", "op_rotate", ("vec3p", "vec3", "vec3", "vec3"), "vec3p", rotate_case),
    Case("sdf", "op_scale", ("vec3p", "real"), "vec3p", scale_case),
    Case("sdf", "repeat_axis", ("packet", "real"), "packet", repeat_axis_case),
    Case("sdf", "op_repeat", ("vec3p", "vec3"), "vec3p", repeat_case),
    Case("sdf", "repeat_axis_limited", ("packet", "real", "real"), "packet",
         repeat_axis_limited_case),
    Case("sdf", "op_repeat_limited", ("vec3p", "vec3", "vec3"), "vec3p", repeat_limited_case),
    Case("culling", "ray_meets_sphere", ("vec3p", "vec3p", "vec4"), "mask", culling_case),
    Case("camera", "camera_ray", ("packet", "packet"), "vec3p", camera_case),
]
CASE_IDS = [case.name for case in CASES]

TWINS = TwinCases(CASES, SEED, ROWS, defines=camera_defines())


# --- Tests --------------------------------------------------------------------------------

@pytest.mark.parametrize("library", LIBRARIES)
def test_every_function_of_the_library_is_checked_here(library):
    TWINS.assert_checks_all(library)


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
@pytest.mark.parametrize("precision", PRECISIONS)
def test_derived_packet_form_equals_scalar_function_to_the_bit(opencl_device, precision, case):
    need_precision(opencl_device, precision)
    expected, got = TWINS.results(opencl_device, precision, case.name)
    # the inputs reach more than one result (a constant would hide a wrong packet form)
    assert all(len(np.unique(column)) > 1 for column in expected.T), case.name
    assert_bits_equal(got, expected, case.name)
