"""Fixtures of the GPU backend's tests.

Tests that draw through OpenGL take the ``gpu`` fixture, which skips them, saying why, on a
machine where `marchlab.render.backend_problem("gpu")` finds no usable EGL context (or fails
them where ``MARCHLAB_REQUIRE_BACKENDS`` names gpu: tests/required_backends.py). Tests of the
shader generator are plain Python and never skip.
"""

from __future__ import annotations

import pytest

from required_backends import need_backend


@pytest.fixture
def gpu():
    """Skip the test unless the gpu backend can draw on this machine (fail it if required)."""
    need_backend("gpu")
