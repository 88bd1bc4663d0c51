"""Shadows: is the way from a surface point to a light blocked?

A shadow ray starts at the surface point pushed out along the normal by ``surface_offset``
(without the push it would start inside the surface's own epsilon shell and find itself: shadow
acne). It is marched toward the light, no farther than the light.

A hard shadow ray may also leave out of its march the object it starts on, where that object
is convex (``render.shadow_skip_own``). A convex solid C lies on one side of its tangent
plane at any surface point q: C is inside {x : n . (x - q) <= 0}, n the outward normal. A ray
from q (or from q pushed out along n) toward a light with n . l > 0, the only rays cast, has
n . (q + t l - q) = t n . l > 0 for every t > 0: it never enters C, so C cannot block it and
its distance only holds the ray back. Left out, the ray no longer creeps away from its own
surface in steps as short as its height above it: on the classroom the shadow rays take a
third of the steps, and block exactly the same pixels (docs/sphere-tracing.md, "Shadow rays
that skip their own object"). The normal is an estimate; where it is off by more than the
angle between n and l, at grazing light whose diffuse term n . l is near 0 anyway, a ray
could pass through its own object's rim. Soft shadows keep their own object: its distance
along the ray is part of the penumbra k h / t they read.
"""

from __future__ import annotations

import numpy as np

from .march import march


def hard_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance,
                objects=None, **marching):
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
    objects : (N, K) bool ndarray, optional
        The objects each ray may meet (False: left out), as `reference_cpu.march.march`
        takes them: False at the convex object a ray starts on (`own_object_mask`).
    **marching
        ``relaxation``, ``omega``, ``bounds`` of `reference_cpu.march.march`.
    """
    limit = np.minimum(light_distance, max_distance)
    _, _, blocked = march(origins, to_light, sdf, max_steps, epsilon, limit, objects=objects,
                          **marching)
    return np.where(blocked, 0, 1).astype(origins.dtype)


def own_object_mask(own, count):
    """The objects mask of shadow rays that leave out their own object.

    Parameters
    ----------
    own : (N,) int ndarray
        The top-level object each ray starts on where it may be left out (convex, with a
        bit: `reference_cpu.culling.own_objects`), else -1.
    count : int
        The scene's number of top-level objects K.

    Returns
    -------
    (N, K) bool ndarray or None
        False at (i, own[i]); None where no ray leaves anything out.
    """
    rays = np.flatnonzero(own >= 0)
    if len(rays) == 0:
        return None
    objects = np.ones((len(own), count), dtype=bool)
    objects[rays, own[rays]] = False
    return objects


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
