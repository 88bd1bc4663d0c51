"""Time integrators: how one step of length h turns accelerations into motion.

Every step of `World.step` has the same four stages, kept apart as in Box2D (solver.c):

    1. integrate velocities   v* = v_n + h g               gravity g is the only force
    2. find contacts          at the positions x_n
    3. resolve contacts       impulses turn v* into v_{n+1}
    4. integrate positions    x_{n+1} from x_n, v_n and v_{n+1}

The three schemes differ only in stage 4, in which velocity carries the body over the step:

    explicit Euler        x_{n+1} = x_n + h v_n                 the velocity at the start
    semi-implicit Euler   x_{n+1} = x_n + h v_{n+1}             the velocity at the end
    velocity Verlet       x_{n+1} = x_n + h (v_n + v_{n+1}) / 2 their mean

All three are ``x_{n+1} = x_n + h v_n + c h (v_{n+1} - v_n)`` with c = 0, 1 and 1/2. A contact
impulse is part of v_{n+1} - v_n, so it moves the body the way a force spread over the step
would: a ball resting on the floor (v_n = v_{n+1} = 0) stays put under all three.

Free fall from (y0, v0) (g the magnitude of gravity, t_n = n h), by summing the steps:

    explicit Euler        y_n = y0 + v0 t_n - g t_n^2 / 2 + g h t_n / 2
    semi-implicit Euler   y_n = y0 + v0 t_n - g t_n^2 / 2 - g h t_n / 2
    velocity Verlet       y_n = y0 + v0 t_n - g t_n^2 / 2                  exact

(sum_{k<n} k = n(n-1)/2 for explicit, sum_{k<=n} k = n(n+1)/2 for semi-implicit), and the energy
per unit mass E/m = v_n^2/2 + g y_n drifts by +g^2 h t_n / 2 (explicit: gains) and
-g^2 h t_n / 2 (semi-implicit: loses); Verlet's does not drift.

Each y_n above lies on an exact parabola, x(t) = x_n + t u + t^2 a / 2 with a = (v_{n+1} - v_n)/h
and u = v_n + (c - 1/2) h a (check: x(h) is the line above). `parabola_start_velocity` gives u;
the continuous collision test finds where that parabola meets a wall (continuous.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


def explicit_euler(x: np.ndarray, v_old: np.ndarray, v_new: np.ndarray, h) -> np.ndarray:
    """x_{n+1} = x_n + h v_n for x, v_old, v_new : (N, 3) (m, m/s) and step h (s)."""
    return x + h * v_old


def semi_implicit_euler(x: np.ndarray, v_old: np.ndarray, v_new: np.ndarray, h) -> np.ndarray:
    """x_{n+1} = x_n + h v_{n+1}: symplectic Euler, the scheme Box2D and most games use."""
    return x + h * v_new


def velocity_verlet(x: np.ndarray, v_old: np.ndarray, v_new: np.ndarray, h) -> np.ndarray:
    """x_{n+1} = x_n + h (v_n + v_{n+1}) / 2.

    With a constant acceleration a (v_{n+1} = v_n + h a) this is x_n + h v_n + h^2 a / 2,
    velocity Verlet's position update, and exact for free fall.
    """
    return x + h * (0.5 * (v_old + v_new))


@dataclass(frozen=True)
class Integrator:
    """One time-stepping scheme.

    Attributes
    ----------
    name : str
        The name ``World(integrator=...)`` takes.
    positions : callable
        ``positions(x, v_old, v_new, h) -> x_new``, the stage that differs between schemes;
        also used with x = 0 to turn angular velocities into a rotation over the step.
    weight : float
        c in ``x_{n+1} = x_n + h v_n + c h (v_{n+1} - v_n)``: 0, 1 or 1/2.
    """
    name: str
    positions: Callable
    weight: float


INTEGRATORS = {
    "explicit": Integrator("explicit", explicit_euler, 0.0),
    "semi_implicit": Integrator("semi_implicit", semi_implicit_euler, 1.0),
    "verlet": Integrator("verlet", velocity_verlet, 0.5),
}


def integrate_velocities(velocity: np.ndarray, gravity: np.ndarray, h, moving: np.ndarray):
    """v* = v_n + h g for the bodies still in the world (``moving`` : (N,) bool).

    velocity : (N, 3) m/s, gravity : (3,) m/s^2, h : s. Returns a new (N, 3) array.
    """
    return velocity + (h * gravity) * moving[:, None].astype(velocity.dtype)


def parabola_start_velocity(integrator: Integrator, v_old, v_new, h):
    """u = v_n + (c - 1/2)(v_{n+1} - v_n): the velocity at the start of the step of the parabola
    on which the scheme puts the body (module docstring). (N, 3) m/s."""
    return v_old + (integrator.weight - 0.5) * (v_new - v_old)
