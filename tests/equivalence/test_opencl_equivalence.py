"""The OpenCL backend against the NumPy reference at equal precision, under tight bounds.

The opencl backend runs the reference's algorithm compiled, with exact IEEE arithmetic
(`gpu_shader.opencl.build_options`), so at equal precision it must agree with NumPy far
more closely than the gates of `test_equivalence.py` ask of every backend. For each bundled
scene and feature case (`cases.py`):

opencl float32 against numpy float32
    1. hit flags differ only within 1 px of the reference silhouette (``hit_differs_far`` of
       `marchlab.compare.compare_frames` is 0);
    2. on the interior of `compare_frames` (hit in both, 2 px from any edge): colour within
       1e-3 (a quarter of one 8-bit level) and |dt| <= max(2 epsilon, 1e-5 t), the gates'
       depth bound.

opencl float64 against numpy float64
    1. hit flags as above;
    2. |dt| <= 1e-9 wherever both hit (absolute; t is 1 to 100 scene units here);
    3. colour within 2**-24 on the interior. `Frame.color` is float32 at either precision, and
       two float64 computations that differ by the few float64 ulps OpenCL allows its maths
       functions (and fused multiply-adds) round to the same float32 or to its neighbour: at
       most one float32 ulp, which is 2**-24 = 6.0e-8 for a colour in [0, 1]. A looser
       1e-6 would let through a kernel that shaded in float32 (the float32 pair differs by up
       to 6e-7 where both hit); anything above one ulp means a different computation.

Measured with PoCL 3.1 on an AVX-512 CPU, over all cases: depth identical at both precisions,
colour max |dc| 1.2e-7 on the float32 interior and 0 in float64.

Unlike `compare_frames`' ``color_max``, the colour bounds excuse no interior pixel whose path
label differs (a reflected checker edge or shadow edge where rounding picked the other side):
no case has one. Should one appear, the table in the message shows it as
``color_max_path_differs`` and ``path_differs``.

On failure the two images, the difference x16 and the error mask are written to the test's
tmp_path and named in the message. References come from `reference_frame`, rendered once per
run and shared with `test_equivalence.py`.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.opencl import device as opencl_device
from marchlab import render
from marchlab.compare import (Comparison, Gates, compare_frames, failures, gates_against,
                              write_difference_images)
from required_backends import need_backend

from .cases import all_cases
from .conftest import reference_frame

CASES = all_cases()
IDS = [name for name, _, _ in CASES]

COLOR_FLOAT32 = 1e-3           # a quarter of one 8-bit level (1/255 = 3.9e-3)
DEPTH_FLOAT64 = 1e-9           # scene units, absolute
COLOR_FLOAT64 = 2.0 ** -24     # one float32 ulp of a colour in [0.5, 1], the largest in [0, 1]


@pytest.fixture(scope="module")
def opencl() -> None:
    """Skip, with the backend's own reason, where the opencl backend cannot run (or fail,
    where it is required)."""
    need_backend("opencl")


@pytest.fixture(scope="module")
def opencl_float64(opencl) -> None:
    """Skip, saying which device, where the OpenCL device has no float64."""
    device = opencl_device()
    if not device.fp64:
        pytest.skip(f"the OpenCL device {device.label} has no float64 (cl_khr_fp64)")


def interior_color_max(c: Comparison) -> float:
    """Max |colour difference| over the whole interior, pixels with differing paths included."""
    return max(c.color_max, c.color_max_path_differs)


def float32_failures(c: Comparison) -> list[str]:
    """One line per float32 bound that ``c`` (opencl against numpy, both float32) breaks."""
    out = []
    if c.hit_differs_far:
        out.append(f"coverage: {c.hit_differs_far} pixels differ in hit more than 1 px from "
                   "the reference silhouette")
    if not interior_color_max(c) <= COLOR_FLOAT32:
        out.append(f"interior colour: {interior_color_max(c):.3g} > {COLOR_FLOAT32:.3g}")
    if not c.depth_excess <= 1:
        out.append(f"interior depth: |dt| reaches {c.depth_excess:.3g} x max(2 epsilon, 1e-5 t)")
    return out


def float64_failures(reference, candidate, c: Comparison) -> list[str]:
    """One line per float64 bound that ``candidate`` breaks against ``reference``."""
    out = []
    if c.hit_differs_far:
        out.append(f"coverage: {c.hit_differs_far} pixels differ in hit more than 1 px from "
                   "the reference silhouette")
    both = reference.hit & candidate.hit
    depth_max = float(np.abs(reference.depth[both] - candidate.depth[both]).max(initial=0.0))
    if not depth_max <= DEPTH_FLOAT64:
        out.append(f"depth where both hit: |dt| reaches {depth_max:.3g} > {DEPTH_FLOAT64:.0e}")
    if not interior_color_max(c) <= COLOR_FLOAT64:
        out.append(f"interior colour: {interior_color_max(c):.3g} > {COLOR_FLOAT64:.3g} "
                   "(one float32 ulp)")
    return out


def evidence(name, pair, reference, candidate, c, failed, color_bound, tmp_path) -> str:
    """Write the difference images and return the assertion message that names them."""
    written = write_difference_images(reference, candidate, Gates(color=color_bound), tmp_path)
    table = "\n".join(f"  {k} = {v}" for k, v in c.rows())
    return (f"{name}: {pair}:\n" + "\n".join(failed) + f"\n{table}\nimages: "
            + ", ".join(str(p) for p in written))


@pytest.mark.parametrize("name, scene, size", CASES, ids=IDS)
def test_opencl_float32_matches_numpy_float32_to_1e_3_in_colour(opencl, name, scene, size,
                                                                tmp_path):
    width, height = size
    reference = reference_frame(scene, width, height, "float32")
    candidate = render(scene, width, height, backend="opencl", precision="float32",
                       path_labels=True)
    c = compare_frames(reference, candidate, epsilon=scene.render.epsilon)
    failed = float32_failures(c)
    message = ""
    if failed:                      # write the evidence before the assertion reports it
        message = evidence(name, "opencl float32 vs numpy float32", reference, candidate, c,
                           failed, COLOR_FLOAT32, tmp_path)
    assert failed == [], message


@pytest.mark.parametrize("name, scene, size", CASES, ids=IDS)
def test_opencl_float64_matches_numpy_float64_to_1e_9_in_depth(opencl_float64, name, scene,
                                                               size, tmp_path):
    width, height = size
    reference = reference_frame(scene, width, height, "float64")
    candidate = render(scene, width, height, backend="opencl", precision="float64",
                       path_labels=True)
    c = compare_frames(reference, candidate, epsilon=scene.render.epsilon)
    failed = float64_failures(reference, candidate, c)
    message = ""
    if failed:
        message = evidence(name, "opencl float64 vs numpy float64", reference, candidate, c,
                           failed, COLOR_FLOAT64, tmp_path)
    assert failed == [], message


def test_the_float32_bound_catches_a_colour_error_the_gates_allow(opencl):
    """2e-3 on every colour passes the gates' 1/255 but fails the tight pair's 1e-3."""
    name, scene, (width, height) = CASES[0]
    reference = reference_frame(scene, width, height, "float32")
    frame = render(scene, width, height, backend="opencl", precision="float32",
                   path_labels=True)
    frame.color = np.clip(frame.color + np.float32(2e-3), 0, 1)
    c = compare_frames(reference, frame, epsilon=scene.render.epsilon)
    gates = failures(c, gates_against("float32"))
    assert not any(line.startswith("interior colour") for line in gates)
    assert any(line.startswith("interior colour") for line in float32_failures(c))


def test_the_float64_bounds_catch_a_depth_error_of_1e_8_and_a_colour_error_of_two_ulps(
        opencl_float64):
    """1e-8 on every depth passes the gates' max(2 epsilon, 1e-5 t) but fails 1e-9; two float32
    ulps (2**-23) on every colour fail the one-ulp bound."""
    name, scene, (width, height) = CASES[0]
    reference = reference_frame(scene, width, height, "float64")
    frame = render(scene, width, height, backend="opencl", precision="float64",
                   path_labels=True)
    frame.depth = frame.depth + 1e-8
    frame.color = np.clip(frame.color - np.float32(2.0 ** -23), 0, 1)
    c = compare_frames(reference, frame, epsilon=scene.render.epsilon)
    assert c.depth_excess <= 1
    failed = float64_failures(reference, frame, c)
    assert any(line.startswith("depth where both hit") for line in failed)
    assert any(line.startswith("interior colour") for line in failed)
