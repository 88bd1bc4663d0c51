"""Bounding spheres of SDF trees: a sphere that holds the whole solid of a shape.

Ray tracers have culled objects with bounding spheres since Whitted 1980: a ray that misses an
object's bounding sphere can never reach that object, so the march may leave it out of the
scene's distance. This module computes the spheres from the tree; the
ray test lives next to the march of each backend (`reference_cpu.culling`,
``glsl/culling.glsl``).

Each rule below assumes the primitives' distances are exact and follows what each operator
does to the solid (the set where the distance is <= 0):

- a union's solid is inside the sphere that encloses its children's spheres;
- an intersection's solid is inside each child's: the smallest is kept;
- a subtraction's solid is inside its first child's;
- Quilez's smooth union subtracts at most k/4 from min(d1, d2) (at h = 1/2), so its solid
  is within k/4 of the union's, and a fold over n children within (n - 1) k/4: the enclosing
  sphere grows by that much; the smooth intersection
  and subtraction only add to the distance, so they keep the sharp rules;
- a morph's (1 - t) d1 + t d2 is at least min(d1, d2), so its solid is inside the union's;
- transforms move, turn and scale the sphere; limited repetition encloses every copy.

A plane or an infinite repetition has no bounding sphere (None).
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import rotation_matrix
from .shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Intersection, Morph, Node,
                     Plane, Pyramid, Repeat, Rotate, RoundBox, Scale, SmoothIntersection,
                     SmoothSubtraction, SmoothUnion, Sphere, Subtraction, Torus, Translate, Union)

# A sphere as (centre (3,) float64 ndarray, radius), or None for an unbounded shape.
Sphere_ = tuple[np.ndarray, float] | None


def bounding_sphere(node: Node) -> Sphere_:
    """A sphere holding the solid of ``node``, or None where the solid is unbounded.

    Returns
    -------
    (centre (3,) ndarray, radius float) or None
    """
    origin = np.zeros(3)
    match node:
        case Sphere():
            return origin, node.radius
        case Box() | RoundBox():              # a round box's corners are inside the box's
            return origin, math.hypot(*node.half_size)
        case Torus():
            return origin, node.major_radius + node.minor_radius
        case CappedCylinder():
            return origin, math.hypot(node.radius, node.half_height)
        case Capsule():
            a, b = np.asarray(node.a, float), np.asarray(node.b, float)
            return (a + b) / 2, float(np.linalg.norm(b - a)) / 2 + node.radius
        case Cone():                          # base disc at y = 0, apex at y = height
            return np.array([0.0, node.height / 2, 0.0]), math.hypot(node.radius,
                                                                      node.height / 2)
        case Pyramid():                       # base corners at y = 0, apex at y = height
            return np.array([0.0, node.height / 2, 0.0]), math.hypot(node.base / math.sqrt(2),
                                                                      node.height / 2)
        case Disk():                          # the rounded rim reaches out to the radius
            return origin, node.radius
        case HexPrism():                      # the hexagon's corners are 2 apothem / sqrt(3) out
            return origin, math.hypot(2 * node.apothem / math.sqrt(3), node.half_length)
        case Plane():
            return None
        case Translate():
            inner = bounding_sphere(node.child)
            return None if inner is None else (inner[0] + node.offset, inner[1])
        case Rotate():
            inner = bounding_sphere(node.child)
            return None if inner is None else (rotation_matrix(node.degrees) @ inner[0],
                                               inner[1])
        case Scale():
            inner = bounding_sphere(node.child)
            return None if inner is None else (inner[0] * node.factor, inner[1] * node.factor)
        case Repeat(count=None):
            return None
        case Repeat():
            inner = bounding_sphere(node.child)
            if inner is None:
                return None
            reach = np.asarray(node.period, float) * np.asarray(node.count, float)
            return inner[0], inner[1] + float(np.linalg.norm(reach))   # the farthest copy
        case Union() | SmoothUnion() | Morph():
            parts = [bounding_sphere(c) for c in node.children]
            if any(part is None for part in parts):
                return None
            centre, radius = enclosing_sphere(parts)
            # Each of the n - 1 smooth minimums of the fold may dig up to k/4 further.
            dig = node.k / 4 * (len(parts) - 1) if isinstance(node, SmoothUnion) else 0.0
            return centre, radius + dig
        case Intersection() | SmoothIntersection():
            parts = [s for s in map(bounding_sphere, node.children) if s is not None]
            return min(parts, key=lambda s: s[1]) if parts else None
        case Subtraction() | SmoothSubtraction():
            return bounding_sphere(node.children[0])
    raise TypeError(f"no bounding-sphere rule for {type(node).__name__}")


def enclosing_sphere(spheres) -> tuple[np.ndarray, float]:
    """A sphere holding every sphere of ``spheres`` (a non-empty list of (centre, radius)).

    Not the smallest one (Welzl's algorithm finds that): centred on the mean of the centres,
    it reaches the farthest sphere's far side. Simple, and tight enough for culling.
    """
    centres = np.array([c for c, _ in spheres], dtype=float)
    centre = centres.mean(axis=0)
    radius = max(float(np.linalg.norm(c - centre)) + r for c, r in spheres)
    return centre, radius


def object_bounds(objects, margin: float) -> list[tuple[int, np.ndarray, float]]:
    """The bounded top-level objects of a scene: (object index, centre, radius + margin).

    ``margin`` widens every sphere; the march uses 2 epsilon, so that a ray that passes
    outside a sphere stays farther than epsilon from the solid inside it and could not
    have hit it (plain sphere tracing stops within epsilon of a surface).
    """
    bounds = []
    for index, node in enumerate(objects):
        sphere = bounding_sphere(node)
        if sphere is not None:
            bounds.append((index, sphere[0], sphere[1] + margin))
    return bounds
