"""The scene's static objects as colliders: the surface the renderer draws is the one balls hit.

Every top-level object of ``objects`` is static. A plane moved only by translations is an
exact plane of the world (`static_planes`); every other object, whatever its SDF (primitives,
CSG, smooth operators, repetition, transforms), becomes a `physics.colliders.Shape` whose
distance is the reference renderer's SDF of that object (`reference_cpu.scene_sdf`) and whose
normal is the renderer's own finite-difference gradient (`reference_cpu.normals`), so what a
ball rolls on is exactly what the picture shows. Restitution and friction come from the
material the renderer shows at the contact: its ``restitution`` and ``friction``, or the
``[physics]`` block's ``plane_restitution`` and ``plane_friction`` where it gives none.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings

import numpy as np

from physics.colliders import Shape
from physics.convex import ConvexSolid, convex_solid
from reference_cpu.normals import estimate_normal
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.bodies import PhysicsSettings
from scene_model.bounds import bounding_sphere
from scene_model.scene import Scene
from scene_model.shapes import Node, Plane, Repeat, Translate, children, primitives

# Central-difference step of the normal (m). In float32 a smaller step would lose the
# difference in rounding (positions near 10 m are rounded to 1e-6 m).
NORMAL_STEP = {np.dtype(np.float64): 1e-5, np.dtype(np.float32): 1e-3}


def plane_of(node: Node) -> tuple[tuple[float, float, float], float] | None:
    """(unit normal, offset) with ``n . x = offset`` if ``node`` is a plane moved only by
    translations, else None.

    A scene's plane is ``n/|n| . x = offset`` (reference_cpu.sdf.sdf_plane); moved by ``t`` it
    becomes ``n/|n| . x = offset + n/|n| . t``.
    """
    shift = np.zeros(3)
    while isinstance(node, Translate):
        shift += node.offset
        node = node.child
    if not isinstance(node, Plane):
        return None
    normal = np.asarray(node.normal) / math.sqrt(np.dot(node.normal, node.normal))
    return tuple(normal.tolist()), float(node.offset + normal @ shift)


def static_planes(scene: Scene) -> list[tuple[tuple[float, float, float], float]]:
    """The exact planes the bodies collide with: every top-level `plane_of` that no motion
    moves (a moving plane is a shape)."""
    moved = {motion.object for motion in scene.motions}
    return [plane for index, plane in enumerate(map(plane_of, scene.objects))
            if plane is not None and index not in moved]


def scene_shapes(scene: Scene, settings: PhysicsSettings, dtype=np.float64) -> list[Shape]:
    """Every top-level object that is not an exact plane, as a `Shape`, in scene order.

    Warns (one line each) for an object whose distance may overestimate, where a fast ball could
    pass into it: a repetition whose copies reach out of their cells (`unsafe_distance`).
    """
    dtype = np.dtype(dtype)
    motions = {motion.object: motion for motion in scene.motions}
    shapes = []
    for index in shape_indices(scene):
        node = scene.objects[index]
        name = f"objects[{index}]"
        problem = unsafe_distance(node)
        if problem is not None:
            warnings.warn(f"{name} ({node.kind}) as a collider: {problem}; balls may pass into "
                          "it", stacklevel=2)
        shape = object_shape(node, name, scene, settings, dtype)
        shapes.append(dataclasses.replace(shape, motion=motions.get(index)))
    return shapes


def shape_indices(scene: Scene) -> list[int]:
    """Indices in ``objects`` of the objects that become shapes, in the order of
    ``world.shapes``: all but the exact planes that no motion moves."""
    moved = {motion.object for motion in scene.motions}
    return [index for index, node in enumerate(scene.objects)
            if index in moved or plane_of(node) is None]


def shape_objects(scene: Scene) -> list[Node]:
    """The top-level objects that become shapes (`shape_indices`), in the order of
    `scene_shapes` and so of ``world.shapes``."""
    return [scene.objects[index] for index in shape_indices(scene)]


def primitive_coefficients(node: Node, scene: Scene,
                           settings: PhysicsSettings) -> tuple[np.ndarray, np.ndarray]:
    """Restitution and friction (K,) of each primitive of ``node`` in depth-first order (its
    object ids): its material's, or the [physics] table's plane_restitution and
    plane_friction where the material gives none."""
    restitution, friction = [], []
    for primitive in primitives([node]):
        material = scene.materials[primitive.material]
        restitution.append(settings.plane_restitution if material.restitution is None
                           else material.restitution)
        friction.append(settings.plane_friction if material.friction is None
                        else material.friction)
    return np.asarray(restitution), np.asarray(friction)


def object_shape(node: Node, name: str, scene: Scene, settings: PhysicsSettings,
                 dtype) -> Shape:
    """One object as a `Shape`: the renderer's SDF and normal, the materials' coefficients."""
    distance, normal, step = node_distance(node, dtype)
    with_ids = build_scene_sdf([node], dtype, with_ids=True)
    restitution, friction = (np.asarray(values, dtype)
                             for values in primitive_coefficients(node, scene, settings))

    def surface(p):
        # The id of the primitive whose distance the operators chose, as the renderer colours.
        ids = with_ids(np.asarray(p, dtype))[1]
        return restitution[ids], friction[ids]

    return Shape(name, distance, normal, float(restitution[0]), float(friction[0]), surface,
                 normal_step=step)


@functools.lru_cache(maxsize=64)
def body_solid(node: Node) -> ConvexSolid:
    """A convex body's solid (`physics.convex.convex_solid`): the renderer's SDF and normal
    of ``node`` in float64, so the body the step moves has the surface the picture shows; its
    mass, centre of mass, principal axes and surface samples computed from them. Kept per
    node: the same solid for the world and for drawing it where the world has it.

    Raises
    ------
    PhysicsError
        A solid without volume.
    """
    distance, normal, _ = node_distance(node, np.float64)
    centre, radius = bounding_sphere(node)
    return convex_solid(node.kind, distance, normal, centre - radius, centre + radius)


def node_distance(node: Node, dtype):
    """The renderer's signed distance of ``node`` (points (K, 3) -> (K,)) and its
    central-difference unit normal (points -> (K, 3)) in ``dtype``, and that normal's step
    (m, `NORMAL_STEP`)."""
    sdf = build_scene_sdf([node], dtype)
    step = NORMAL_STEP[np.dtype(dtype)]

    def distance(p):
        return sdf(np.asarray(p, dtype))[0]

    def normal(p):
        return estimate_normal(sdf, np.asarray(p, dtype), step)

    return distance, normal, step


def unsafe_distance(node: Node) -> str | None:
    """Why the SDF of ``node`` may overestimate the distance, or None where it is a bound.

    Repetition folds space into one cell, so it gives the distance to the copy in the point's
    own cell only: where a copy reaches past its cell's wall into the next cell, a point there
    does not see it, and the distance overestimates (Quilez, "Domain repetition", 2023). The
    test samples the repeated shape's SDF on its cell's walls (a `WALL_SAMPLES` grid over the
    part its bounding sphere could reach): a negative distance there means it crosses the wall.
    Every other node of the scene format keeps the distance a lower bound.
    """
    if isinstance(node, Repeat):
        bound = bounding_sphere(node.child)
        if bound is not None:
            centre, radius = bound
            sdf = build_scene_sdf([node.child])
            for axis, period in enumerate(node.period):
                if period and abs(centre[axis]) + radius > period / 2:
                    depth = _deepest_on_walls(sdf, centre, radius, axis, period / 2)
                    if depth < 0:
                        return (f"its copies reach {-depth:.3g} past their cells' walls along "
                                f"{'xyz'[axis]} (period {period:.3g})")
    for child in children(node):
        problem = unsafe_distance(child)
        if problem is not None:
            return problem
    return None


WALL_SAMPLES = 65      # points along each side of the square sampled on a cell wall


def _deepest_on_walls(sdf, centre, radius, axis, half) -> float:
    """Least distance of ``sdf`` over the two planes x_axis = +-half, within the square that
    the bounding sphere (centre, radius) covers there."""
    others = [k for k in range(3) if k != axis]
    u = np.linspace(-radius, radius, WALL_SAMPLES)
    a, b = np.meshgrid(centre[others[0]] + u, centre[others[1]] + u, indexing="ij")
    deepest = np.inf
    for wall in (-half, half):
        p = np.zeros((a.size, 3))
        p[:, axis], p[:, others[0]], p[:, others[1]] = wall, a.ravel(), b.ravel()
        deepest = min(deepest, float(np.min(sdf(p)[0])))
    return deepest
