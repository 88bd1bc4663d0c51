"""Fixtures of the GPU backend's tests.

Tests that draw through OpenGL take the ``gpu`` fixture, which skips them, saying why, on a
machine where `marchlab.render.backend_problem("gpu")` finds no usable EGL context. Tests of
the shader generator are plain Python and never skip.
"""

from __future__ import annotations

import pytest

from marchlab.render import backend_problem


@pytest.fixture(scope="session")
def gpu_problem() -> str | None:
    """Why the gpu backend cannot run here (one line), or None if it can."""
    return backend_problem("gpu")


@pytest.fixture
def gpu(gpu_problem):
    """Skip the test unless the gpu backend can draw on this machine."""
    if gpu_problem is not None:
        pytest.skip(f"gpu backend unavailable here: {gpu_problem}")
