"""The moving part of a scene: the ``[physics]`` settings and the dynamic bodies, ``[[bodies]]``.

A `Body` is a solid sphere, box, capsule or any convex solid of the scene's nodes that the
physics module moves and every renderer draws. It is plain data like the rest of the scene:
`body_node` is the object drawn for it, and `scene_model.scene` puts the bodies into a scene
(`scene_objects`, `scene_at`). Stepping the world is the physics engine's job (physics/,
driven by marchlab/simulation.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .errors import SceneError
from .fields import (MAX_DEGREES, MAX_SPEED, POINT, SIZE, SIZES, Each, Range, Record, Vec3, param,
                     unit_interval)
from .bounds import bounding_sphere
from .shapes import Box, Capsule, Node, Rotate, Sphere, Translate, children, is_convex

# The names of the time-stepping schemes and contact solvers, here once: the scene format
# accepts them, and physics.INTEGRATORS and physics.SOLVERS are keyed by them.
INTEGRATOR_NAMES = ("semi_implicit", "explicit", "verlet")
SOLVER_NAMES = ("sequential", "simultaneous")
BODY_SHAPES = ("sphere", "box", "capsule", "convex")   # physics.solids.KIND_NAMES, in order
Integrator = Literal[INTEGRATOR_NAMES]
Solver = Literal[SOLVER_NAMES]
BodyShape = Literal[BODY_SHAPES]

# Ranges of the physical quantities (SI units), chosen so that every product the step forms
# (m v, 1 / m, r^2 w) stays far inside float32's range, as the GPU step needs.
MIN_DT, MAX_DT = 1e-6, 0.1          # s: a tenth of a second already skips through thin contacts
DT = Range(MIN_DT, MAX_DT, positive=True)
GRAVITY = Each(Range(-1000.0, 1000.0))                 # m/s^2: about 100 g each way
FRICTION = Range(0.0, 10.0)                            # rubber on concrete is about 1
DENSITY = Range(1e-3, 1e6, positive=True)              # kg/m^3: lighter than any gas to 1e6
MASS = Range(1e-6, 1e9, positive=True)                 # kg: a milligram to a million tonnes
VELOCITY = Each(Range(-MAX_SPEED, MAX_SPEED))


@dataclass(frozen=True)
class PhysicsSettings(Record):
    """How the bodies are stepped (see physics.World), and the values a body may leave out."""
    gravity: Vec3 = param((0.0, -9.81, 0.0), "Acceleration of gravity (m/s^2).", GRAVITY)
    dt: float = param(1 / 240, "Fixed time step (s); never tied to the frame rate.", DT)
    integrator: Integrator = param("semi_implicit", "Explicit Euler, semi-implicit "
                                                    "(symplectic) Euler or velocity Verlet.")
    solver: Solver = param("sequential", "Contact solver: Gauss-Seidel (sequential) or "
                                         "Jacobi (simultaneous, as the GPU step does).")
    seed: int = param(0, "Seeds the small random offset given to a body spawned on "
                         "another's centre.",
                   Range(0, 2**63 - 1, allowed="[0, 2^63 - 1]"))
    restitution: float = param(0.5, "Coefficient of restitution of a body that gives none.",
                               unit_interval)
    friction: float = param(0.5, "Coefficient of friction of a body that gives none.",
                            FRICTION)
    density: float = param(1000.0, "Density (kg/m^3) of a body that gives neither mass nor "
                                    "density (1000: water).", DENSITY)
    plane_restitution: float = param(0.0, "Coefficient of restitution of the static planes "
                                          "(a pair bounces with the larger of its two).",
                                     unit_interval)
    plane_friction: float = param(0.5, "Coefficient of friction of the static planes (a pair "
                                       "slides with the geometric mean of its two).",
                                  FRICTION)


@dataclass(frozen=True)
class Body(Record):
    """A dynamic solid sphere, box, capsule or convex solid: moved by the physics step and drawn
    as itself."""
    shape: BodyShape = param("sphere", "Its shape: a sphere of ``radius``, a box of "
                                       "``half_size``, a capsule: the points within "
                                       "``radius`` of a segment 2 ``half_length`` long along "
                                       "its own y axis, or ``convex``: the solid of ``solid``.")
    position: Vec3 = param((0.0, 1.0, 0.0), "Centre at t = 0 (m); for a convex body, where "
                                            "its solid's origin is.", POINT)
    velocity: Vec3 = param((0.0, 0.0, 0.0), "Velocity at t = 0 (m/s).", VELOCITY)
    angular_velocity: Vec3 = param((0.0, 0.0, 0.0), "Angular velocity at t = 0 (rad/s).",
                                   VELOCITY)
    radius: float = param(0.25, "Radius (m) of a sphere or a capsule.", SIZE)
    half_size: Vec3 = param((0.25, 0.25, 0.25), "Half the extent of a box along its own x, y, "
                                                "z (m).", SIZES)
    half_length: float = param(0.25, "Half the length of a capsule's segment (m).", SIZE)
    rotation: Vec3 = param((0.0, 0.0, 0.0), "Orientation of a box, capsule or convex body at "
                                            "t = 0: Euler angles in degrees, R = Rz Ry Rx as "
                                            "for rotate.",
                           Each(Range(-MAX_DEGREES, MAX_DEGREES)))
    solid: Node | None = param(None, "A convex body's solid: any bounded convex object of "
                                     "the scene format (a primitive but the torus and the "
                                     "plane, moved, turned, scaled or intersected), drawn "
                                     "with its own materials. Its mass is spread evenly.")
    mass: float | None = param(None, "Mass (kg); absent: from density.", MASS)
    density: float | None = param(None, "Density (kg/m^3), mass = density times the "
                                         "volume; absent: [physics] density.", DENSITY)
    restitution: float | None = param(None, "Coefficient of restitution e; absent: "
                                            "[physics] restitution.", unit_interval)
    friction: float | None = param(None, "Coefficient of friction mu; absent: "
                                         "[physics] friction.", FRICTION)
    material: str = param("default", "Name of a material in the scene's [materials] table.")

    def check(self):
        if self.mass is not None and self.density is not None:
            raise SceneError("give mass or density, not both", ("density",))
        if self.shape != "convex":
            if self.solid is not None:
                raise SceneError(f"only a convex body has a solid (this body's shape is "
                                 f"{self.shape!r})", ("solid",))
            return
        if self.solid is None:
            raise SceneError("a convex body needs a solid (a table with a type, such as "
                             "{ type = \"cone\", radius = 0.3, height = 0.6 })", ("solid",))
        problem = convex_problem(self.solid)
        if problem is not None:
            raise SceneError(problem, ("solid",))


def convex_problem(node: Node) -> str | None:
    """Why ``node`` cannot be a convex body's solid, or None: it must be convex
    (`shapes.is_convex`: a union, subtraction, blend, morph, repetition or torus is not) and
    bounded (a plane is not). The node named is the innermost one at fault."""
    if not is_convex(node):
        culprit = _first(node, lambda n: not is_convex(n))
        return (f"{_a(culprit.kind)} is not convex: a convex body's solid is a primitive "
                "other than a torus, moved, turned, scaled or intersected with others")
    if bounding_sphere(node) is None:
        culprit = _first(node, lambda n: bounding_sphere(n) is None)
        return f"{_a(culprit.kind)} is not bounded: a body needs a finite solid"
    return None


def _first(node: Node, bad) -> Node:
    """The innermost node of ``node``'s tree for which ``bad`` holds, ``bad(node)`` being
    true: the first such child's, depth first, or ``node`` itself."""
    for child in children(node):
        if bad(child):
            return _first(child, bad)
    return node


def _a(kind: str) -> str:
    """'a union', 'an intersection' (a u sounded 'you' takes 'a')."""
    return f"{'an' if kind[0] in 'aeio' else 'a'} {kind}"


def body_node(body: Body, position=None, rotation=None) -> Node:
    """The object drawn for ``body``: a sphere of its radius, or its box, capsule or convex
    solid turned by ``rotation`` (Euler degrees), translated to ``position`` (defaults: the
    body's own; for a convex body, where its solid's origin goes).

    A sphere is drawn unturned (it looks the same), so its shader never changes; a box or
    capsule always has its rotate node, so only numbers change from frame to frame."""
    centre = body.position if position is None else position
    if body.shape == "sphere":
        return Translate(Sphere(body.radius, material=body.material), centre)
    degrees = body.rotation if rotation is None else tuple(float(a) for a in rotation)
    if body.shape == "convex":
        solid = body.solid
    elif body.shape == "box":
        solid = Box(body.half_size, material=body.material)
    else:
        solid = Capsule((0.0, -body.half_length, 0.0), (0.0, body.half_length, 0.0),
                        body.radius, material=body.material)
    return Translate(Rotate(solid, degrees), centre)
