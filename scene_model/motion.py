"""Kinematic objects: static objects of the scene moved along a prescribed path over time.

A `Motion` names one top-level object of ``objects`` and moves it: turned at the constant
angular velocity ``spin`` about ``pivot``, and moved back and forth by
``amplitude sin(2 pi t / period)``. The object's points go at time t from x to

    x(t) = R(t) (x - pivot) + pivot + s(t),    s(t) = amplitude sin(2 pi t / period),

with R(t) the turn by the angle |spin| t about the axis spin / |spin| (Rodrigues' formula).
The physics step collides the bodies with the object where it is and gives them its surface
velocity, v(x) = w x (x - pivot - s(t)) + s'(t) (a paddle, a turntable, a moving platform);
nothing pushes it back. The renderers draw it where it is (`posed_objects`). Plain data and
plain maths: no engine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fields import POINT, Each, Range, Record, Vec3, param
from .shapes import Node, Rotate, Translate

MAX_SPIN = 36000.0           # degrees per second: 100 turns a second


@dataclass(frozen=True)
class Motion(Record):
    """One kinematic object: ``objects[object]`` turned about ``pivot`` at the rate ``spin``
    and moved back and forth by ``amplitude sin(2 pi t / period)``. It pushes the bodies and
    is not pushed."""
    object: int = param(0, "Index of the moving object in ``objects`` (0 is the first).",
                        Range(0, 10 ** 6, allowed="[0, 1e6]"))
    pivot: Vec3 = param((0.0, 0.0, 0.0), "The point the object turns about (m).", POINT)
    spin: Vec3 = param((0.0, 0.0, 0.0), "Angular velocity in degrees per second: its "
                                         "direction is the axis, its length the rate.",
                       Each(Range(-MAX_SPIN, MAX_SPIN)))
    amplitude: Vec3 = param((0.0, 0.0, 0.0), "Largest displacement of the back-and-forth "
                                              "motion (m).", Each(Range(-1e3, 1e3)))
    period: float = param(1.0, "Period of the back-and-forth motion (s).",
                          Range(1e-3, 1e6, positive=True))


def motion_pose(motion: Motion, t: float) -> tuple[np.ndarray, np.ndarray]:
    """R(t) (3, 3) and s(t) (3,) of ``motion`` at time ``t`` (s), float64."""
    w = np.radians(np.asarray(motion.spin, np.float64))
    angle = math.sqrt(float(w @ w)) * t
    if angle == 0:
        rotation = np.eye(3)
    else:
        # Rodrigues: R = I + sin(a) K + (1 - cos(a)) K^2, K the cross-product matrix of the
        # unit axis.
        k = w / math.sqrt(float(w @ w))
        cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        rotation = np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross
    shift = np.asarray(motion.amplitude, np.float64) * math.sin(2 * math.pi * t / motion.period)
    return rotation, shift


def motion_velocity(motion: Motion, t: float, points: np.ndarray) -> np.ndarray:
    """Velocity (K, 3) in m/s at time ``t`` of the object's points now at ``points`` (K, 3):
    w x (x - pivot - s(t)) + s'(t)."""
    w = np.radians(np.asarray(motion.spin, np.float64))
    _, shift = motion_pose(motion, t)
    arm = np.asarray(points, np.float64) - np.asarray(motion.pivot) - shift
    omega = 2 * math.pi / motion.period
    return np.cross(w, arm) + np.asarray(motion.amplitude) * omega * math.cos(omega * t)


def euler_degrees(rotation: np.ndarray) -> tuple[float, float, float]:
    """Euler angles (degrees) with R = Rz(z) Ry(y) Rx(x) (`geometry.rotation_matrix`).

    Every angle comes from an atan2, never an asin, so none loses digits near y = +-90
    degrees (asin(-R_20) there keeps only half of them), and z is found from x rather than
    from R_00 and R_10, which both vanish at the lock (Day, "Extracting Euler angles from a
    rotation matrix", Insomniac Games, 2012).
    """
    r = np.asarray(rotation, np.float64)
    x = math.atan2(r[2, 1], r[2, 2])
    y = math.atan2(-r[2, 0], math.hypot(r[0, 0], r[1, 0]))
    sin_x, cos_x = math.sin(x), math.cos(x)
    z = math.atan2(sin_x * r[0, 2] - cos_x * r[0, 1], cos_x * r[1, 1] - sin_x * r[1, 2])
    return tuple(math.degrees(a) for a in (x, y, z))


def posed_node(node: Node, motion: Motion, t: float) -> Node:
    """``node`` where ``motion`` has it at time ``t``: translate(rotate(translate(node, -pivot),
    R(t)), pivot + s(t))."""
    rotation, shift = motion_pose(motion, t)
    pivot = np.asarray(motion.pivot, np.float64)
    inner = Translate(node, tuple(float(c) for c in -pivot))
    return Translate(Rotate(inner, euler_degrees(rotation)),
                     tuple(float(c) for c in pivot + shift))


def posed_objects(objects: tuple[Node, ...], motions, t: float) -> tuple[Node, ...]:
    """``objects`` with each one that a motion moves put where it is at time ``t``."""
    moved = {motion.object: motion for motion in motions}
    return tuple(posed_node(node, moved[index], t) if index in moved else node
                 for index, node in enumerate(objects))
