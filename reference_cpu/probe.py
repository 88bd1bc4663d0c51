"""One pixel's march, step by step: what a viewer's probe and a lesson's plot show.

`probe_pixel` marches the primary ray of one pixel exactly as the reference renders it: the
same camera ray (scene_model.camera), SDF, settings, relaxation and culling (the `Tracer`
of render.py and `march` of march.py). At every step it records how far along the ray the
march stands (t) and the distance the SDF reports there, through march's ``observe`` hook.
Its step count and its last t are the frame's ``steps`` and ``depth`` at that pixel, bit for
bit (tests/test_probe.py), so the plot explains the number the steps heat map shows. (With
anti-aliasing the ray through the pixel's centre still gives its depth, but its steps are
the sum over all the pixel's rays: `scene_model.sampling`.)

Plain sphere tracing (Hart 1996) steps by the distance itself: t[k+1] = t[k] + d[k], and the
ray hits at the first step with d < epsilon or misses once t + d passes max_distance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.camera import camera_rays
from scene_model.scene import Scene

from .march import march
from .render import Tracer


@dataclass(frozen=True)
class MarchProbe:
    """The march of one pixel's primary ray.

    Attributes
    ----------
    t : (K,) ndarray
        Distance along the ray at each of the K SDF evaluations (m); t[0] = 0.
    distance : (K,) ndarray
        |SDF| at each of them (m).
    steps : int
        K, the SDF evaluations spent: the frame's ``steps`` at the pixel.
    hit : bool
    depth : float
        t where it hit (the frame's ``depth``), inf for a miss.
    """
    t: np.ndarray
    distance: np.ndarray
    steps: int
    hit: bool
    depth: float


def probe_pixel(scene: Scene, x: int, y: int, width: int, height: int,
                precision: str = "float64") -> MarchProbe:
    """March the primary ray of pixel (column ``x``, row ``y``, row 0 at the top) of a
    ``width`` x ``height`` render of ``scene`` (objects only, as `render.render` takes it),
    recording every step."""
    dtype = np.dtype(precision)
    origin, directions = camera_rays(scene.camera, width, height, dtype)
    direction = directions[y, x][None, :]
    tracer = Tracer(scene, dtype)
    settings = scene.render
    ts, distances = [], []

    def observe(index, t, distance, step):
        if len(index):                      # this one ray, while it is still marching
            ts.append(t[0])
            distances.append(distance[0])

    depth, steps, hit = march(origin, direction, tracer.sdf, settings.max_steps,
                              settings.epsilon, settings.max_distance, observe,
                              **tracer.marching)
    count = int(steps[0])
    return MarchProbe(t=np.array(ts[:count], dtype), distance=np.array(distances[:count], dtype),
                      steps=count, hit=bool(hit[0]), depth=float(depth[0]))
