"""Shadows: is the way from a surface point to a light blocked?

A shadow ray starts at the surface point pushed out along the normal by ``surface_offset``
(without the push it would start inside the surface's own epsilon shell and find itself: shadow
acne). It is marched toward the light, no farther than the light.
"""

from __future__ import annotations

import numpy as np

from .march import march


def hard_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance):
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
    """
    limit = np.minimum(light_distance, max_distance)
    _, _, blocked = march(origins, to_light, sdf, max_steps, epsilon, limit)
    return np.where(blocked, 0, 1).astype(origins.dtype)


def soft_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance, k):
    """Penumbra estimate in [0, 1] (Quilez, "Soft shadows in raymarched SDFs", 2010).

    While marching, a ray that passes at distance h from a surface after travelling t is
    "almost blocked" by the ratio h/t (the angle it clears the occluder by); the light
    visible is the smallest k h / t seen, clamped to [0, 1]. A hit (h < epsilon) means 0.
    The first sample, at t = 0, has not travelled yet and gives no ratio. It uses the same
    stepping rules as `march`.
    """
    dtype = origins.dtype
    n = len(origins)
    visible = np.ones(n, dtype=dtype)
    limit = np.minimum(light_distance, max_distance).astype(dtype)

    index = np.arange(n)
    o, d, t, lim = origins, to_light, np.zeros(n, dtype=dtype), limit
    for step in range(max_steps):
        h = sdf(o + t[:, None] * d)[0]
        if step > 0:
            visible[index] = np.minimum(visible[index], k * h / t)
        blocked = h < epsilon
        visible[index[blocked]] = 0
        t = t + np.abs(h)
        keep = ~blocked & (t <= lim)
        index, o, d, t, lim = index[keep], o[keep], d[keep], t[keep], lim[keep]
        if index.size == 0:
            break
    return np.clip(visible, 0, 1)
