"""Kinematic objects: static objects of the scene moved along a prescribed path over time.

A `Motion` names one top-level object of ``objects`` and moves it. The object's points go at
time t from x to

    x(t) = R(t) (x - pivot) + pivot + s(t),

a turn R(t) about the pivot and a shift s(t), given one of two ways:

* **constant**: R(t) the turn by the angle |spin| t about the axis spin / |spin|
  (Rodrigues' formula), and s(t) = amplitude sin(2 pi t / period);
* **keyframed**: a pose (``offsets``, ``turns``) at each of the key ``times``, and in between
  the shift interpolated and the turn carried from one key's to the next's about the single
  axis that joins them (spherical linear interpolation, Shoemake, "Animating rotation with
  quaternion curves", SIGGRAPH 1985), at the rate the ``interpolation`` gives: ``linear``
  (constant velocity along each segment) or ``smoothstep`` (3u^2 - 2u^3 of the segment's
  fraction u: starting and stopping at rest at each key). Before the first key the object
  holds the first pose; after the last, the last, or with ``loop`` it starts over.

The physics step collides the bodies with the object where it is and gives them its surface
velocity, v(x) = w x (x - pivot - s(t)) + s'(t) (a paddle, a turntable, a moving platform),
with w the angular velocity of R(t); nothing pushes it back. The renderers draw it where it
is (`posed_objects`). Plain data and plain maths: no engine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from typing import Literal

from .errors import SceneError
from .fields import MAX_DEGREES, POINT, Each, Range, Record, Rule, Vec3, param
from .geometry import axis_angle_matrix, rotation_matrix, rotation_vector
from .keyframes import KEY_TIMES, MIN_KEY_GAP, check_key_times, key_fraction
from .shapes import Node, Rotate, Translate

MAX_SPIN = 36000.0           # degrees per second: 100 turns a second
MAX_OFFSET = 1e3             # m: as the amplitude


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
    times: tuple[float, ...] = param((), "Key times (s), increasing, at least "
                                         f"{MIN_KEY_GAP:g} s apart; empty: no keyframes.",
                                     KEY_TIMES)
    offsets: tuple[Vec3, ...] = param((), "The shift s at each key time (m); empty: none.",
                                      Rule(lambda v: all(abs(c) <= MAX_OFFSET for p in v
                                                         for c in p),
                                           f"components must be within +-{MAX_OFFSET:g} m",
                                           f"each in [-{MAX_OFFSET:g}, {MAX_OFFSET:g}]"))
    turns: tuple[Vec3, ...] = param((), "The turn about the pivot at each key time, Euler "
                                        "angles in degrees (R = Rz Ry Rx, as rotate); "
                                        "empty: none.",
                                    Rule(lambda v: all(abs(c) <= MAX_DEGREES for p in v
                                                       for c in p),
                                         f"angles must be within +-{MAX_DEGREES:g} degrees",
                                         f"each in [-{MAX_DEGREES:g}, {MAX_DEGREES:g}]"))
    interpolation: Literal["linear", "smoothstep"] = param(
        "linear", "Between keys: constant velocity, or smoothstep (at rest at every key).")
    loop: bool = param(False, "After the last key start over from the first (the keys then "
                              "repeat every last - first seconds); otherwise hold the last "
                              "pose.")

    def check(self):
        if not self.times:
            for name in ("offsets", "turns"):
                if getattr(self, name):
                    raise SceneError("needs key times: give times as well", (name,))
            return
        for name in ("offsets", "turns"):
            given = len(getattr(self, name))
            if given not in (0, len(self.times)):
                raise SceneError(f"must have one value per key time ({len(self.times)}), or "
                                 f"none (got {given})", (name,))
        check_key_times(self.times)
        for name in ("spin", "amplitude"):
            if any(getattr(self, name)):
                raise SceneError("a keyframed motion has no constant spin or oscillation: "
                                 "give its turns and offsets at the keys instead", (name,))
        if self.loop and len(self.times) < 2:
            raise SceneError("a loop needs at least two key times", ("loop",))


def motion_pose(motion: Motion, t: float) -> tuple[np.ndarray, np.ndarray]:
    """R(t) (3, 3) and s(t) (3,) of ``motion`` at time ``t`` (s), float64."""
    if motion.times:
        rotation, shift, _, _ = _keyframed(motion, t)
        return rotation, shift
    rotation = axis_angle_matrix(np.radians(np.asarray(motion.spin, np.float64)) * t)
    shift = np.asarray(motion.amplitude, np.float64) * math.sin(2 * math.pi * t / motion.period)
    return rotation, shift


def motion_rates(motion: Motion, t: float) -> tuple[np.ndarray, np.ndarray]:
    """The angular velocity w (3,) in rad/s, world frame, and the shift's rate s'(t) (3,) in
    m/s of ``motion`` at time ``t`` (s), float64."""
    if motion.times:
        _, _, w, shift_rate = _keyframed(motion, t)
        return w, shift_rate
    omega = 2 * math.pi / motion.period
    return (np.radians(np.asarray(motion.spin, np.float64)),
            np.asarray(motion.amplitude, np.float64) * omega * math.cos(omega * t))


def motion_velocity(motion: Motion, t: float, points: np.ndarray) -> np.ndarray:
    """Velocity (K, 3) in m/s at time ``t`` of the object's points now at ``points`` (K, 3):
    w x (x - pivot - s(t)) + s'(t)."""
    _, shift = motion_pose(motion, t)
    w, shift_rate = motion_rates(motion, t)
    arm = np.asarray(points, np.float64) - np.asarray(motion.pivot) - shift
    return np.cross(w, arm) + shift_rate


def _keyframed(motion: Motion, t: float):
    """R(t), s(t), the angular velocity w(t) (rad/s, world frame) and s'(t) of a keyframed
    motion (the module docstring)."""
    count = len(motion.times)
    offsets = np.asarray(motion.offsets or [(0.0, 0.0, 0.0)] * count, np.float64)
    turns = [rotation_matrix(turn) for turn in (motion.turns or [(0.0, 0.0, 0.0)] * count)]
    i, weight, rate = key_fraction(motion.times, t, motion.interpolation, motion.loop)
    if weight == 0 and rate == 0:                       # before the first key or after the last
        return turns[i], offsets[i], np.zeros(3), np.zeros(3)
    # The turn from key i to key i + 1 is one rotation about a fixed axis, R_{i+1} R_i^T =
    # exp(r): carrying the fraction ``weight`` of it is slerp, at the angular velocity r rate.
    between = rotation_vector(turns[i + 1] @ turns[i].T)
    rotation = axis_angle_matrix(weight * between) @ turns[i]
    step = offsets[i + 1] - offsets[i]
    return rotation, offsets[i] + weight * step, between * rate, step * rate


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
