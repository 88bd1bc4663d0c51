"""Real renders on the opencl backend against the reference renderer and analytic answers.

Every test takes the ``opencl_device`` fixture (tests/opencl/conftest.py) and is skipped, with
the reason, where pyopencl or a working OpenCL device is missing.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

import gpu_shader.opencl as opencl
from marchlab import MarchlabError
import marchlab
from scene_model.builder import Camera, Scene, sphere


# A camera on the z axis looking down -z at the origin, as in tests/gpu/test_gpu_backend.py.
CAMERA_Z = 5.0
CAMERA = Camera(position=(0.0, 0.0, CAMERA_Z), look_at=(0.0, 0.0, 0.0), fov=60.0)
SILHOUETTE_PIXELS = 3          # hit masks of two correct renderers may differ here, at most
# Odd sizes: the middle pixel's centre lies on the optical axis, and neither side is a
# multiple of the work-group (16 x 4), so the launch is padded in both directions.
WIDTH, HEIGHT = 33, 25


def ball_at(x: float, y: float, radius: float = 1.2) -> Scene:
    return Scene(objects=(sphere(radius).at(x, y, 0.0),), camera=CAMERA)


def hit_centroid_column(frame) -> float:
    return float(np.nonzero(frame.hit)[1].mean())


LAYOUT = {"color": np.float32, "steps": np.int32, "object_id": np.int32, "path": np.uint32,
          "hit": np.bool_}


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_sphere_frame_has_the_reference_layout_and_the_analytic_centre_depth(opencl_device,
                                                                             precision):
    """Ball of radius 1.2 at the origin, camera at z = 5: the middle ray hits at t = 3.8.

    Sphere tracing stops where the SDF is below epsilon, so the depth is within epsilon of
    the surface (and within 1e-5 t of rounding of it).
    """
    radius = 1.2
    scene = ball_at(0.0, 0.0, radius)
    frame = marchlab.render(scene, WIDTH, HEIGHT, backend="opencl", precision=precision,
                            path_labels=True)
    reference = marchlab.render(scene, WIDTH, HEIGHT, precision=precision, path_labels=True)
    assert (frame.backend, frame.precision) == ("opencl", precision)
    for name in ("color", "depth", "normal", "steps", "object_id", "hit", "path"):
        ours, theirs = getattr(frame, name), getattr(reference, name)
        assert (name, ours.shape, ours.dtype) == (name, theirs.shape, theirs.dtype)
        assert ours.shape[:2] == (HEIGHT, WIDTH)
    for name, dtype in LAYOUT.items():
        assert getattr(frame, name).dtype == dtype, name
    assert frame.depth.dtype == np.dtype(precision) and frame.normal.dtype == np.dtype(precision)
    assert 0 < frame.hit.sum() < frame.hit.size                 # the ball, and sky around it
    assert np.isinf(frame.depth[~frame.hit]).all() and (frame.object_id[~frame.hit] == -1).all()
    assert np.isfinite(frame.depth[frame.hit]).all() and (frame.object_id[frame.hit] == 0).all()
    assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS

    middle = (HEIGHT // 2, WIDTH // 2)
    exact = CAMERA_Z - radius
    epsilon = scene.render.epsilon
    assert frame.hit[middle]
    assert abs(float(frame.depth[middle]) - exact) <= max(epsilon, 1e-5 * exact)
    assert np.allclose(frame.normal[middle], (0.0, 0.0, 1.0), atol=1e-5)   # facing the camera


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_classroom_kernel_builds_and_draws_what_the_reference_draws(opencl_device, precision):
    scene = marchlab.load_scene("classroom")
    frame = marchlab.render(scene, 32, 24, backend="opencl", precision=precision)
    reference = marchlab.render(scene, 32, 24, precision=precision)
    assert frame.precision == precision
    assert (frame.hit != reference.hit).sum() <= SILHOUETTE_PIXELS
    agree = frame.hit & reference.hit
    assert agree.sum() > 0.25 * frame.hit.size                 # floor and spheres
    assert (frame.object_id[agree] == reference.object_id[agree]).mean() > 0.99
    sources = [source for source, p in opencl_device.programs if p == precision]
    real = "double" if precision == "float64" else "float"
    # shadow rays, marched one light at a time or two at once (glsl/shadow_pair.glsl)
    assert any(f"typedef {real} real;" in s and re.search(r"\bhard_shadow(_pair)?\(", s)
               for s in sources)


def test_progress_bands_draw_the_same_frame_as_one_launch(opencl_device):
    """Bands of rows with progress reports must leave no row undrawn.

    The ball fills the whole image (radius 4, 1 from the camera), and an empty scene is
    drawn first at the same size, so a band left out would show misses (or garbage).
    """
    scene = ball_at(0.0, 0.0, radius=4.0)
    marchlab.render(Scene(objects=(), camera=CAMERA), WIDTH, HEIGHT, backend="opencl")
    reports = []
    banded = marchlab.render(scene, WIDTH, HEIGHT, backend="opencl",
                             progress=lambda done, total: reports.append((done, total)))
    whole = marchlab.render(scene, WIDTH, HEIGHT, backend="opencl")
    assert whole.hit.all()
    for name in ("color", "depth", "normal", "steps", "object_id", "hit", "path"):
        assert np.array_equal(getattr(banded, name), getattr(whole, name)), name
    total = WIDTH * HEIGHT
    done = [d for d, _ in reports]
    assert len(reports) > 1 and all(t == total for _, t in reports)
    assert all(a < b for a, b in zip(done, done[1:]))           # strictly increasing
    assert all(d % WIDTH == 0 for d in done)                     # whole rows
    assert reports[-1] == (total, total)


def test_moving_an_object_reuses_the_built_program_and_moves_the_image(opencl_device):
    """Only parameters change when the ball moves from x = -0.8 to x = +0.8: no new build.

    The ball's centre projects to column W/2 + x * (H/2) / (z tan(fov/2)) - 0.5, so the hit
    region moves right by 1.6 of those pixels per unit (within a pixel: perspective widens
    both blobs alike).
    """
    first = marchlab.render(ball_at(-0.8, 0.0), WIDTH, HEIGHT, backend="opencl")
    built = list(opencl_device.programs)
    second = marchlab.render(ball_at(0.8, 0.0), WIDTH, HEIGHT, backend="opencl")
    assert list(opencl_device.programs) == built                # nothing compiled
    pixels_per_unit = (HEIGHT / 2) / (CAMERA_Z * math.tan(math.radians(30.0)))
    shift = hit_centroid_column(second) - hit_centroid_column(first)
    assert shift == pytest.approx(1.6 * pixels_per_unit, abs=1.0)


def test_float64_on_a_device_without_fp64_is_a_one_line_error(opencl_device, monkeypatch):
    no_fp64 = dataclasses.replace(opencl_device, fp64=False)
    monkeypatch.setattr(opencl, "_chosen", no_fp64)
    scene = ball_at(0.0, 0.0)
    with pytest.raises(MarchlabError) as caught:
        marchlab.render(scene, 8, 6, backend="opencl", precision="float64")
    message = str(caught.value)
    assert "\n" not in message and "cl_khr_fp64" in message and no_fp64.label in message
    assert "--precision float32" in message
    frame = marchlab.render(scene, 8, 6, backend="opencl", precision="float32")   # still fine
    assert frame.precision == "float32"
