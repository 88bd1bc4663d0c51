"""Shadows: is the way from a surface point to a light blocked?

A shadow ray starts at the surface point pushed out along the normal by ``surface_offset``
(without the push it would start inside the surface's own epsilon shell and find itself: shadow
acne). It is marched toward the light, no farther than the light.
"""

from __future__ import annotations

import numpy as np

from .march import march


def hard_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance,
                **marching):
    """1 where the light is visible, 0 where the shadow ray hits something first.

    The shadow ray is an ordinary march (`reference_cpu.march.march`) limited to the distance
    of the light. A ray that runs out of steps without hitting anything counts as lit.

    Parameters
    ----------
    origins : (N, 3) ndarray
        Surface points already offset along their normals.
    to_light : (N, 3) ndarray
        Unit directions toward the light.
    light_distance : (N,) ndarray
        Distance to the light (inf for a directional light).
    **marching
        ``relaxation``, ``omega``, ``bounds`` of `reference_cpu.march.march`.
    """
    limit = np.minimum(light_distance, max_distance)
    _, _, blocked = march(origins, to_light, sdf, max_steps, epsilon, limit, **marching)
    return np.where(blocked, 0, 1).astype(origins.dtype)


def soft_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance, k):
    """Penumbra estimate in [0, 1] (Quilez, "Soft shadows in raymarched SDFs", 2010).

    A ray that passes at distance h from a surface after travelling t clears it by an angle
    of about h/t: the smaller that is, the more of an area light the occluder would hide. So
    the shadow ray is an ordinary march that also keeps the smallest k h / t it sees; the
    light visible is that value clamped to [0, 1], and 0 if the ray hits something. Larger k
    gives harder shadows. The first sample, at t = 0, has not travelled yet and is skipped.
    """
    visible = np.ones(len(origins), dtype=origins.dtype)

    def penumbra(index, t, h, step):
        if step > 1:
            visible[index] = np.minimum(visible[index], k * h / t)

    limit = np.minimum(light_distance, max_distance)
    _, _, blocked = march(origins, to_light, sdf, max_steps, epsilon, limit, observe=penumbra)
    visible[blocked] = 0
    return np.clip(visible, 0, 1)
