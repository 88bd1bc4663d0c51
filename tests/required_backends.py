"""Backends the suite must run: the one rule for a test whose backend is missing.

A test that needs the gpu or opencl backend calls `need_backend`. Where the backend cannot
run on this machine, the test is skipped with the backend's own reason
(`marchlab.render.backend_problem`: no EGL context, no OpenCL device), so a student without
those drivers can still run the suite. A run that names the backend in the environment
variable ``MARCHLAB_REQUIRE_BACKENDS`` (comma-separated; ``make test`` sets ``gpu,opencl``)
fails that test instead, naming the backend and the reason: without it, a suite whose every
backend was skipped would look as green as one that ran them all.
"""

from __future__ import annotations

import functools
import os

import pytest

from marchlab.render import BACKENDS, backend_problem

VARIABLE = "MARCHLAB_REQUIRE_BACKENDS"


def required_backends() -> frozenset[str]:
    """The backend names in ``MARCHLAB_REQUIRE_BACKENDS``; empty when it is unset or empty.

    Raises `pytest.UsageError` for a name marchlab has no backend for, listing the known ones
    (tests/conftest.py asks once at start-up, so a misspelt name stops the run at once).
    """
    value = os.environ.get(VARIABLE, "")
    names = frozenset(name.strip() for name in value.split(",") if name.strip())
    unknown = sorted(names - BACKENDS.keys())
    if unknown:
        raise pytest.UsageError(f"{VARIABLE}={value!r}: unknown backend {', '.join(unknown)}; "
                                f"the known backends are {', '.join(BACKENDS)}")
    return names


@functools.cache
def why_unavailable(backend: str) -> str | None:
    """`marchlab.render.backend_problem`, asked once per run: None if ``backend`` can run."""
    return backend_problem(backend)


def need_backend(backend: str) -> None:
    """Return if ``backend`` can run here; else skip the calling test, or fail it if required.

    Call it from a test or a fixture. Both outcomes name the backend and the reason it cannot
    run; the failure also names the variable that made the backend required.
    """
    problem = why_unavailable(backend)
    if problem is None:
        return
    message = f"{backend} backend unavailable: {problem}"
    if backend in required_backends():
        pytest.fail(f"{message} (required by {VARIABLE}={os.environ[VARIABLE]})",
                    pytrace=False)
    pytest.skip(message)
