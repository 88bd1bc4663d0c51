"""Bounding-sphere culling: which objects can a ray reach at all?

Ray tracers have used bounding spheres since Whitted 1980: before marching a ray, test it
against each object's bounding sphere, and leave the objects it misses out of the scene's
distance for that whole march. Sphere tracing stays safe: the distance to the objects left in
is still a bound on how far the ray may go before it meets any of them, and the ray can meet
none of the others. Left out, a far object no longer holds a passing ray back, so rays that
pass close to an object without touching it take fewer steps.

The spheres come from `scene_model.bounds.object_bounds`, widened by 2 epsilon: a ray that passes
outside one stays farther than epsilon from the object, where the plain march would not have
stopped either. Unbounded objects (planes, infinite repetition) are always in. The GLSL and
OpenCL twin is ``glsl/culling.glsl``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.bounds import object_bounds
from scene_model.geometry import dot
from scene_model.shapes import is_convex, object_of_primitive

MAX_CULLED = 32     # objects with a sphere, at most: the shader keeps one bit per object


@dataclass(frozen=True)
class BoundingSpheres:
    """The culled objects of a scene in one precision.

    Attributes
    ----------
    count : int
        Number of top-level objects in the scene.
    index : (K,) int ndarray
        The object each sphere belongs to (K <= MAX_CULLED).
    centre : (K, 3) ndarray
    radius : (K,) ndarray
        Already widened by the margin.
    """
    count: int
    index: np.ndarray
    centre: np.ndarray
    radius: np.ndarray

    @classmethod
    def of(cls, objects, epsilon: float, dtype) -> BoundingSpheres:
        bounds = culled_bounds(objects, epsilon)
        as_dtype = lambda values: np.asarray(values, dtype=np.float64).astype(dtype)
        return cls(len(objects), np.array([i for i, _, _ in bounds], dtype=np.intp),
                   as_dtype([c for _, c, _ in bounds]).reshape(-1, 3),
                   as_dtype([r for _, _, r in bounds]))

    def objects_met(self, origins, directions) -> np.ndarray:
        """Which objects each ray may reach: (N, count) bool, True for unbounded objects."""
        n = len(directions)
        met = np.ones((n, self.count), dtype=bool)
        for k, index in enumerate(self.index):
            met[:, index] = ray_meets_sphere(origins, directions, self.centre[k],
                                             self.radius[k])
        return met


def culled_bounds(objects, epsilon: float) -> list[tuple[int, np.ndarray, float]]:
    """The spheres every backend culls with: `scene_model.bounds.object_bounds` widened by
    2 epsilon, the first `MAX_CULLED` of them."""
    return object_bounds(objects, 2 * epsilon)[:MAX_CULLED]


def object_bits(objects, epsilon: float, culling: bool, skip_own: bool) -> list[tuple]:
    """The top-level objects a march may leave out, one bit each: ``(index, centre, radius)``,
    centre and radius None for an object without a bounding sphere (always met).

    With ``culling`` these are the objects of `culled_bounds`; with ``skip_own`` (hard shadow
    rays leave out the convex object they start on, `reference_cpu.shadows`) the convex
    objects too, after them. At most `MAX_CULLED` in all, the shader's bits: an object
    without one is never left out, which is always safe. Every backend takes its bits from
    here, so all leave out the same objects.
    """
    bits = list(culled_bounds(objects, epsilon)) if culling else []
    if skip_own:
        have = {i for i, _, _ in bits}
        bits += [(i, None, None) for i, node in enumerate(objects)
                 if is_convex(node) and i not in have]
    return bits[:MAX_CULLED]


def own_objects(objects, bits) -> np.ndarray:
    """For each primitive (by object id), the convex top-level object with a bit in ``bits``
    (`object_bits`) that it belongs to, else -1: what its shadow rays leave out. (P,) int."""
    convex = {i for i, _, _ in bits if is_convex(objects[i])}
    return np.array([i if i in convex else -1 for i in object_of_primitive(objects)],
                    dtype=np.intp)


def ray_meets_sphere(origins, directions, centre, radius):
    """Does the ray o + t d, t >= 0, touch the sphere? (Ericson 2005, section 5.3.2)

    With oc = o - c, b = oc . d and c' = |oc|^2 - r^2, the ray's line meets the sphere where
    t^2 + 2 b t + c' = 0 has real roots (b^2 - c' >= 0). That alone also accepts a sphere
    behind the ray; a ray needs a root at t >= 0: it starts inside (c' <= 0), or the sphere
    lies ahead (b <= 0). Ericson's ``TestRaySphere`` makes the same two tests.

    Parameters
    ----------
    origins : (3,) or (N, 3) ndarray
    directions : (N, 3) ndarray
        Unit directions.
    centre : (3,) ndarray
    radius : scalar

    Returns
    -------
    (N,) bool ndarray
    """
    oc = origins - centre
    b = dot(oc, directions)
    c = dot(oc, oc) - radius * radius
    return (c <= 0) | ((b <= 0) & (b * b - c >= 0))
