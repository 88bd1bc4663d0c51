"""Fixtures and analytic helpers of the hard cases.

``renderer`` runs a test body once for every (backend, precision) pair marchlab offers
(`marchlab.render.BACKENDS`): numpy in float64 and float32, gpu in float32, opencl in float32
and float64. A pair this machine cannot run is skipped with the backend's own reason (no EGL
context, no OpenCL device, a device without float64), never passed silently; a backend named
in ``MARCHLAB_REQUIRE_BACKENDS`` fails instead (tests/required_backends.py).

Every frame drawn through `Renderer.draw` is checked for NaN and inf in its colour: none may
reach a colour on any backend in any hard case, so each hard case that renders checks it on
every frame it draws.

``report(what, value)`` records a number a hard case measured (a difference quotient, an
error growth); they are printed at the end of the run, so that a reader sees the measured
values, not only that they stayed within their bounds.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pytest

from marchlab import render
from marchlab.render import BACKENDS, MESH_BACKENDS
from required_backends import need_backend
from scene_model.frame import Frame

# The sphere tracers: the hard cases are SDF scenes (the mesh backends have their own, in
# tests/equivalence/test_raster_equivalence.py and the rasteriser's tests).
RENDERERS = [(name, precision) for name, backend in BACKENDS.items()
             if name not in MESH_BACKENDS for precision in backend.precisions]


@dataclass(frozen=True)
class Renderer:
    """One backend at one precision."""
    backend: str
    precision: str

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(self.precision)

    def draw(self, scene, width: int, height: int) -> Frame:
        """Render ``scene`` (with path labels), failing if any pixel's colour holds a NaN or
        an inf."""
        frame = render(scene, width, height, backend=self.backend, precision=self.precision,
                       path_labels=True)
        bad = ~np.isfinite(frame.color).all(axis=-1)
        assert not bad.any(), (f"{self}: {bad.sum()} pixels with a NaN or inf colour, first at "
                               f"(row, column) {tuple(np.argwhere(bad)[0])}")
        return frame

    def __str__(self) -> str:
        return f"{self.backend} {self.precision}"


MEASURED: list[tuple[str, str, str]] = []       # test, what, value


@pytest.fixture
def report(request):
    """``report(what, value)``: keep a measured number for the summary at the end."""
    def add(what: str, value) -> None:
        MEASURED.append((request.node.name, what, f"{value:.6g}" if isinstance(value, float)
                         else str(value)))
    return add


def pytest_terminal_summary(terminalreporter):
    if not MEASURED:
        return
    terminalreporter.section("hard cases: measured (reported, not gated)")
    for test, what, value in MEASURED:
        terminalreporter.write_line(f"{test}: {what} = {value}")


@functools.cache
def precision_problem(backend: str, precision: str) -> str | None:
    """Why a backend that runs here cannot run at ``precision`` (one line), or None."""
    if backend == "opencl" and precision == "float64":
        from gpu_shader.opencl import device
        if not device().fp64:
            return f"the OpenCL device {device().label} has no float64 (cl_khr_fp64)"
    return None


@pytest.fixture(params=RENDERERS, ids=[f"{b}-{p}" for b, p in RENDERERS])
def renderer(request) -> Renderer:
    """A (backend, precision) pair that can render here; skipped, with its reason, if not
    (a missing backend fails instead where it is required)."""
    backend, precision = request.param
    need_backend(backend)
    problem = precision_problem(backend, precision)
    if problem:
        pytest.skip(problem)
    return Renderer(backend, precision)


@pytest.fixture(params=["float64", "float32"])
def dtype(request) -> np.dtype:
    """The two precisions of the NumPy reference, for tests on ray arrays."""
    return np.dtype(request.param)


# --- analytic helpers ---------------------------------------------------------------------

def unit(v) -> np.ndarray:
    """``v`` (..., 3) scaled to unit length along the last axis, in float64."""
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def dot(a, b) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


def ray_sphere(origins, directions, centre, radius):
    """Where the rays o + t d (t >= 0) first meet the sphere, in float64.

    Returns
    -------
    t : (N,) ndarray
        The nearest t >= 0 on the sphere (the exit for a ray starting inside); inf on a miss.
    closest : (N,) ndarray
        Distance from the centre to each ray's line: a ray grazes the sphere where it is
        near ``radius``.
    """
    oc = np.asarray(origins, np.float64) - centre
    d = np.asarray(directions, np.float64)
    b = dot(oc, d)
    c = dot(oc, oc) - radius ** 2
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0))
    near, far = -b - root, -b + root
    t = np.where(near >= 0, near, far)
    t = np.where((disc >= 0) & (t >= 0), t, np.inf)
    closest = np.sqrt(np.maximum(dot(oc, oc) - b * b, 0))
    return t, closest


def pixel_rays(scene, width: int, height: int):
    """The camera's origin (3,) and pixel directions (H, W, 3), in float64, as the contract
    defines them (`marchlab.camera_rays`): the truth each backend's pixels are held to."""
    from marchlab import camera_rays
    return camera_rays(scene.camera, width, height, np.float64)
