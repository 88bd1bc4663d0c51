"""The gpu backend's two shader stages (`gpu_shader.render.STAGES`): the generated program as a
fragment shader drawn over the frame, and the same program as a compute shader dispatched one
invocation per pixel ("glsl-compute", glsl/main.comp).

Both run the same functions on the same pixel centres, so on one driver the frames agree to
the last bit: measured on llvmpipe, no pixel of any buffer differs on any case below. A
hardware driver may schedule the two stages' arithmetic differently; there the compute frame
must pass the equivalence suite's gates against the fragment frame instead (docs/equivalence.md).
Tests that draw take the ``gpu`` fixture; tests of the program text and of the stage setting
need no GPU.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gpu_shader import context as context_module
from gpu_shader import render as gpu_render
from gpu_shader.context import gl_context, is_software
from gpu_shader.generate import generate
from gpu_shader.render import ENV_STAGE, Renderer, default_stage
from marchlab import MarchlabError
from marchlab.compare import compare_frames, failures, gates_against
from scene_model.scenefile import load_scene

from equivalence.cases import all_cases

# Cases that between them use every part of the entry points: the cone pre-pass (tile 8 and
# 5), anti-aliasing, glass, the texture atlas, per-object shading, soft shadows, relaxed and
# culled marching, a scene whose parameters are read from the uniform block (galton), and
# the steps AOV.
CASE_NAMES = ("scene:classroom", "scene:galton", "scene:glass+prepass", "scene:textures",
              "feature:prepass_cone_tile_5", "feature:aa_prepass_mirrors",
              "feature:glass_everything", "feature:texture_file_mirror_studio",
              "feature:shading_per_object", "feature:relaxed_culled_mirrors",
              "feature:lights_all_soft", "feature:steps")
CASES = [case for case in all_cases() if case[0] in CASE_NAMES]
BUFFERS = ("color", "depth", "normal", "steps", "object_id", "hit", "path")


@pytest.fixture
def renderers(gpu):
    ctx = gl_context()
    if ctx.version_code < 430:
        pytest.skip(f"compute shaders need OpenGL 4.3; this context has {ctx.version_code}")
    return _renderers(ctx)


_made: dict = {}


def _renderers(ctx):
    """A fragment and a compute renderer on ``ctx``, made once (they cache their programs)."""
    if id(ctx) not in _made:
        _made[id(ctx)] = (Renderer(ctx, "fragment"), Renderer(ctx, "compute"))
    return _made[id(ctx)]


def assert_same_frames(fragment, compute, scene):
    if is_software(gl_context()):
        for name in BUFFERS:
            a, b = getattr(fragment, name), getattr(compute, name)
            if a is None and b is None:          # path labels, where none were asked for
                continue
            differ = int(np.count_nonzero((a != b) & ~(np.isnan(a) & np.isnan(b)))
                         if a.dtype.kind == "f" else np.count_nonzero(a != b))
            assert differ == 0, f"{name} differs in {differ} values"
    else:
        c = compare_frames(fragment, compute, epsilon=scene.render.epsilon)
        assert failures(c, gates_against("float32")) == [], c.rows()


def test_case_list_names_only_cases_that_exist():
    assert sorted(name for name, _, _ in CASES) == sorted(CASE_NAMES)


@pytest.mark.parametrize("name, scene, size", CASES, ids=[c[0] for c in CASES])
def test_compute_stage_draws_the_fragment_stage_frame(renderers, name, scene, size):
    fragment, compute = (r.render(scene, *size, path_labels=True) for r in renderers)
    assert 0 < fragment.hit.sum()
    assert_same_frames(fragment, compute, scene)


def test_compute_frame_drawn_in_bands_equals_one_dispatch(renderers):
    """A progress callback makes the compute stage dispatch bands of rows (first_row), as
    the fragment stage draws scissored bands; the frame is the same and progress reaches
    every pixel."""
    _, compute = renderers
    scene = load_scene("classroom")
    calls = []
    whole = compute.render(scene, 64, 80)
    banded = compute.render(scene, 64, 80, progress=lambda done, total: calls.append(
        (done, total)))
    for name in BUFFERS[:-1]:
        np.testing.assert_array_equal(getattr(banded, name), getattr(whole, name))
    assert len(calls) > 1 and calls[-1] == (64 * 80, 64 * 80)


def test_image_whose_size_is_not_a_multiple_of_the_group_is_filled_to_its_edges(renderers):
    """The last work groups reach past the right and bottom edges; every pixel is written
    (a pixel never written would keep the previous frame's value: here, a different scene)."""
    fragment, compute = renderers
    compute.render(load_scene("primitives"), 61, 45)          # leaves its planes in the target
    scene = load_scene("classroom")
    assert_same_frames(fragment.render(scene, 61, 45), compute.render(scene, 61, 45), scene)


# --- the program text and the stage setting (no GPU needed) -------------------------------

def test_compute_program_is_the_fragment_program_with_another_entry_point():
    scene = load_scene("classroom")
    fragment = generate(scene, 64, 48, dialect="glsl", flat_rows=0)
    compute = generate(scene, 64, 48, dialect="glsl-compute")
    assert compute.compute and not fragment.compute
    assert compute.vertex_source == ""
    np.testing.assert_array_equal(compute.parameters, fragment.parameters)
    assert compute.source.startswith("#version 430 core")
    assert "imageStore(out_color, pixel, color_hit)" in compute.source
    def functions(program):        # from the SDF's building blocks up to the entry point
        return program.source.split("// ---- the SDF building blocks")[1].split(
            "// ---- the entry point")[0]

    assert functions(compute) == functions(fragment)


def test_compute_prepass_is_a_compute_shader_too():
    scene = load_scene("classroom")
    scene = dataclasses.replace(scene, render=dataclasses.replace(scene.render, prepass="cone"))
    program = generate(scene, 64, 48, dialect="glsl-compute")
    assert "glsl/prepass.comp" in program.prepass_source
    assert "uniform sampler2D cone_starts" in program.source


def test_stage_setting_names_a_stage(monkeypatch, gpu):
    monkeypatch.setenv(ENV_STAGE, "vertex")
    with pytest.raises(MarchlabError, match=f"{ENV_STAGE}='vertex': expected one of "
                                            "fragment, compute"):
        default_stage(gl_context())


def test_stage_setting_is_obeyed(monkeypatch, gpu):
    for stage in ("fragment", "compute"):
        monkeypatch.setenv(ENV_STAGE, stage)
        if stage == "compute" and gl_context().version_code < 430:
            continue
        assert default_stage(gl_context()) == stage


def test_default_stage_is_fragment_on_llvmpipe_and_compute_on_a_hardware_gpu(monkeypatch, gpu):
    """llvmpipe draws fragments in about half the time of its compute shaders
    (docs/performance.md, "Fragment or compute"); a hardware GPU with OpenGL 4.3 computes."""
    monkeypatch.delenv(ENV_STAGE, raising=False)
    ctx = gl_context()
    expected = "compute" if ctx.version_code >= 430 and not is_software(ctx) else "fragment"
    assert default_stage(ctx) == expected
    assert gpu_render._renderer().stage in ("fragment", "compute")


class FakeContext:
    """What `default_stage` reads of a moderngl context."""

    def __init__(self, version_code: int, renderer: str):
        self.version_code = version_code
        self.info = {"GL_RENDERER": renderer}


@pytest.mark.parametrize("version, renderer, stage", [
    (430, "NVIDIA H100 80GB HBM3/PCIe/SSE2", "compute"),
    (460, "AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 17.0.6)", "compute"),
    (330, "NVIDIA H100 80GB HBM3/PCIe/SSE2", "fragment"),        # no compute shaders
    (410, "Apple M2", "fragment"),                                # macOS stops at 4.1
    (450, "llvmpipe (LLVM 15.0.6, 256 bits)", "fragment"),        # measured slower there
])
def test_default_stage_follows_the_device(monkeypatch, version, renderer, stage):
    monkeypatch.delenv(ENV_STAGE, raising=False)
    assert default_stage(FakeContext(version, renderer)) == stage


def test_compute_stage_asked_of_an_opengl_3_3_context_is_a_one_line_error(monkeypatch):
    monkeypatch.setenv(ENV_STAGE, "compute")
    with pytest.raises(MarchlabError, match=r"^MARCHLAB_GPU_STAGE=compute: compute shaders "
                                            r"need OpenGL 4\.3; Apple M2 has 4\.1$"):
        default_stage(FakeContext(410, "Apple M2"))


def test_context_asks_for_opengl_4_3_first_then_takes_what_the_driver_makes():
    """NVIDIA's EGL makes exactly the version asked for (3.3 by default), so the backend asks
    for 4.3 first (for the compute stage) and, where that fails, for the driver's default."""
    calls = []

    class FakeModernGL:
        @staticmethod
        def create_standalone_context(**options):
            calls.append(options)
            if options.get("require") == 430:
                raise RuntimeError("eglCreateContext failed (0x3009)")
            return "a 3.3 context"

    assert context_module._standalone(FakeModernGL, 1) == "a 3.3 context"
    assert calls == [{"backend": "egl", "device_index": 1, "require": 430},
                     {"backend": "egl", "device_index": 1}]
