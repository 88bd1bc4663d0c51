"""``marchlab render --backend opencl`` and ``marchlab shader --dialect opencl``.

Commands run in-process through `marchlab.cli.main` (tests/cli_helpers.py). ``shader`` and
the user errors need no OpenCL; the renders take the ``opencl_device`` fixture
(tests/opencl/conftest.py). One test runs the real ``marchlab`` command, so that its
MARCHLAB_OPENCL_DEVICE is read by a fresh process rather than this one's cached choice.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from PIL import Image
from cli_helpers import assert_one_line_error, leftovers, run_cli, run_marchlab

import gpu_shader.opencl as opencl
import marchlab


# --- marchlab shader --dialect opencl ---------------------------------------------------------

def test_opencl_shader_is_a_kernel_taking_the_parameter_buffer(capsys):
    code, out, err = run_cli(capsys, "shader", "classroom", "--dialect", "opencl")
    assert code == 0 and err == ""
    assert re.search(r"^__kernel void render\(PARAMETERS,$", out, re.M)
    assert re.search(r"^real scene_sdf\(PARAMETERS, vec3 p\)$", out, re.M)
    code_only = "\n".join(line.partition("//")[0] for line in out.splitlines())
    assert "typedef float real;" in out and "double" not in code_only
    assert "#version" not in out                      # not the GLSL shader


def test_opencl_shader_in_float64_declares_real_as_double(capsys):
    code, out, err = run_cli(capsys, "shader", "classroom", "--dialect", "opencl",
                             "--precision", "float64")
    assert code == 0 and err == ""
    assert "typedef double real;" in out and "typedef double3 vec3;" in out
    assert "#pragma OPENCL EXTENSION cl_khr_fp64 : enable" in out


@pytest.mark.parametrize("argv", [["--dialect", "hlsl"],
                                  ["--dialect", "glsl", "--precision", "float64"],
                                  ["--dialect", "opencl", "--precision", "float16"]],
                         ids=["unknown-dialect", "glsl-in-float64", "unknown-precision"])
def test_shader_dialect_errors_are_one_line_exit_2(capsys, argv):
    code, out, err = run_cli(capsys, "shader", "classroom", *argv)
    assert_one_line_error(code, err)
    assert out == ""


# --- marchlab render --backend opencl ---------------------------------------------------------

@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_render_with_opencl_writes_the_png_of_the_frame(opencl_device, capsys, tmp_path,
                                                        precision):
    output = tmp_path / "x.png"
    code, out, err = run_cli(capsys, "render", "classroom", "--backend", "opencl",
                             "--precision", precision, "--size", "32x24", "-o", output)
    assert code == 0 and err == ""
    assert f"opencl {precision}" in out and f"wrote {output} (32x24" in out
    with Image.open(output) as image:
        pixels = np.asarray(image.convert("RGB"))
    expected = marchlab.render(marchlab.load_scene("classroom"), 32, 24, backend="opencl",
                               precision=precision).image()
    assert pixels.shape == (24, 32, 3)
    assert np.array_equal(pixels, expected)         # PNG is lossless: the same 8-bit frame
    assert leftovers(tmp_path) == []


def test_render_without_an_opencl_platform_is_one_line_exit_2(capsys, monkeypatch, tmp_path):
    """A fake pyopencl that lists no platform: the user is told what to install."""
    class NoPlatform:
        def get_platforms(self):
            raise RuntimeError("clGetPlatformIDs failed: PLATFORM_NOT_FOUND_KHR")

    monkeypatch.setattr(opencl, "_chosen", None)
    monkeypatch.delenv(opencl.DEVICE_VARIABLE, raising=False)
    monkeypatch.setattr(opencl, "_import_pyopencl", NoPlatform)
    code, out, err = run_cli(capsys, "render", "classroom", "--backend", "opencl",
                             "--size", "8x6", "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert "no OpenCL platform found" in err and "pocl-opencl-icd" in err
    assert list(tmp_path.iterdir()) == []


def test_render_in_float64_without_fp64_is_one_line_exit_2(opencl_device, capsys, monkeypatch,
                                                           tmp_path):
    monkeypatch.setattr(opencl, "_chosen", dataclasses.replace(opencl_device, fp64=False))
    code, _, err = run_cli(capsys, "render", "classroom", "--backend", "opencl",
                           "--precision", "float64", "--size", "8x6", "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert "cl_khr_fp64" in err and "--precision float32" in err
    assert list(tmp_path.iterdir()) == []


def test_device_variable_matching_nothing_is_one_line_exit_2_listing_devices(
        opencl_device, monkeypatch, tmp_path):
    cl = pytest.importorskip("pyopencl")
    monkeypatch.setenv(opencl.DEVICE_VARIABLE, "no-such-device")   # the subprocess's only
    result = run_marchlab("render", "classroom", "--backend", "opencl", "--size", "8x6",
                          "-o", tmp_path / "x.png", cwd=tmp_path)
    assert_one_line_error(result.returncode, result.stderr)
    assert "MARCHLAB_OPENCL_DEVICE='no-such-device' matches no OpenCL device" in result.stderr
    for index, label, _ in opencl.candidates(cl):
        assert f"{index} {label}" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_kernel_built_afresh_prints_nothing_of_the_compiler_to_the_terminal(
        opencl_device, monkeypatch, tmp_path):
    # PoCL's clang writes "186 warnings generated." straight to file descriptor 2, past any
    # Python warning filter; the build's -w must keep it quiet. Both caches are off, so the
    # kernel really is compiled in this subprocess.
    monkeypatch.setenv("PYOPENCL_NO_CACHE", "1")
    monkeypatch.setenv("POCL_KERNEL_CACHE", "0")
    result = run_marchlab("render", "lights", "--backend", "opencl", "--size", "8x6",
                          "-o", tmp_path / "x.png", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
