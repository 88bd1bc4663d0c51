"""The reference sampled around each pixel's centre, for a hardware rasteriser's values.

A hardware rasteriser snaps vertices to 2^-b of a pixel and interpolates from the snapped
triangle, so each value it computes at a pixel centre is the exact one at a point up to
s = 2^-(b + 1) pixels away along each axis (`gpu_shader.context.subpixel_shift`: 2^-9 on an
NVIDIA H100, 0 on llvmpipe, which interpolates from the unsnapped positions). A test then
draws its reference four more times with the camera turned by (+-2 s, +-2 s) pixels
(`scene_model.camera.turned`), which at every pixel enclose the square of side 2 s about the
centre (tests/test_camera.py), and measures the GPU's value from the range the reference's
five values span (`marchlab.compare.outside_range`), as `marchlab.compare` does with whole
frames. On llvmpipe there are no turns: the test keeps its tolerances of float32 rounding.
"""

from __future__ import annotations

import numpy as np

from gpu_shader.context import gl_context, subpixel_shift


def shift() -> float:
    """s for the tests' GL context."""
    return subpixel_shift(gl_context())


def turns() -> list[tuple[float, float]]:
    """The four (dx, dy) turns in pixels, none where s is 0."""
    s = shift()
    return [(dx, dy) for dx in (-2 * s, 2 * s) for dy in (-2 * s, 2 * s)] if s else []


def around(draw) -> list:
    """``draw(dx, dy)`` for each of `turns`."""
    return [draw(dx, dy) for dx, dy in turns()]


def steady(references) -> np.ndarray:
    """(H, W): pixels where every reference raster shows the same object at about the same
    distance. Where an occluding edge passes between the turned samples, some of them fall
    on the surface behind and do not enclose the GPU's sample on the front one."""
    first = references[0]
    out = first.hit.copy()
    for other in references[1:]:
        with np.errstate(invalid="ignore"):
            out &= (other.object_id == first.object_id) & (
                np.abs(other.depth - first.depth) <= 1e-3 * first.depth)
    return out
