"""A scene as a union of *parts*: the subtrees that the ground truth intersects one at a time.

The scene is the union of its top-level objects (docs/scene-format.md), and a ``union`` node is
a union too, so both are taken apart; translate, rotate and scale nodes around them are folded
into one similarity transform per part. What is left at the bottom, a *leaf*, is a primitive
(which `reference_cpu.truth.analytic` intersects exactly and `reference_cpu.truth.mesh`
tessellates) or any other subtree (which the mesher samples and meshes as a whole).

A part places its leaf in the world by the similarity x = offset + scale * R @ x_local; a
point p of the world is x_local = R^T (p - offset) / scale in the leaf's frame, and distances
in the leaf's frame are multiplied by ``scale`` to be world distances.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.geometry import rotation_matrix
from scene_model.scenefile import SHORTHAND
from scene_model.shapes import Node, Rotate, Scale, Translate, Union, primitives

from ..scene_sdf import build_scene_sdf


@dataclass(frozen=True)
class Part:
    """One leaf of the scene's union and where it stands in the world.

    Attributes
    ----------
    leaf : scene_model.shapes.Node
        A primitive, or a subtree that is neither a union nor a translate/rotate/scale.
    path : tuple
        Where ``leaf`` sits in the scene file, e.g. ``("objects", 2)``, for error messages.
    first_id : int
        Object id of the first primitive under ``leaf`` (depth-first, as
        `scene_model.shapes.primitives` numbers them).
    rotation : (3, 3) ndarray
        R, float64.
    scale : float
        Uniform scale factor s.
    offset : (3,) ndarray
        Translation, float64.
    """
    leaf: Node
    path: tuple
    first_id: int
    rotation: np.ndarray
    scale: float
    offset: np.ndarray

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) in the leaf's frame: R^T (p - offset) / s."""
        return (points - self.offset) @ self.rotation / self.scale

    def direction_to_local(self, directions: np.ndarray) -> np.ndarray:
        """World directions (..., 3) in the leaf's frame, R^T d / s (not renormalised, so
        that a ray's parameter t is the same in both frames)."""
        return directions @ self.rotation / self.scale

    def to_world(self, points: np.ndarray) -> np.ndarray:
        """Leaf-frame points (..., 3) in the world: offset + s R x."""
        return self.offset + self.scale * points @ self.rotation.T

    def normal_to_world(self, normals: np.ndarray) -> np.ndarray:
        """Leaf-frame unit normals (..., 3) in the world: R n (a uniform scale keeps them)."""
        return normals @ self.rotation.T


def scene_parts(objects) -> list[Part]:
    """The parts of the union of ``objects`` (a sequence of `Node`), in object-id order."""
    parts: list[Part] = []
    next_id = 0
    for index, node in enumerate(objects):
        for part in _parts(node, ("objects", index), np.eye(3), 1.0, np.zeros(3), next_id):
            parts.append(part)
        next_id += sum(1 for _ in primitives([node]))
    return parts


def _parts(node, path, rotation, scale, offset, first_id):
    """Yield the parts under ``node``, whose frame is placed by (rotation, scale, offset)."""
    # The path names the table in the scene file: its shorthand keys (position, rotation,
    # scale) become an outer translate(rotate(scale(...))) chain that shares the table's path,
    # as scene_model.scenefile writes and reads it. Other transform nodes add ".child".
    for cls, _ in SHORTHAND.values():
        if type(node) is cls:
            rotation, scale, offset = _fold(node, rotation, scale, offset)
            node = node.child
    while isinstance(node, (Translate, Rotate, Scale)):
        rotation, scale, offset = _fold(node, rotation, scale, offset)
        node, path = node.child, path + ("child",)
    if isinstance(node, Union):
        for i, child in enumerate(node.children):
            yield from _parts(child, path + ("children", i), rotation, scale, offset, first_id)
            first_id += sum(1 for _ in primitives([child]))
        return
    yield Part(node, path, first_id, rotation, float(scale), offset)


def _fold(node, rotation, scale, offset):
    """Compose one transform node into the placement x = offset + scale R x_local.

    The child of a transform sits in the frame x_parent = offset_n + x (translate),
    M x (rotate, M = Rz Ry Rx) or f x (scale), so each folds in on the right.
    """
    if isinstance(node, Translate):
        return rotation, scale, offset + scale * rotation @ np.asarray(node.offset, float)
    if isinstance(node, Rotate):
        return rotation @ rotation_matrix(node.degrees), scale, offset
    return rotation, scale * node.factor, offset


def part_sdf(part: Part):
    """The exact world SDF of one part: ``f(points (N, 3)) -> (distance (N,), object id (N,))``.

    The leaf's SDF (`reference_cpu.scene_sdf`, float64) at the points moved into its frame,
    times the scale; the ids are the leaf's depth-first ids shifted by ``part.first_id``.
    """
    leaf_sdf = build_scene_sdf([part.leaf], np.float64, with_ids=True)

    def sdf(points):
        distance, ids = leaf_sdf(part.to_local(points))
        return distance * part.scale, ids + part.first_id
    return sdf
