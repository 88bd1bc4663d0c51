"""Over-relaxed sphere tracing (reference_cpu.relaxation) against analytic answers.

The rules (docs/scene-format.md, "Faster marching") change how long a step is, never where a
ray may stop: a step of omega r that leaves a gap between the empty spheres of two
consecutive points (r_prev + r < s) is taken back to the plain step r_prev, and that point
decides nothing. So a relaxed ray must hit where a plain ray hits, stopping within epsilon of
the surface and at most epsilon / |cos theta| short of it (test_march.py derives the bound).
It may take fewer evaluations, and on a surface seen at a grazing angle it does: on a plane
at elevation alpha each fixed step keeps the fraction 1 - omega sin(alpha) of the height
instead of 1 - sin(alpha), so the count falls to about 1 / omega of plain, as long as the
spheres overlap (omega (1 + sin alpha) <= 2; hard_cases/test_grazing_floor.py checks the
exact counts); "auto" reaches omega ~ 2 / (1 + sin alpha), about half.

Where the overlap test matters: a slab thinner than a relaxed step (but thicker than
epsilon) in front of a far wall. A naive over-relaxed march (t += omega f, no overlap test)
jumps over the slab and converges on the wall; the real march takes the step back and hits
the slab.

The tests at the end pin a defect this suite found and the contract now handles: a step that
lands *inside* a solid exactly along the surface normal (a ray meeting a wall head-on, or
radial in a sphere) satisfies r_prev + r = s exactly and passes the overlap test; the sign
change of the distance now takes it back. The iteration cap with relaxation is in
hard_cases/test_iteration_cap.py.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from test_march import CENTRE, RADIUS, ray_sphere, rays_toward_sphere, unit

from gpu_shader.generate import generate
from marchlab import render
from reference_cpu import relaxation as relaxation_module
from reference_cpu.march import march
from reference_cpu.scene_sdf import build_scene_sdf
from required_backends import need_backend
from scene_model.builder import Camera, RenderSettings, Scene, box, plane, sphere

EPSILON = 1e-3
RELAXED = [("fixed", 1.2), ("fixed", 1.5), ("fixed", 1.9), ("auto", 1.2)]
IDS = [f"{mode}-{omega}" if mode == "fixed" else mode for mode, omega in RELAXED]
SLACK = {np.dtype("float64"): 1e-12, np.dtype("float32"): 2e-6}   # rounding of t ~ 6


@pytest.fixture(params=["float64", "float32"])
def dtype(request):
    return np.dtype(request.param)


# --- where relaxed rays stop ----------------------------------------------------------------

@pytest.mark.parametrize("mode, omega", RELAXED, ids=IDS)
def test_relaxed_rays_hit_a_sphere_where_plain_rays_do_within_epsilon_over_cos(dtype, mode,
                                                                              omega):
    rng = np.random.default_rng(21)
    origins, directions = rays_toward_sphere(rng, 4000)
    t_exact, closest = ray_sphere(origins, directions, CENTRE, RADIUS)
    sdf = build_scene_sdf([sphere(RADIUS).at(*CENTRE)], dtype)
    o, d = origins.astype(dtype), directions.astype(dtype)
    _, _, plain_hit = march(o, d, sdf, 512, EPSILON, 100.0)
    t, _, hit = march(o, d, sdf, 512, EPSILON, 100.0, relaxation=mode, omega=omega)

    # Same hit mask outside the tangent band (measured: identical inside it too).
    tangent = np.abs(closest - RADIUS) <= 2 * EPSILON
    assert tangent.sum() >= 5 and hit.sum() >= 1000
    np.testing.assert_array_equal(hit[~tangent], plain_hit[~tangent])
    np.testing.assert_array_equal(hit[~tangent], np.isfinite(t_exact)[~tangent])

    # Within epsilon of the surface, and at most epsilon / cos(theta) short, never past it:
    # a step that lands inside leaves r_prev + r < s and is taken back.
    p = origins[hit] + t[hit, None].astype(np.float64) * directions[hit]
    assert np.all(np.abs(np.linalg.norm(p - CENTRE, axis=1) - RADIUS) < EPSILON + SLACK[dtype])
    enters = hit & np.isfinite(t_exact)
    normal = unit(origins[enters] + t_exact[enters, None] * directions[enters] - CENTRE)
    cos_theta = np.abs(np.einsum("ij,ij->i", normal, directions[enters]))
    short = t_exact[enters] - t[enters]
    assert np.all(short >= -SLACK[dtype])
    assert np.all(short <= EPSILON / cos_theta + SLACK[dtype])


@pytest.mark.parametrize("mode, omega", RELAXED, ids=IDS)
def test_float32_and_float64_relaxed_marches_agree_within_2_epsilon(mode, omega):
    """Same hits outside the tangent band; both stop within [t* - eps / cos, t*], so they
    differ by less than eps / cos + float32 rounding (measured: < 1.0 eps / cos)."""
    rng = np.random.default_rng(22)
    origins, directions = rays_toward_sphere(rng, 3000)
    t_exact, closest = ray_sphere(origins, directions, CENTRE, RADIUS)
    runs = {}
    for dtype in (np.float64, np.float32):
        sdf = build_scene_sdf([sphere(RADIUS).at(*CENTRE)], dtype)
        runs[dtype] = march(origins.astype(dtype), directions.astype(dtype), sdf, 512,
                            EPSILON, 100.0, relaxation=mode, omega=omega)
    (t64, _, hit64), (t32, _, hit32) = runs[np.float64], runs[np.float32]
    clear = np.abs(closest - RADIUS) > 2 * EPSILON
    np.testing.assert_array_equal(hit64[clear], hit32[clear])
    both = hit64 & hit32 & np.isfinite(t_exact)
    normal = unit(origins[both] + t_exact[both, None] * directions[both] - CENTRE)
    cos_theta = np.abs(np.einsum("ij,ij->i", normal, directions[both]))
    assert np.all(np.abs(t64[both] - t32[both]) <= EPSILON / cos_theta + 2e-6)


# --- fewer evaluations at grazing angles ---------------------------------------------------

@pytest.mark.parametrize("mode, omega, ratio", [("fixed", 1.2, 0.853), ("fixed", 1.5, 0.687),
                                                ("fixed", 1.9, 0.546), ("auto", 1.2, 0.62)],
                         ids=["fixed-1.2", "fixed-1.5", "fixed-1.9", "auto"])
def test_relaxation_takes_fewer_evaluations_on_a_grazing_floor(dtype, mode, omega, ratio):
    """Rays from height 1 at 0.5 to 3 degrees below the horizon (where even omega = 1.9
    keeps the spheres overlapping). Each ray's count against plain is at most ``ratio``:
    1/omega + 0.02 for fixed (measured 0.837, 0.667, 0.526), 0.62 for auto (measured
    0.543 in float64, 0.578 in float32); total ratios 0.83, 0.66, 0.52 and 0.53-0.55."""
    alpha = np.radians(np.linspace(0.5, 3.0, 200))
    directions = np.column_stack([np.cos(alpha), -np.sin(alpha), np.zeros_like(alpha)])
    origin = np.array([0.0, 1.0, 0.0], dtype)
    sdf = build_scene_sdf([plane()], dtype)
    _, plain, _ = march(origin, directions.astype(dtype), sdf, 100_000, EPSILON, 1e4)
    _, steps, hit = march(origin, directions.astype(dtype), sdf, 100_000, EPSILON, 1e4,
                          relaxation=mode, omega=omega)
    assert hit.all() and plain.min() >= 100
    assert np.all(steps <= ratio * plain)


def test_on_direct_sphere_hits_fixed_relaxation_costs_one_step_and_auto_saves():
    """Seen from 3-6 radii away, a sphere is reached head-on enough that the first fixed step
    overshoots it, is taken back, and omega stays 1 for the rest of the ray: every hit costs
    exactly one more evaluation than plain, at any omega (measured: +1 on every ray that
    hits, at most +1 on any of the 4000 rays). auto starts at omega = 1 and never takes more
    than plain here (measured: 22% fewer evaluations in total)."""
    rng = np.random.default_rng(21)
    origins, directions = rays_toward_sphere(rng, 4000)
    sdf = build_scene_sdf([sphere(RADIUS).at(*CENTRE)])
    _, plain, plain_hit = march(origins, directions, sdf, 512, EPSILON, 100.0)
    for omega in (1.2, 1.5, 1.9):
        _, steps, hit = march(origins, directions, sdf, 512, EPSILON, 100.0,
                              relaxation="fixed", omega=omega)
        extra = steps.astype(int) - plain
        assert np.all(extra[hit & plain_hit] == 1) and extra.max() == 1
    _, steps, _ = march(origins, directions, sdf, 512, EPSILON, 100.0, relaxation="auto")
    assert np.all(steps <= plain) and steps.sum() <= 0.8 * plain.sum()


# --- the overlap test at work ----------------------------------------------------------------

SLAB_NEAR, SLAB_WIDTH, WALL = 1.0, 1 / 64, 3.0       # binary fractions: exact arithmetic


def slab_and_wall():
    """A slab 1/64 thick (16 epsilon, far less than a relaxed step of ~1) from z = 1 to
    1.015625, 10 across, and the solid z >= 3 behind it."""
    return [box(5.0, 5.0, SLAB_WIDTH / 2).at(0.0, 0.0, SLAB_NEAR + SLAB_WIDTH / 2),
            plane((0.0, 0.0, -1.0), -WALL)]


def naive_over_relaxed_march(origin, directions, sdf, omega, steps=200):
    """t += omega f(o + t d) with no overlap test (signed f, so a step into a solid comes
    back out); a hit where |f| < epsilon."""
    t = np.zeros(len(directions))
    done = np.zeros(len(directions), dtype=bool)
    for _ in range(steps):
        f = sdf(origin + t[:, None] * directions)[0]
        done |= np.abs(f) < EPSILON
        t = np.where(done, t, t + omega * f)
    return t, done


@pytest.mark.parametrize("omega", [1.5, 1.9])
def test_overlap_test_keeps_a_thin_slab_that_a_naive_relaxed_march_jumps_over(omega):
    angles = np.radians(np.linspace(0, 40, 41))
    directions = np.column_stack([np.sin(angles), np.zeros_like(angles), np.cos(angles)])
    origin = np.zeros(3)
    sdf = build_scene_sdf(slab_and_wall())
    t_slab, t_wall = SLAB_NEAR / np.cos(angles), WALL / np.cos(angles)

    naive_t, naive_hit = naive_over_relaxed_march(origin, directions, sdf, omega)
    assert naive_hit.all()
    np.testing.assert_allclose(naive_t, t_wall, atol=EPSILON / np.cos(angles).min())

    t, _, hit = march(origin, directions, sdf, 1000, EPSILON, 100.0, relaxation="fixed",
                      omega=omega)
    assert hit.all()
    short = t_slab - t
    assert np.all((short >= 0) & (short < EPSILON / np.cos(angles)))


def test_taken_back_steps_count_as_evaluations():
    """Head-on at the slab with omega = 1.5: step 1 at t = 0 sees r = 1 and steps to 1.5,
    behind the slab; step 2 there sees r = 0.484375 (to the slab's back face), and
    1 + 0.484375 < 1.5: taken back to t = 1; step 3 sees r = 0, a hit. Three evaluations,
    all counted, where plain marching needs two."""
    calls = []
    sdf = build_scene_sdf(slab_and_wall())

    def counting_sdf(p):
        calls.append(len(p))
        return sdf(p)

    origin, direction = np.zeros(3), np.array([[0.0, 0.0, 1.0]])
    t, steps, hit = march(origin, direction, counting_sdf, 100, EPSILON, 100.0,
                          relaxation="fixed", omega=1.5)
    assert hit[0] and t[0] == SLAB_NEAR and steps[0] == 3 == len(calls)
    calls.clear()
    t, steps, hit = march(origin, direction, counting_sdf, 100, EPSILON, 100.0)
    assert hit[0] and t[0] == SLAB_NEAR and steps[0] == 2 == len(calls)


def test_auto_omega_stays_between_1_and_2(monkeypatch):
    """omega = 2 / (1 - clamp(m, -1, 0)) lies in [1, 2] whatever the measured slope m, which
    leaves [-1, 0] where the distance grows along the ray (measured: m from -1 to 0.99 on
    these rays, omega from 1 to 2 exactly): the clamp is needed."""
    omegas, slopes = [], []
    original = relaxation_module.Relaxation.step

    def recording_step(self, t, r):
        result = original(self, t, r)
        omegas.append(self.omega.copy())
        slopes.append(self.slope.copy())
        return result

    monkeypatch.setattr(relaxation_module.Relaxation, "step", recording_step)
    rng = np.random.default_rng(23)
    origins, directions = rays_toward_sphere(rng, 500)
    scene = [sphere(RADIUS).at(*CENTRE), plane(), *slab_and_wall(),
             sphere(0.5).at(2, 1, 0).smooth_union(box(0.4).at(2.8, 1, 0), k=2.0)]
    for dtype in (np.float64, np.float32):
        sdf = build_scene_sdf(scene, dtype)
        march(origins.astype(dtype), directions.astype(dtype), sdf, 300, EPSILON, 50.0,
              relaxation="auto")
        march(CENTRE.astype(dtype), directions.astype(dtype), sdf, 300, EPSILON, 50.0,
              relaxation="auto")                                   # from inside the sphere
    omega, slope = np.concatenate(omegas), np.concatenate(slopes)
    assert np.all((omega >= 1) & (omega <= 2))
    assert omega.max() > 1.9 and (omega == 1).any()
    assert slope.min() < -1 or slope.max() > 0              # the clamp does something


# --- the shader generator ---------------------------------------------------------------------

def small_scene(**render_settings):
    return Scene(objects=(plane(), sphere(1.0).at(0, 1, 0)),
                 render=RenderSettings(**render_settings))


@pytest.mark.parametrize("dialect", ["glsl", "opencl"])
def test_plain_programs_hold_no_relaxation_code(dialect):
    program = generate(small_scene(), 32, 24, dialect=dialect)
    assert "RELAXATION_AUTO" not in program.source and "OMEGA" not in program.source
    assert "last_step" not in program.source
    assert not [f for f in program.features if f.startswith("relaxation")]


@pytest.mark.parametrize("dialect", ["glsl", "opencl"])
@pytest.mark.parametrize("mode", ["fixed", "auto"])
def test_relaxed_programs_name_their_mode_and_define_it(dialect, mode):
    program = generate(small_scene(relaxation=mode), 32, 24, dialect=dialect)
    assert f"relaxation:{mode}" in program.features
    assert f"#define RELAXATION_AUTO {int(mode == 'auto')}" in program.source
    # relaxed.glsl holds both branches; the defines say which one the compiler keeps.
    assert (re.search(r"^#define SLOPE_WEIGHT ", program.source, re.M) is not None) == (
        mode == "auto")
    assert (re.search(r"^#define OMEGA +P\[", program.source, re.M) is not None) == (
        mode == "fixed")


def test_changing_omega_changes_parameters_not_source():
    a = generate(small_scene(relaxation="fixed", omega=1.2), 32, 24)
    b = generate(small_scene(relaxation="fixed", omega=1.9), 32, 24)
    assert a.source == b.source
    changed = np.argwhere(a.parameters != b.parameters)
    assert len(changed) == 1                                  # just OMEGA
    row, column = changed[0]
    assert (a.parameters[row, column], b.parameters[row, column]) == (1.2, 1.9)


# --- backends: step counts on the equivalence suite's relaxed and culled cases -----------------

@pytest.fixture(scope="module")
def relaxed_cases():
    from equivalence.cases import feature_cases
    cases = feature_cases()
    return {name: cases[name] for name in ("relaxation_fixed", "relaxation_auto",
                                           "bounding_spheres", "relaxed_culled_mirrors")}


CASE_NAMES = ["relaxation_fixed", "relaxation_auto", "bounding_spheres",
              "relaxed_culled_mirrors"]


@pytest.mark.parametrize("precision", ["float32", "float64"])
@pytest.mark.parametrize("name", CASE_NAMES)
def test_opencl_counts_the_same_steps_as_numpy_at_equal_precision(relaxed_cases, name,
                                                                  precision):
    """The OpenCL kernel runs the reference's arithmetic exactly (IEEE, no fused operations),
    so every pixel's step count, relaxed and culled, is the reference's (measured: all)."""
    need_backend("opencl")
    if precision == "float64":
        from gpu_shader.opencl import device
        if not device().fp64:
            pytest.skip(f"the OpenCL device {device().label} has no float64")
    scene = relaxed_cases[name]
    reference = render(scene, 48, 36, backend="numpy", precision=precision)
    frame = render(scene, 48, 36, backend="opencl", precision=precision)
    np.testing.assert_array_equal(frame.steps, reference.steps)
    np.testing.assert_array_equal(frame.hit, reference.hit)


@pytest.mark.parametrize("name", CASE_NAMES)
def test_gpu_step_counts_differ_from_numpy_float32_on_few_pixels_by_few_steps(relaxed_cases,
                                                                             name):
    """llvmpipe rounds a few operations differently, and a relaxed march turns that into a
    step or two: measured at most 2 pixels of 1728 (0.1%), by at most 2 steps."""
    need_backend("gpu")
    scene = relaxed_cases[name]
    reference = render(scene, 48, 36, backend="numpy", precision="float32")
    frame = render(scene, 48, 36, backend="gpu")
    differ = frame.steps != reference.steps
    assert differ.mean() <= 0.005
    assert np.abs(frame.steps.astype(int) - reference.steps).max() <= 4
    np.testing.assert_array_equal(frame.hit, reference.hit)


# --- a step that lands inside exactly along the normal (the sign test takes it back) ------------

@pytest.mark.parametrize("omega", [1.2, 1.5, 1.9])
def test_fixed_relaxed_ray_meeting_a_floor_head_on_hits_it(dtype, omega):
    t, steps, hit = march(np.array([0.0, 3.0, 0.0], dtype), np.array([[0.0, -1.0, 0.0]], dtype),
                          build_scene_sdf([plane()], dtype), 100, EPSILON, 100.0,
                          relaxation="fixed", omega=omega)
    assert hit[0] and 3.0 - EPSILON < t[0] <= 3.0


@pytest.mark.parametrize("wall, precision", [(20.0, "float64"), (20.3, "float32")])
def test_auto_relaxed_ray_along_a_floor_hits_the_wall_ahead(wall, precision):
    dtype = np.dtype(precision)
    sdf = build_scene_sdf([plane(), plane((-1.0, 0.0, 0.0), -wall)], dtype)
    t, _, hit = march(np.array([0.0, 0.5, 0.0], dtype), np.array([[1.0, 0.0, 0.0]], dtype),
                      sdf, 500, EPSILON, 100.0, relaxation="auto")
    assert hit[0] and wall - EPSILON < t[0] <= wall


@pytest.mark.parametrize("backend", ["numpy", "gpu", "opencl"])
def test_every_backend_hits_every_pixel_of_a_wall_seen_head_on_with_fixed_omega(backend):
    need_backend(backend)
    scene = Scene(camera=Camera(position=(0.0, 3.0, 0.0), look_at=(0.0, 0.0, 0.0),
                                up=(0.0, 0.0, -1.0), fov=40.0),
                  render=RenderSettings(relaxation="fixed", omega=1.2, shading="depth"),
                  objects=(plane(),))
    frame = render(scene, 5, 5, backend=backend, precision="float32")
    assert frame.hit.all(), f"{int((~frame.hit).sum())} of 25 pixels missed the wall"
