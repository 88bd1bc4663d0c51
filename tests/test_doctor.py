"""``marchlab doctor`` says, one line per backend and extra, what works here and how to fix
the rest; ``--brief`` says it in one line (make demo prints it before rendering).

The machine's real backends are replaced by `backend_problem` stand-ins, so these tests say the
same on a machine with every driver and on one with none.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

import marchlab.doctor as doctor
from cli_helpers import run_cli
from marchlab.render import BACKENDS

ROOT = Path(__file__).resolve().parent.parent
GPU_PROBLEM = "the gpu backend cannot make an OpenGL 3.3+ context through EGL (no device)"


@pytest.fixture
def only_numpy(monkeypatch):
    """Every backend but numpy fails here, with a reason naming it."""
    monkeypatch.setattr(doctor, "backend_problem",
                        lambda name: None if name == "numpy" else f"no driver for {name}")


def report_lines(capsys, *argv) -> list[str]:
    code, out, err = run_cli(capsys, "doctor", *argv)
    assert (code, err) == (0, "")
    return out.splitlines()


def test_doctor_gives_one_line_per_backend_and_extra_after_its_heading(capsys, only_numpy):
    lines = report_lines(capsys)
    assert len(lines) == 1 + len(BACKENDS) + len(doctor.EXTRAS)
    assert lines[0].startswith("marchlab ")
    labels = [line.split("  ")[0].strip() for line in lines[1:]]
    assert labels == [f"backend {b}" for b in BACKENDS] + [f"extra {e}" for e in doctor.EXTRAS]


def test_doctor_names_an_unavailable_backend_with_its_reason_and_the_apt_packages(
        capsys, monkeypatch):
    monkeypatch.setattr(doctor, "backend_problem",
                        lambda name: GPU_PROBLEM if name == "gpu" else None)
    monkeypatch.setattr(doctor, "device_of", lambda name: f"device of {name}")
    find_spec = importlib.util.find_spec          # moderngl is installed: the driver is missing
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: object() if name == "moderngl" else find_spec(name, *a))
    (gpu,) = [line for line in report_lines(capsys) if line.startswith("backend gpu ")]
    assert f"unavailable: {GPU_PROBLEM}" in gpu
    assert gpu.endswith("fix: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri "
                        "(or make system-packages as root)")
    (opencl,) = [line for line in report_lines(capsys) if line.startswith("backend opencl ")]
    assert opencl.endswith("works: device of opencl")


def test_a_backend_without_its_python_package_is_fixed_with_its_pip_extra(capsys, monkeypatch,
                                                                         only_numpy):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "pyopencl" else find_spec(name, *a))
    (opencl,) = [line for line in report_lines(capsys) if line.startswith("backend opencl ")]
    assert "unavailable: no driver for opencl -- fix: pip install 'marchlab[opencl]'" in opencl


def test_a_reason_of_several_lines_stays_on_the_backends_one_line(capsys, monkeypatch):
    monkeypatch.setattr(doctor, "backend_problem",
                        lambda name: None if name == "numpy" else "first line\n  second line")
    lines = report_lines(capsys)
    assert len(lines) == 1 + len(BACKENDS) + len(doctor.EXTRAS)
    assert sum("unavailable: first line second line" in line for line in lines) == \
        len(BACKENDS) - 1


def test_a_backend_that_raises_an_unexpected_error_is_reported_not_a_traceback(capsys,
                                                                              monkeypatch):
    def broken(name):
        if name == "opencl":
            raise RuntimeError("clGetPlatformIDs failed: -1001")
        return None
    monkeypatch.setattr(doctor, "backend_problem", broken)
    monkeypatch.setattr(doctor, "device_of", lambda name: "a device")
    (opencl,) = [line for line in report_lines(capsys) if line.startswith("backend opencl ")]
    assert "unavailable: RuntimeError: clGetPlatformIDs failed: -1001" in opencl


def test_a_missing_extra_names_its_packages_and_its_pip_extra(capsys, monkeypatch, only_numpy):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "embreex" else find_spec(name, *a))
    (embree,) = [line for line in report_lines(capsys) if line.startswith("extra embree ")]
    assert "missing: embreex not installed" in embree
    assert embree.endswith("fix: pip install 'marchlab[embree]'")


def test_brief_is_one_line_naming_each_unavailable_backend_and_why(capsys, only_numpy):
    (line,) = report_lines(capsys, "--brief")
    assert line.startswith("marchlab: backends that render here: numpy; unavailable: ")
    for backend in set(BACKENDS) - {"numpy"}:
        assert f"{backend} (no driver for {backend})" in line


def test_brief_with_every_backend_working_names_them_all(capsys, monkeypatch):
    monkeypatch.setattr(doctor, "backend_problem", lambda name: None)
    monkeypatch.setattr(doctor, "device_of", lambda name: f"device of {name}")
    assert report_lines(capsys, "--brief") == [
        f"marchlab: backends that render here: {', '.join(BACKENDS)}"]


def test_the_numpy_reference_works_on_this_machine_whatever_else_is_missing(capsys):
    (numpy,) = [line for line in report_lines(capsys) if line.startswith("backend numpy ")]
    assert "works: NumPy " in numpy


def test_the_apt_packages_doctor_names_are_those_the_makefile_installs():
    makefile = (ROOT / "Makefile").read_text()
    match = re.search(r"^SYSTEM_PACKAGES\s*:=\s*(.+)$", makefile, re.MULTILINE)
    assert match, "the Makefile has no SYSTEM_PACKAGES line"
    named = sorted(p for packages in doctor.APT_PACKAGES.values() for p in packages)
    assert named == sorted(match.group(1).split())


def test_a_device_that_cannot_be_named_after_its_check_is_still_one_line(capsys, monkeypatch):
    import gpu_shader.opencl as opencl
    from scene_model.errors import MarchlabError

    def vanished():
        raise MarchlabError("no OpenCL platform found")
    monkeypatch.setattr(doctor, "backend_problem", lambda name: None)
    monkeypatch.setattr(opencl, "device_name", vanished)
    (line,) = [line for line in report_lines(capsys) if line.startswith("backend opencl ")]
    assert line.endswith("works: device unknown (no OpenCL platform found)")
