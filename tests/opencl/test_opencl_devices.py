"""How the opencl backend (`gpu_shader.opencl`) chooses its device and builds for it.

Device selection runs with a fake pyopencl whose devices build or fail as each test says
(never skipped; the process's real choice, `gpu_shader.opencl._chosen`, is put back by
monkeypatch after each test). The build options ask for exact IEEE arithmetic; the two checks
on the real device take the ``opencl_device`` fixture (tests/opencl/conftest.py) and are
skipped, with the reason, where pyopencl or a working OpenCL device is missing.
"""

from __future__ import annotations

import sys
from types import SimpleNamespace

import pytest

import gpu_shader.opencl as opencl
from marchlab import MarchlabError
from marchlab.render import backend_problem


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
