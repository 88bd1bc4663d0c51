"""The three planes a generated program writes per pixel, the `Frame` they make, and the bands
of rows a program is run in when progress is reported.

The GLSL shader writes them into three render targets, the OpenCL kernel into three buffers
of 4-vectors (``glsl/main.frag``, ``glsl/main.cl``):

    0  colour r, g, b in [0, 1]; 1 on a hit, 0 on a miss
    1  unit normal x, y, z; depth t (inf on a miss)
    2  SDF evaluations; object id (-1 on a miss); path label (24 bits); 0

With anti-aliasing (``render.samples`` > 1) the colour is the mean of the pixel's samples, the
evaluations the sum over all its rays, and the rest the ray through its centre's
(glsl/pipeline/samples.glsl).

Each plane is (H, W, 4), row 0 at the top of the image. Planes 0 and 1 are float; plane 2 is
int32 where the program can write integers (GLSL, an RGBA32I target) and float in OpenCL,
where all three share one buffer type. The program writes every value in its final form, so
the Frame is views of the planes, plus integer casts of a float plane 2.
"""

from __future__ import annotations

import numpy as np

from scene_model.frame import Frame
from scene_model.sampling import pixel_max_steps
from scene_model.scene import Scene

BANDS = 8              # with a progress callback, a program runs in this many bands of rows


def frame_from_planes(planes, scene: Scene, backend: str, precision: str) -> Frame:
    """The `Frame` held by ``planes``: a (3, H, W, 4) float array, or three (H, W, 4) arrays
    whose last is int32 (no casts needed)."""
    color_hit, normal_depth, steps_id = planes
    labels = steps_id[..., 2]
    return Frame(color=color_hit[..., :3].astype(np.float32, copy=False),
                 depth=normal_depth[..., 3],
                 normal=normal_depth[..., :3],
                 steps=steps_id[..., 0].astype(np.int32, copy=False),
                 object_id=steps_id[..., 1].astype(np.int32, copy=False),
                 hit=color_hit[..., 3] > 0.5, gamma=scene.render.gamma,
                 max_steps=pixel_max_steps(scene.render.max_steps, scene.render.samples),
                 dither=scene.render.dither,
                 path=(labels.view(np.uint32) if labels.dtype == np.int32
                       else labels.astype(np.uint32)),
                 backend=backend, precision=precision)


def row_bands(height: int, progress) -> list[tuple[int, int]]:
    """(start, stop) rows per launch: the whole image at once, or `BANDS` bands when a
    progress callback wants reports along the way."""
    if progress is None:
        return [(0, height)]
    rows = -(-height // BANDS)
    return [(start, min(start + rows, height)) for start in range(0, height, rows)]
