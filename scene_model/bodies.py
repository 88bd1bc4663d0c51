"""The moving part of a scene: the ``[physics]`` settings and the dynamic spheres, ``[[bodies]]``.

A `Body` is a solid sphere that the physics module moves and every renderer draws. It is plain
data like the rest of the scene: `body_sphere` is the sphere drawn for it, and
`scene_model.scene` puts the bodies into a scene (`scene_objects`, `scene_at`). Stepping the
world is the physics engine's job (physics/, driven by marchlab/simulation.py).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Literal

from .errors import SceneError
from .fields import MAX_SPEED, POINT, SIZE, Each, Range, Record, Vec3, param, unit_interval
from .shapes import Node, Sphere, Translate

# The names of the time-stepping schemes and contact solvers, here once: the scene format
# accepts them, and physics.INTEGRATORS and physics.SOLVERS are keyed by them.
INTEGRATOR_NAMES = ("semi_implicit", "explicit", "verlet")
SOLVER_NAMES = ("sequential", "simultaneous")
Integrator = Literal[INTEGRATOR_NAMES]
Solver = Literal[SOLVER_NAMES]

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
    """A dynamic solid sphere: moved by the physics step and drawn as a sphere."""
    position: Vec3 = param((0.0, 1.0, 0.0), "Centre at t = 0 (m).", POINT)
    velocity: Vec3 = param((0.0, 0.0, 0.0), "Velocity at t = 0 (m/s).", VELOCITY)
    angular_velocity: Vec3 = param((0.0, 0.0, 0.0), "Angular velocity at t = 0 (rad/s).",
                                   VELOCITY)
    radius: float = param(0.25, "Radius (m).", SIZE)
    mass: float | None = param(None, "Mass (kg); absent: from density.", MASS)
    density: float | None = param(None, "Density (kg/m^3), mass = 4/3 pi r^3 density; "
                                         "absent: [physics] density.", DENSITY)
    restitution: float | None = param(None, "Coefficient of restitution e; absent: "
                                            "[physics] restitution.", unit_interval)
    friction: float | None = param(None, "Coefficient of friction mu; absent: "
                                         "[physics] friction.", FRICTION)
    material: str = param("default", "Name of a material in the scene's [materials] table.")

    def check(self):
        if self.mass is not None and self.density is not None:
            raise SceneError("give mass or density, not both", ("density",))


def body_sphere(body: Body, position=None) -> Node:
    """The object drawn for ``body``: a sphere of its radius translated to ``position``
    (default: the body's own position)."""
    centre = body.position if position is None else position
    return Translate(Sphere(body.radius, material=body.material), centre)
