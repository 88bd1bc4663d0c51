"""The distance to a whole scene: the SDF tree turned into one Python function.

`build_scene_sdf` walks the tree once and returns a function ``sdf(p)`` that evaluates it over
points ``p : (N, 3)``. Parameters are converted to the render's dtype up front, as a shader
receives them as uniforms. Each primitive's object id is its depth-first index
(`scene_model.shapes.primitives`); at any point the id is that of the primitive whose distance the
operators chose (the nearer one for a union, the farther one for an intersection, the one
that weighs more in a morph).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from scene_model.geometry import rotation_matrix
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Intersection,
                                Morph, Node, Plane, Pyramid, Repeat, Rotate, RoundBox, Scale,
                                SmoothIntersection, SmoothSubtraction, SmoothUnion, Sphere,
                                Subtraction, Torus, Translate, Union)

from . import sdf as S
from .march import columns

# sdf(p) -> (distance (N,), object id (N,) int or None when ids were not asked for)
SDF = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray | None]]

# The distance of each binary operator, and whether it keeps the id of the first argument.
_COMBINE = {
    Union: (lambda a, b, k: S.op_union(a, b), lambda a, b: a <= b),
    Intersection: (lambda a, b, k: S.op_intersection(a, b), lambda a, b: a >= b),
    Subtraction: (lambda a, b, k: S.op_subtraction(a, b), lambda a, b: a >= -b),
    SmoothUnion: (S.op_smooth_union, lambda a, b: a <= b),
    SmoothIntersection: (S.op_smooth_intersection, lambda a, b: a >= b),
    SmoothSubtraction: (S.op_smooth_subtraction, lambda a, b: a >= -b),
}


def build_scene_sdf(objects, dtype=np.float64, with_ids: bool = False) -> SDF:
    """The SDF of the union of ``objects`` (a sequence of `Node`) as a function of points.

    With ``with_ids`` the function also returns the object id at each point; without, it
    skips that bookkeeping (marching needs only distances) and returns None for the ids.

    The function is ``sdf(p, objects=None)``. ``objects``, an (N, len(objects)) bool array,
    leaves object j out of point i's union where ``objects[i, j]`` is False (bounding-sphere
    culling, `reference_cpu.culling`): its distance counts as inf there, and it is
    evaluated only at the points that keep it.
    """
    dtype = np.dtype(dtype)
    next_id = iter(range(1 << 30))
    parts = [_build(node, dtype, with_ids, next_id) for node in objects]

    def scene_sdf(p, objects=None):
        d, ids = _empty(len(p), dtype, with_ids)
        # The union of the objects, folded left to right like a Union node (see _COMBINE).
        for j, part in enumerate(parts):
            d2, ids2 = part(p) if objects is None else _where_kept(part, p, objects[:, j],
                                                                    dtype, with_ids)
            if with_ids:
                ids = np.where(d <= d2, ids, ids2) if j else ids2
            d = S.op_union(d, d2) if j else d2
        return d, ids
    return scene_sdf


def _empty(n, dtype, with_ids):
    """What a point sees with no object: distance inf, object id -1."""
    return np.full(n, np.inf, dtype=dtype), np.full(n, -1, np.int32) if with_ids else None


def _where_kept(part, p, kept, dtype, with_ids):
    """``part(p)`` where ``kept`` (N,) is True, (inf, -1) elsewhere."""
    if kept.all():
        return part(p)
    d, ids = _empty(len(p), dtype, with_ids)
    if kept.any():
        d[kept], part_ids = part(columns(p[kept]))
        if with_ids:
            ids[kept] = part_ids
    return d, ids


def _build(node: Node, dtype: np.dtype, with_ids: bool, next_id) -> SDF:
    """The SDF of ``node``; ``next_id`` hands out object ids in depth-first order."""
    f = dtype.type                                   # scalars in the render's precision

    def vec(v):                                      # vectors in the render's precision
        return np.asarray(v, dtype=np.float64).astype(dtype)

    def leaf(distance):
        object_id = next(next_id)
        if not with_ids:
            return lambda p: (distance(p), None)
        return lambda p: (distance(p), np.full(len(p), object_id, dtype=np.int32))

    def child():
        return _build(node.child, dtype, with_ids, next_id)

    match node:
        case Sphere():
            r = f(node.radius)
            return leaf(lambda p: S.sdf_sphere(p, r))
        case Box():
            b = vec(node.half_size)
            return leaf(lambda p: S.sdf_box(p, b))
        case RoundBox():
            b, r = vec(node.half_size), f(node.radius)
            return leaf(lambda p: S.sdf_round_box(p, b, r))
        case Plane():
            n = vec(np.divide(node.normal, np.linalg.norm(node.normal)))
            h = f(node.offset)
            return leaf(lambda p: S.sdf_plane(p, n, h))
        case Torus():
            big, small = f(node.major_radius), f(node.minor_radius)
            return leaf(lambda p: S.sdf_torus(p, big, small))
        case CappedCylinder():
            r, h = f(node.radius), f(node.half_height)
            return leaf(lambda p: S.sdf_capped_cylinder(p, r, h))
        case Capsule():
            a, b, r = vec(node.a), vec(node.b), f(node.radius)
            return leaf(lambda p: S.sdf_capsule(p, a, b, r))
        case Cone():
            r, h = f(node.radius), f(node.height)
            return leaf(lambda p: S.sdf_cone(p, r, h))
        case Pyramid():
            b, h = f(node.base), f(node.height)
            return leaf(lambda p: S.sdf_pyramid(p, b, h))
        case Disk():
            r, t = f(node.radius), f(node.thickness)
            return leaf(lambda p: S.sdf_disk(p, r, t))
        case HexPrism():
            a, h = f(node.apothem), f(node.half_length)
            return leaf(lambda p: S.sdf_hex_prism(p, a, h))
        case Translate():
            inner, offset = child(), vec(node.offset)
            return lambda p: inner(S.op_translate(p, offset))
        case Rotate():
            inner, matrix = child(), vec(rotation_matrix(node.degrees))
            return lambda p: inner(S.op_rotate(p, matrix))
        case Scale():
            inner, s = child(), f(node.factor)
            return lambda p: _scaled(inner(S.op_scale(p, s)), s)
        case Repeat(count=None):
            inner, period = child(), vec(node.period)
            return lambda p: inner(S.op_repeat(p, period))
        case Repeat():
            inner, period, count = child(), vec(node.period), vec(node.count)
            return lambda p: inner(S.op_repeat_limited(p, period, count))
        case Morph():
            return _morph(node, f(node.t), dtype, with_ids, next_id)

    combine, keeps_first = _COMBINE[type(node)]
    parts = [_build(c, dtype, with_ids, next_id) for c in node.children]
    k = f(getattr(node, "k", 0.0))

    def combined(p):
        d, ids = parts[0](p)
        for part in parts[1:]:
            d2, ids2 = part(p)
            if with_ids:
                ids = np.where(keeps_first(d, d2), ids, ids2)
            d = combine(d, d2, k)
        return d, ids
    return combined


def _morph(node, t, dtype, with_ids, next_id) -> SDF:
    """The blend of the two children; the object id is the first child's where t <= 1/2 (it
    weighs at least as much), the second's above: one id for the whole shape, at any t."""
    first = _build(node.children[0], dtype, with_ids, next_id)
    second = _build(node.children[1], dtype, with_ids, next_id)

    def morphed(p):
        (d1, ids1), (d2, ids2) = first(p), second(p)
        return S.op_morph(d1, d2, t), ids1 if t <= 0.5 else ids2
    return morphed


def _scaled(result, factor):
    d, ids = result
    return d * factor, ids
