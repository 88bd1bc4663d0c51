"""Every candidate backend against the NumPy reference, pixel by pixel.

For each bundled scene and each feature case (`cases.py`), the candidate's float32 frame is
compared with the reference rendered in float32 and in float64, and must pass the gates of
`marchlab.compare` (Khronos CTS / Firefox reftest practice):

1. coverage: hit flags differ only within 1 px of the reference silhouette, on <= 0.05% of
   pixels (likewise the path labels, within 1 px of a discontinuity; 0.1% for the bundled
   glass scene, `cases.PATH_FRACTION`);
2. interior (hit in both, 2 px from any edge): |dt| <= max(2 epsilon, 1e-5 t), normals
   within 0.5 degrees, colour within 1/255 of float32 and 2/255 of float64;
3. display: 8-bit images within 1 level outside the excused pixels.

On failure the two images, an amplified difference and the error mask are written to the
test's tmp_path and named in the message.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from marchlab import render
from marchlab.compare import compare_frames, failures, gates_against, write_difference_images

from .cases import PATH_FRACTION, all_cases
from .conftest import TRENDS, reference_frame

CASES = all_cases()


@pytest.mark.parametrize("reference_precision", ["float32", "float64"])
@pytest.mark.parametrize("name, scene, size", CASES, ids=[c[0] for c in CASES])
def test_backend_matches_reference_within_gates(backend, name, scene, size,
                                                reference_precision, tmp_path):
    width, height = size
    reference = reference_frame(scene, width, height, reference_precision)
    candidate = render(scene, width, height, backend=backend, precision="float32",
                       path_labels=True)
    c = compare_frames(reference, candidate, epsilon=scene.render.epsilon)
    TRENDS.append((name, backend, reference_precision, c.psnr, c.ssim))
    gates = gates_against(reference_precision)
    if name in PATH_FRACTION:
        gates = dataclasses.replace(gates, path_fraction=PATH_FRACTION[name])
    failed = failures(c, gates)
    message = ""
    if failed:                      # write the evidence before the assertion reports it
        written = write_difference_images(reference, candidate, gates, tmp_path)
        table = "\n".join(f"  {k} = {v}" for k, v in c.rows())
        message = (f"{name}: {backend} float32 vs numpy {reference_precision}:\n"
                   + "\n".join(failed) + f"\n{table}\nimages: "
                   + ", ".join(str(p) for p in written))
    assert failed == [], message


@pytest.mark.parametrize("name, scene, size", CASES[:1], ids=[CASES[0][0]])
def test_buffers_have_the_reference_layout(backend, name, scene, size):
    """Same shapes, dtypes and miss conventions as the reference frame."""
    width, height = size
    reference = reference_frame(scene, width, height, "float32")
    frame = render(scene, width, height, backend=backend, path_labels=True)
    for field in ("color", "depth", "normal", "steps", "object_id", "hit", "path"):
        a, b = getattr(reference, field), getattr(frame, field)
        assert b.shape == a.shape, field
        assert b.dtype == a.dtype, field
    assert np.all(np.isinf(frame.depth[~frame.hit]))
    assert np.all(frame.object_id[~frame.hit] == -1)
    assert np.all(frame.normal[~frame.hit] == 0)
    assert frame.precision == "float32" and frame.backend == backend


def test_the_gates_catch_a_colour_error_of_two_levels(backend):
    """The suite can fail: a frame 2/255 too bright in its interior fails the colour gate."""
    name, scene, (width, height) = CASES[0]
    reference = reference_frame(scene, width, height, "float32")
    frame = render(scene, width, height, backend=backend, path_labels=True)
    frame.color = np.clip(frame.color + np.float32(2 / 255), 0, 1)
    failed = failures(compare_frames(reference, frame, epsilon=scene.render.epsilon),
                      gates_against("float32"))
    assert any(line.startswith("interior colour") for line in failed)
    assert any(line.startswith("display") for line in failed)
