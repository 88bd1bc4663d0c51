"""Fixtures of the OpenCL backend's tests.

Tests that compute on a real device take the ``opencl_device`` fixture, which skips them,
saying why, where `marchlab.render.backend_problem("opencl")` finds no pyopencl or no
OpenCL device that builds a kernel (or fails them where ``MARCHLAB_REQUIRE_BACKENDS`` names
opencl: tests/required_backends.py). Tests of the generated text and of device selection
use fakes and never skip.
"""

from __future__ import annotations

import pytest

import gpu_shader.opencl as opencl
from required_backends import need_backend


@pytest.fixture
def opencl_device() -> opencl.Device:
    """The device the backend computes on; skips the test if there is none (fails if required)."""
    need_backend("opencl")
    return opencl.device()
