"""Fixtures of the OpenCL backend's tests.

Tests that compute on a real device take the ``opencl_device`` fixture, which skips them,
saying why, where `marchlab.render.backend_problem("opencl")` finds no pyopencl or no
OpenCL device that builds a kernel. Tests of the generated text and of device selection
use fakes and never skip.
"""

from __future__ import annotations

import pytest

import gpu_shader.opencl as opencl
from marchlab.render import backend_problem


@pytest.fixture(scope="session")
def opencl_problem() -> str | None:
    """Why the opencl backend cannot run here (one line), or None if it can."""
    return backend_problem("opencl")


@pytest.fixture
def opencl_device(opencl_problem) -> opencl.Device:
    """The device the backend computes on; skips the test if there is none."""
    if opencl_problem is not None:
        pytest.skip(f"opencl backend unavailable here: {opencl_problem}")
    return opencl.device()
