"""The gpu backend (`gpu_shader.render`, `gpu_shader.context`) through `marchlab.render`.

Frames are compared with the NumPy reference in float32: same buffers, same dtypes, rows
top-first, hit masks equal but for a few silhouette pixels. Every test that draws takes the
``gpu`` fixture (tests/gpu/conftest.py) and is skipped, with the reason, on a machine without
a usable EGL context (failed where ``MARCHLAB_REQUIRE_BACKENDS`` names gpu); the
error-message tests of the context need no GPU either way.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest

import gpu_shader.context as context
from gpu_shader.generate import generate
from gpu_shader.render import Renderer, ShaderCompileError
import gpu_shader.render as gpu_render
from marchlab import MarchlabError
import marchlab
from marchlab.render import backend_problem
from required_backends import need_backend
from scene_model.builder import Camera, Scene, sphere

# A camera on the z axis looking down -z: image row 0 is the top, x grows to the right.
CAMERA = Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=60.0)
SILHOUETTE_PIXELS = 3          # hit masks of two correct renderers may differ here, at most


def ball_at(x: float, y: float, radius: float = 0.6) -> Scene:
    return Scene(objects=(sphere(radius).at(x, y, 0.0),), camera=CAMERA)


def hit_centroid_column(frame) -> float:
    columns = np.nonzero(frame.hit)[1]
    return float(columns.mean())


# --- the Frame it returns ------------------------------------------------------------------

def test_gpu_renders_in_float32_only():
    with pytest.raises(MarchlabError, match="float32 only"):
        marchlab.render(ball_at(0, 0), 8, 6, backend="gpu", precision="float64")


def test_gpu_frame_has_the_numpy_frames_buffers_dtypes_and_shapes(gpu):
    scene = ball_at(0.0, 0.0, radius=1.2)
    frame = marchlab.render(scene, 40, 30, backend="gpu", path_labels=True)
    reference = marchlab.render(scene, 40, 30, precision="float32", path_labels=True)
    assert (frame.backend, frame.precision) == ("gpu", "float32")
    for name in ("color", "depth", "normal", "steps", "object_id", "hit", "path"):
        ours, theirs = getattr(frame, name), getattr(reference, name)
        assert (name, ours.shape, ours.dtype) == (name, theirs.shape, theirs.dtype)
    assert frame.color.shape == (30, 40, 3) and frame.color.dtype == np.float32
    assert frame.steps.dtype == np.int32 and frame.object_id.dtype == np.int32
    assert frame.path.dtype == np.uint32 and frame.hit.dtype == bool
    assert 0 < frame.hit.sum() < frame.hit.size           # the ball, and sky around it
    assert (frame.object_id[~frame.hit] == -1).all() and (frame.object_id[frame.hit] == 0).all()
    assert np.isinf(frame.depth[~frame.hit]).all() and np.isfinite(frame.depth[frame.hit]).all()


def test_non_square_image_has_rows_top_first_in_both_backends(gpu):
    """37x23 with a ball above the axis: it covers the top rows, the bottom rows stay empty."""
    scene = ball_at(0.0, 1.2)
    frame = marchlab.render(scene, 37, 23, backend="gpu")
    reference = marchlab.render(scene, 37, 23, precision="float32")
    assert frame.hit.shape == (23, 37)
    for f in (frame, reference):
        rows = np.nonzero(f.hit.any(axis=1))[0]
        assert rows.size and rows.max() < 23 // 2      # only above the middle row
    assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS


def test_empty_scene_shows_the_background_of_the_reference(gpu):
    scene = Scene(objects=(), camera=CAMERA)
    frame = marchlab.render(scene, 24, 18, backend="gpu")
    reference = marchlab.render(scene, 24, 18, precision="float32")
    assert not frame.hit.any()
    assert np.abs(frame.color - reference.color).max() <= 1e-5


def test_progress_bands_draw_the_same_frame_as_one_draw(gpu):
    """Drawing in bands with progress reports must leave no band undrawn.

    A different scene is drawn first at the same size, so a band left out would show its
    stale pixels (render targets are reused per size).
    """
    marchlab.render(Scene(objects=(), camera=CAMERA), 40, 30, backend="gpu")
    reports = []
    banded = marchlab.render(ball_at(0.3, -0.2), 40, 30, backend="gpu", path_labels=True,
                             progress=lambda done, total: reports.append((done, total)))
    whole = marchlab.render(ball_at(0.3, -0.2), 40, 30, backend="gpu", path_labels=True)
    for name in ("color", "depth", "steps", "object_id", "hit", "path"):
        assert np.array_equal(getattr(banded, name), getattr(whole, name)), name
    done = [d for d, _ in reports]
    assert done == sorted(done) and reports[-1] == (40 * 30, 40 * 30)


# --- one compiled program per structure -------------------------------------------------------

def test_moving_an_object_reuses_the_program_and_moves_the_image(gpu):
    left, right = ball_at(-0.8, 0.0), ball_at(0.8, 0.0)
    width, height = 48, 36
    programs = gpu_render._renderer().programs
    before = len(programs)
    first = marchlab.render(left, width, height, backend="gpu")
    after_first = len(programs)
    second = marchlab.render(right, width, height, backend="gpu")
    program = gpu_render._renderer().generate(left, width, height)    # in its shader stage
    assert (program.vertex_source, program.source) in programs
    assert after_first - before in (0, 1)      # 0 if an earlier test compiled this structure
    assert len(programs) == after_first        # the move compiled nothing
    # The ball's centre projects to column W/2 + x * (H/2) / (z tan(fov/2)) - 0.5.
    pixels_per_unit = (height / 2) / (5.0 * math.tan(math.radians(30.0)))
    shift = hit_centroid_column(second) - hit_centroid_column(first)
    assert shift == pytest.approx(1.6 * pixels_per_unit, abs=1.0)
    assert set(np.unique(second.object_id)) == {-1, 0}


# --- compile errors quote the generated lines ---------------------------------------------

def broken(source: str, marker: str) -> tuple[str, int, str]:
    """``source`` with the first line containing ``marker`` broken: (text, line number, line)."""
    lines = source.splitlines()
    index = next(i for i, line in enumerate(lines) if marker in line)
    lines[index] = lines[index].rstrip().removesuffix(";") + " +;"
    return "\n".join(lines) + "\n", index + 1, lines[index].strip()


@pytest.mark.parametrize("marker", ["= sdf_sphere(p", "load_parameters();"],
                         ids=["in-scene-sdf", "in-main"])
def test_compile_error_quotes_the_broken_line(gpu, marker):
    source = generate(ball_at(0, 0), 16, 12).source
    text, number, line = broken(source, marker)
    with pytest.raises(ShaderCompileError) as caught:
        gpu_render._renderer().program(text)
    message = str(caught.value)
    assert f"line {number}: {line}" in message
    assert isinstance(caught.value, MarchlabError)
    assert all(text not in key for key in gpu_render._renderer().programs)


def test_compile_error_of_one_line_source_quotes_line_1(gpu):
    with pytest.raises(ShaderCompileError, match="line 1: bad source"):
        Renderer(context.gl_context()).program("bad source")


def test_compile_error_at_the_end_of_the_text_quotes_the_last_line():
    """NVIDIA's compiler names no line for an error at the end of the text (as an H100's
    driver 580 wrote it); the message quotes the last line that is not blank."""
    log = ('GLSL Compiler failed\n\nfragment_shader\n===============\n(0) : error C0000: '
           'syntax error, unexpected $end, expecting "::" at token "<EOF>"')
    message = gpu_render.compile_message(log, "void main()\n{\n    float x = 1.0\n\n")
    assert "  line 3: float x = 1.0" in message
    assert "unexpected $end" in message


# --- the OpenGL context ------------------------------------------------------------------

@pytest.fixture
def moderngl_module():
    """moderngl, for tests that make contexts of their own. Without it the gpu backend cannot
    run either, so `need_backend` skips the test (or fails it, where gpu is required)."""
    if importlib.util.find_spec("moderngl") is None:
        need_backend("gpu")
    import moderngl
    return moderngl


@pytest.fixture
def keep_current(moderngl_module):
    """Make the process's context current again after a test that makes other contexts.

    Making a context makes it current, and the backend draws on whichever context is current
    (see test_frames_are_unchanged_after_another_gl_context_is_made), so later tests would get
    empty frames.
    """
    original = context._context
    yield moderngl_module
    if original is not None:
        original.__enter__()


@pytest.fixture
def fresh_context(keep_current, monkeypatch):
    """Forget the process's context for one test; monkeypatch puts it back afterwards."""
    monkeypatch.setattr(context, "_context", None)
    monkeypatch.setattr(gpu_render, "_renderers", {})
    monkeypatch.delenv(context.ENV_DEVICE, raising=False)
    return keep_current


def release(contexts) -> None:
    """Release contexts made by a test, with the programs the backend compiled on them."""
    for renderer in gpu_render._renderers.values():
        for program, vao in renderer.programs.values():
            if vao is not None:                   # a compute program has none
                vao.release()
            program.release()
    for ctx in contexts:
        ctx.release()


def test_no_egl_is_a_one_line_error_with_the_install_hint(fresh_context, monkeypatch):
    def fail(*args, **kwargs):
        raise RuntimeError("eglGetDisplay failed\nsecond line of a driver message")
    monkeypatch.setattr(fresh_context, "create_standalone_context", fail)
    with pytest.raises(MarchlabError) as caught:
        context.gl_context()
    message = str(caught.value)
    assert "EGL" in message and "apt-get" in message and "eglGetDisplay failed" in message
    assert "\n" not in message
    assert backend_problem("gpu") == message      # what `render --backend gpu` reports


@pytest.mark.parametrize("value", ["abc", "-1", "0x1"])
def test_bad_device_variable_is_a_one_line_error(fresh_context, monkeypatch, value):
    monkeypatch.setenv(context.ENV_DEVICE, value)
    with pytest.raises(MarchlabError) as caught:
        context.gl_context()
    message = str(caught.value)
    assert context.ENV_DEVICE in message and repr(value) in message and "\n" not in message


def test_missing_device_index_is_a_one_line_error(gpu, fresh_context, monkeypatch):
    monkeypatch.setenv(context.ENV_DEVICE, "99")
    with pytest.raises(MarchlabError) as caught:
        context.gl_context()
    message = str(caught.value)
    assert f"{context.ENV_DEVICE}=99" in message and "\n" not in message


def test_device_variable_0_makes_a_working_context(gpu, fresh_context, monkeypatch):
    monkeypatch.setenv(context.ENV_DEVICE, "0")
    ctx = context.gl_context()
    try:
        assert ctx.version_code >= 330
        scene = ball_at(0.0, 0.0, radius=1.2)
        frame = marchlab.render(scene, 24, 18, backend="gpu")
        reference = marchlab.render(scene, 24, 18, precision="float32")
        assert context._context is ctx
        assert reference.hit.sum() > 20
        assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS
    finally:
        release([ctx])


def test_frames_are_unchanged_after_another_gl_context_is_made(gpu, keep_current):
    scene = ball_at(0.0, 0.0, radius=1.2)
    before = marchlab.render(scene, 24, 18, backend="gpu")
    other = keep_current.create_standalone_context(backend="egl", device_index=0)
    try:
        after = marchlab.render(scene, 24, 18, backend="gpu")
    finally:
        other.release()
    assert before.hit.sum() > 20
    assert np.array_equal(after.hit, before.hit)
    assert np.array_equal(after.color, before.color)


def test_first_of_two_software_devices_draws(gpu, fresh_context, monkeypatch):
    """A machine with two llvmpipe EGL devices, simulated by making device 0 twice: the
    first is kept, the second released, and the kept one draws what the reference draws."""
    made = []
    real = fresh_context.create_standalone_context

    def two_devices(backend, device_index):
        if device_index > 1:
            raise RuntimeError(f"requested device index {device_index}, but found 2 devices")
        made.append(real(backend=backend, device_index=0))
        return made[-1]

    monkeypatch.setattr(fresh_context, "create_standalone_context", two_devices)
    try:
        assert context.gl_context() is made[0]
        scene = ball_at(0.0, 0.0, radius=1.2)
        frame = marchlab.render(scene, 24, 18, backend="gpu")
        reference = marchlab.render(scene, 24, 18, precision="float32")
    finally:
        release(made[:1])                # made[1] was released by _make_context
    assert reference.hit.sum() > 20
    assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS


def test_scene_too_large_for_a_private_copy_reads_the_buffer_and_matches_the_reference(gpu):
    """Over MAX_PRIVATE_ROWS fixed rows, P is the uniform buffer itself; the image must not change.

    Each sphere needs 2 rows, so MAX_PRIVATE_ROWS / 2 + 8 spheres are past it. Gates as in
    the equivalence suite (float32 reference).
    """
    from scene_model.builder import Checker, Material, Scene, plane, sphere
    from marchlab.compare import compare_frames, failures, gates_against
    from gpu_shader.dialects import MAX_PRIVATE_ROWS
    from gpu_shader.generate import generate

    objects = [plane(material="floor")] + [sphere(0.1).at(0.3 * i - 30, 0.1, -2)
                                           for i in range(MAX_PRIVATE_ROWS // 2 + 8)]
    scene = Scene(objects=objects, materials={"floor": Material(checker=Checker()),
                                              "default": Material()})
    source = generate(scene, 64, 48).source
    assert "#define P U" in source and len(objects) * 2 > MAX_PRIVATE_ROWS
    reference = marchlab.render(scene, 64, 48, precision="float32")
    frame = marchlab.render(scene, 64, 48, backend="gpu")
    assert frame.hit.sum() > 0.5 * frame.hit.size
    c = compare_frames(reference, frame, epsilon=scene.render.epsilon)
    assert failures(c, gates_against("float32")) == []


# --- how the parameters reach the fragment shader -------------------------------------------

FRAME_BUFFERS = ("color", "depth", "normal", "steps", "object_id", "hit", "path")


@pytest.mark.parametrize("scene_name", ["classroom", "csg"])
def test_parameters_as_flat_varyings_or_a_private_copy_give_the_same_frame_to_the_bit(
        gpu, scene_name):
    """Flat varyings (rows that fit, the default) and the per-pixel private copy are two ways
    of delivering the same numbers: every buffer must agree to the bit. csg needs 32 rows,
    exactly MAX_FLAT_ROWS."""
    from gpu_shader.dialects import MAX_FLAT_ROWS
    from gpu_shader.render import render_program
    from scene_model.shapes import primitives

    scene = marchlab.load_scene(scene_name)
    flat = generate(scene, 48, 36, path_labels=True)
    private = generate(scene, 48, 36, flat_rows=0, path_labels=True)
    rows = len(private.parameters) - 4 * len(list(primitives(scene.objects)))
    assert rows <= MAX_FLAT_ROWS
    if rows > gpu_render._renderer().flat_rows:
        pytest.skip(f"this OpenGL passes {gpu_render._renderer().flat_rows} flat varyings, "
                    f"{scene_name} needs {rows}")
    assert f"flat in vec4 P[{rows}];" in flat.source
    assert f"#define FLAT_ROWS {rows}" in flat.vertex_source
    assert f"vec4 P[{rows}];" in private.source and "flat in" not in private.source
    assert private.vertex_source == ""
    a = render_program(scene, flat, 48, 36)
    b = render_program(scene, private, 48, 36)
    assert a.hit.any()
    for name in FRAME_BUFFERS:
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name


def test_a_scene_with_more_fixed_rows_than_flat_varyings_copies_them_per_pixel(gpu):
    """primitives reads 40 rows with fixed indices, more than MAX_FLAT_ROWS: the program falls
    back to the private copy with the plain vertex shader, and the renderer draws it."""
    from gpu_shader.dialects import MAX_FLAT_ROWS

    scene = marchlab.load_scene("primitives")
    program = generate(scene, 32, 24)
    assert "flat in" not in program.source and program.vertex_source == ""
    assert "P[i] = U[i];" in program.source
    assert MAX_FLAT_ROWS < len(program.parameters)
    frame = marchlab.render(scene, 32, 24, backend="gpu")
    assert frame.hit.any()
    assert gpu_render._renderer().flat_rows <= MAX_FLAT_ROWS
