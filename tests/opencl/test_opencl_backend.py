"""The opencl backend (`gpu_shader.opencl`) and the OpenCL C it runs (`gpu_shader.dialects`).

Three groups of tests:

- `thread_parameters`, the rewrite that passes the parameter buffer ``P`` to every function
  that reads it, on small hand-written sources (plain Python, never skipped);
- device selection, with a fake pyopencl whose devices build or fail as each test says
  (never skipped; the process's real choice, `gpu_shader.opencl._chosen`, is put back by
  monkeypatch after each test);
- real renders, which take the ``opencl_device`` fixture (tests/opencl/conftest.py) and
  are skipped, with the reason, where pyopencl or a working OpenCL device is missing.
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from gpu_shader.dialects import thread_parameters
from gpu_shader.generate import generate
import gpu_shader.opencl as opencl
from marchlab import MarchlabError
import marchlab
from marchlab.render import backend_problem
from scene_model.builder import Camera, Scene, sphere

# A camera on the z axis looking down -z at the origin, as in tests/gpu/test_gpu_backend.py.
CAMERA_Z = 5.0
CAMERA = Camera(position=(0.0, 0.0, CAMERA_Z), look_at=(0.0, 0.0, 0.0), fov=60.0)
SILHOUETTE_PIXELS = 3          # hit masks of two correct renderers may differ here, at most
# Odd sizes: the middle pixel's centre lies on the optical axis, and neither side is a
# multiple of the work-group (16 x 4), so the launch is padded in both directions.
WIDTH, HEIGHT = 33, 25


def ball_at(x: float, y: float, radius: float = 1.2) -> Scene:
    return Scene(objects=(sphere(radius).at(x, y, 0.0),), camera=CAMERA)


def hit_centroid_column(frame) -> float:
    return float(np.nonzero(frame.hit)[1].mean())


def function(source: str, name: str) -> str:
    """The definition of ``name`` in ``source``, from its first line to its closing brace."""
    match = re.search(rf"^\w+ {name}\(.*?^\}}", source, re.M | re.S)
    assert match, f"no definition of {name} in:\n{source}"
    return match.group(0)


# --- thread_parameters: P passed on to whoever reads it ------------------------------------

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


# --- build options ---------------------------------------------------------------------------

CORRECTLY_ROUNDED = 0x80       # any bit: the fake cl below names it


@pytest.mark.parametrize("device_has_it", [True, False], ids=["device-rounds", "device-does-not"])
def test_correctly_rounded_divide_sqrt_is_asked_only_where_the_device_has_it(device_has_it):
    cl = SimpleNamespace(device_fp_config=SimpleNamespace(
        CORRECTLY_ROUNDED_DIVIDE_SQRT=CORRECTLY_ROUNDED))
    config = (CORRECTLY_ROUNDED if device_has_it else 0) | 0x3     # plus two other bits
    dev = opencl.Device("Fake: cpu", SimpleNamespace(single_fp_config=config), None, None, True)
    options = opencl.build_options(cl, dev, "float32")
    assert ("-cl-fp32-correctly-rounded-divide-sqrt" in options) == device_has_it
    assert "-cl-single-precision-constant" in options


def test_build_options_of_the_real_device_are_exact_ieee(opencl_device):
    cl = pytest.importorskip("pyopencl")
    single, double = (opencl.build_options(cl, opencl_device, p) for p in ("float32", "float64"))
    assert "-cl-single-precision-constant" in single
    assert "-cl-single-precision-constant" not in double      # 0.1 must stay a double there
    for options in (single, double):
        assert not any("fast-relaxed-math" in o or "unsafe-math" in o or "mad-enable" in o
                       for o in options), options


# --- device selection, with a fake pyopencl -----------------------------------------------

class FakeCL:
    """A pyopencl stand-in listing ``platforms``: {platform name: [device names]}.

    Contexts and queues are plain tuples; `opencl._probe` is replaced by the ``machine``
    fixture, so nothing here computes.
    """

    def __init__(self, platforms: dict[str, list[str]], extensions: str = "cl_khr_fp64"):
        self.platforms = [
            SimpleNamespace(name=f" {name} ", get_devices=lambda names=names: [
                SimpleNamespace(name=f"{device} ", extensions=extensions) for device in names])
            for name, names in platforms.items()]
        self.listed = 0

    def get_platforms(self):
        self.listed += 1
        if not self.platforms:      # what pyopencl raises without an ICD
            raise RuntimeError("clGetPlatformIDs failed: PLATFORM_NOT_FOUND_KHR")
        return self.platforms

    def Context(self, devices):
        return ("context", devices[0].name.strip())

    def CommandQueue(self, context):
        return ("queue", context)


@pytest.fixture
def machine(monkeypatch):
    """Install a fake OpenCL machine: ``machine(platforms, failing={device: reason})``.

    Returns (fake cl, list of probed device names). The process's cached choice and
    MARCHLAB_OPENCL_DEVICE are reset for the test and restored after it.
    """
    monkeypatch.setattr(opencl, "_chosen", None)
    monkeypatch.delenv(opencl.DEVICE_VARIABLE, raising=False)

    def install(platforms, failing=(), extensions="cl_khr_fp64"):
        cl = FakeCL(platforms, extensions)
        probed = []
        failing = dict(failing)

        def probe(cl_, dev):
            probed.append(dev.name.strip())
            return failing.get(dev.name.strip())

        monkeypatch.setattr(opencl, "_import_pyopencl", lambda: cl)
        monkeypatch.setattr(opencl, "_probe", probe)
        return cl, probed

    return install


TWO_PLATFORMS = {"Portable Computing Language": ["pthread-generic", "pthread-skylake"],
                 "Intel(R) OpenCL": ["Intel(R) Core(TM) i7"]}


def test_candidates_are_indexed_platform_colon_device_with_stripped_labels():
    found = opencl.candidates(FakeCL(TWO_PLATFORMS))
    assert [(index, label) for index, label, _ in found] == [
        ("0:0", "Portable Computing Language: pthread-generic"),
        ("0:1", "Portable Computing Language: pthread-skylake"),
        ("1:0", "Intel(R) OpenCL: Intel(R) Core(TM) i7")]


def test_no_platform_is_a_one_line_error_naming_pocl_opencl_icd(machine):
    machine({})
    with pytest.raises(MarchlabError) as caught:
        opencl.device()
    message = str(caught.value)
    assert message.startswith("no OpenCL platform found")
    assert "pocl-opencl-icd" in message and "\n" not in message
    assert backend_problem("opencl") == message           # what --backend opencl reports


def test_missing_pyopencl_is_a_one_line_error_naming_the_extra(monkeypatch):
    monkeypatch.setattr(opencl, "_chosen", None)
    monkeypatch.setitem(sys.modules, "pyopencl", None)     # import fails
    with pytest.raises(MarchlabError) as caught:
        opencl.check()
    message = str(caught.value)
    assert "pyopencl" in message and "marchlab[opencl]" in message and "\n" not in message


def test_device_whose_probe_fails_is_skipped_for_the_next(machine):
    _, probed = machine(TWO_PLATFORMS, failing={"pthread-generic": "unknown target CPU"})
    dev = opencl.device()
    assert dev.label == "Portable Computing Language: pthread-skylake"
    assert dev.context == ("context", "pthread-skylake") and dev.queue == ("queue", dev.context)
    assert probed == ["pthread-generic", "pthread-skylake"]       # and not the third
    assert opencl.device_name() == dev.label


def test_all_devices_failing_is_one_line_listing_each_with_its_reason(machine):
    reasons = {"pthread-generic": "error: unknown target CPU 'generic'",
               "pthread-skylake": "the test kernel computed wrong values",
               "Intel(R) Core(TM) i7": "clCreateContext failed: DEVICE_NOT_AVAILABLE"}
    _, probed = machine(TWO_PLATFORMS, failing=reasons)
    with pytest.raises(MarchlabError) as caught:
        opencl.device()
    message = str(caught.value)
    assert "\n" not in message and "pocl-opencl-icd" in message
    assert "Portable Computing Language: pthread-generic (error: unknown target CPU 'generic')" \
        in message
    assert "Portable Computing Language: pthread-skylake (the test kernel computed wrong " \
           "values)" in message
    assert "Intel(R) OpenCL: Intel(R) Core(TM) i7 (clCreateContext failed: " \
           "DEVICE_NOT_AVAILABLE)" in message
    assert len(probed) == 3


@pytest.mark.parametrize("wanted, label", [
    ("0:1", "Portable Computing Language: pthread-skylake"),
    ("1:0", "Intel(R) OpenCL: Intel(R) Core(TM) i7"),
    ("SKYLAKE", "Portable Computing Language: pthread-skylake"),
    ("intel(r) opencl", "Intel(R) OpenCL: Intel(R) Core(TM) i7"),
    ("2", "Intel(R) OpenCL: Intel(R) Core(TM) i7"),
], ids=["index-0:1", "index-1:0", "name-any-case", "platform-name", "position-in-list"])
def test_device_variable_picks_that_device_by_index_or_name(machine, monkeypatch, wanted, label):
    _, probed = machine(TWO_PLATFORMS)
    monkeypatch.setenv(opencl.DEVICE_VARIABLE, wanted)
    assert opencl.device().label == label
    assert probed == [label.split(": ", 1)[1]]               # the others were never tried


def test_device_variable_naming_a_broken_device_does_not_fall_back(machine, monkeypatch):
    _, probed = machine(TWO_PLATFORMS, failing={"pthread-skylake": "error: no LLVM target"})
    monkeypatch.setenv(opencl.DEVICE_VARIABLE, "0:1")
    with pytest.raises(MarchlabError, match=r"tried Portable Computing Language: "
                                            r"pthread-skylake \(error: no LLVM target\)\. "):
        opencl.device()
    assert probed == ["pthread-skylake"]


def test_device_variable_matching_nothing_is_one_line_listing_the_devices(machine, monkeypatch):
    _, probed = machine(TWO_PLATFORMS)
    monkeypatch.setenv(opencl.DEVICE_VARIABLE, "nvidia")
    with pytest.raises(MarchlabError) as caught:
        opencl.device()
    message = str(caught.value)
    assert message == ("MARCHLAB_OPENCL_DEVICE='nvidia' matches no OpenCL device (there are: "
                       "0:0 Portable Computing Language: pthread-generic; "
                       "0:1 Portable Computing Language: pthread-skylake; "
                       "1:0 Intel(R) OpenCL: Intel(R) Core(TM) i7)")
    assert probed == []


def test_choice_is_made_once_per_process(machine, monkeypatch):
    cl, probed = machine(TWO_PLATFORMS)
    first = opencl.device()
    monkeypatch.setenv(opencl.DEVICE_VARIABLE, "1:0")        # too late: already chosen
    second = opencl.device()
    assert second is first and first.label.endswith("pthread-generic")
    assert probed == ["pthread-generic"] and cl.listed == 1


def test_failure_is_kept_too(machine):
    cl, _ = machine({})
    errors = []
    for _ in range(2):
        with pytest.raises(MarchlabError) as caught:
            opencl.device()
        errors.append(caught.value)
    assert errors[1] is errors[0]
    assert cl.listed == 1                                      # the machine was asked once


@pytest.mark.parametrize("extensions, fp64", [("cl_khr_int64 cl_khr_fp64 cl_khr_fp16", True),
                                              ("cl_khr_int64 cl_khr_fp16", False)])
def test_fp64_follows_the_cl_khr_fp64_extension(machine, extensions, fp64):
    machine(TWO_PLATFORMS, extensions=extensions)
    assert opencl.device().fp64 is fp64


def test_probe_reports_the_error_line_of_a_multi_line_build_log():
    log = ("clBuildProgram failed: BUILD_PROGRAM_FAILURE - clBuildProgram failed: "
           "BUILD_PROGRAM_FAILURE\n\nBuild on <pyopencl.Device 'cpu'>:\n\n"
           "error: unknown target CPU 'generic'\nnote: valid target CPU values are: x86-64")

    def fail(devices):
        raise RuntimeError(log)

    assert opencl._probe(SimpleNamespace(Context=fail), None) == \
        "error: unknown target CPU 'generic'"


def test_probe_accepts_the_real_device(opencl_device):
    assert opencl._probe(pytest.importorskip("pyopencl"), opencl_device.cl_device) is None


# --- real renders ------------------------------------------------------------------------------

LAYOUT = {"color": np.float32, "steps": np.int32, "object_id": np.int32, "path": np.uint32,
          "hit": np.bool_}


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_sphere_frame_has_the_reference_layout_and_the_analytic_centre_depth(opencl_device,
                                                                             precision):
    """Ball of radius 1.2 at the origin, camera at z = 5: the middle ray hits at t = 3.8.

    Sphere tracing stops where the SDF is below epsilon, so the depth is within epsilon of
    the surface (and within 1e-5 t of rounding of it).
    """
    radius = 1.2
    scene = ball_at(0.0, 0.0, radius)
    frame = marchlab.render(scene, WIDTH, HEIGHT, backend="opencl", precision=precision,
                            path_labels=True)
    reference = marchlab.render(scene, WIDTH, HEIGHT, precision=precision, path_labels=True)
    assert (frame.backend, frame.precision) == ("opencl", precision)
    for name in ("color", "depth", "normal", "steps", "object_id", "hit", "path"):
        ours, theirs = getattr(frame, name), getattr(reference, name)
        assert (name, ours.shape, ours.dtype) == (name, theirs.shape, theirs.dtype)
        assert ours.shape[:2] == (HEIGHT, WIDTH)
    for name, dtype in LAYOUT.items():
        assert getattr(frame, name).dtype == dtype, name
    assert frame.depth.dtype == np.dtype(precision) and frame.normal.dtype == np.dtype(precision)
    assert 0 < frame.hit.sum() < frame.hit.size                 # the ball, and sky around it
    assert np.isinf(frame.depth[~frame.hit]).all() and (frame.object_id[~frame.hit] == -1).all()
    assert np.isfinite(frame.depth[frame.hit]).all() and (frame.object_id[frame.hit] == 0).all()
    assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS

    middle = (HEIGHT // 2, WIDTH // 2)
    exact = CAMERA_Z - radius
    epsilon = scene.render.epsilon
    assert frame.hit[middle]
    assert abs(float(frame.depth[middle]) - exact) <= max(epsilon, 1e-5 * exact)
    assert np.allclose(frame.normal[middle], (0.0, 0.0, 1.0), atol=1e-5)   # facing the camera


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_classroom_kernel_builds_and_draws_what_the_reference_draws(opencl_device, precision):
    scene = marchlab.load_scene("classroom")
    frame = marchlab.render(scene, 32, 24, backend="opencl", precision=precision)
    reference = marchlab.render(scene, 32, 24, precision=precision)
    assert frame.precision == precision
    assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS
    agree = frame.hit & reference.hit
    assert agree.sum() > 0.25 * frame.hit.size                 # floor and spheres
    assert (frame.object_id[agree] == reference.object_id[agree]).mean() > 0.99
    sources = [source for source, p in opencl_device.programs if p == precision]
    real = "double" if precision == "float64" else "float"
    # shadow rays, marched one light at a time or two at once (glsl/shadow_pair.glsl)
    assert any(f"typedef {real} real;" in s and re.search(r"\bhard_shadow(_pair)?\(", s)
               for s in sources)


def test_progress_bands_draw_the_same_frame_as_one_launch(opencl_device):
    """Bands of rows with progress reports must leave no row undrawn.

    The ball fills the whole image (radius 4, 1 from the camera), and an empty scene is
    drawn first at the same size, so a band left out would show misses (or garbage).
    """
    scene = ball_at(0.0, 0.0, radius=4.0)
    marchlab.render(Scene(objects=(), camera=CAMERA), WIDTH, HEIGHT, backend="opencl")
    reports = []
    banded = marchlab.render(scene, WIDTH, HEIGHT, backend="opencl",
                             progress=lambda done, total: reports.append((done, total)))
    whole = marchlab.render(scene, WIDTH, HEIGHT, backend="opencl")
    assert whole.hit.all()
    for name in ("color", "depth", "normal", "steps", "object_id", "hit", "path"):
        assert np.array_equal(getattr(banded, name), getattr(whole, name)), name
    total = WIDTH * HEIGHT
    done = [d for d, _ in reports]
    assert len(reports) > 1 and all(t == total for _, t in reports)
    assert all(a < b for a, b in zip(done, done[1:]))           # strictly increasing
    assert all(d % WIDTH == 0 for d in done)                     # whole rows
    assert reports[-1] == (total, total)


def test_moving_an_object_reuses_the_built_program_and_moves_the_image(opencl_device):
    """Only parameters change when the ball moves from x = -0.8 to x = +0.8: no new build.

    The ball's centre projects to column W/2 + x * (H/2) / (z tan(fov/2)) - 0.5, so the hit
    region moves right by 1.6 of those pixels per unit (within a pixel: perspective widens
    both blobs alike).
    """
    first = marchlab.render(ball_at(-0.8, 0.0), WIDTH, HEIGHT, backend="opencl")
    built = list(opencl_device.programs)
    second = marchlab.render(ball_at(0.8, 0.0), WIDTH, HEIGHT, backend="opencl")
    assert list(opencl_device.programs) == built                # nothing compiled
    pixels_per_unit = (HEIGHT / 2) / (CAMERA_Z * math.tan(math.radians(30.0)))
    shift = hit_centroid_column(second) - hit_centroid_column(first)
    assert shift == pytest.approx(1.6 * pixels_per_unit, abs=1.0)


def test_float64_on_a_device_without_fp64_is_a_one_line_error(opencl_device, monkeypatch):
    no_fp64 = dataclasses.replace(opencl_device, fp64=False)
    monkeypatch.setattr(opencl, "_chosen", no_fp64)
    scene = ball_at(0.0, 0.0)
    with pytest.raises(MarchlabError) as caught:
        marchlab.render(scene, 8, 6, backend="opencl", precision="float64")
    message = str(caught.value)
    assert "\n" not in message and "cl_khr_fp64" in message and no_fp64.label in message
    assert "--precision float32" in message
    frame = marchlab.render(scene, 8, 6, backend="opencl", precision="float32")   # still fine
    assert frame.precision == "float32"


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
