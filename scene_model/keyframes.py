"""Animation as plain data: keyframed fields and a camera orbit, read at a time t.

A `Keyframes` entry names one number or 3-vector of the scene by its field path (what
``marchlab render --set`` takes: ``"camera.fov"``, ``"objects[1].radius"``,
``"lights[0].position"``, ``"objects[2].rotation"``) and gives its value at key times. In
between the value is interpolated, per component,

    v(t) = v_i + w(u) (v_{i+1} - v_i),    u = (t - t_i) / (t_{i+1} - t_i),

with w(u) = u (``"linear"``: constant speed) or w(u) = 3u^2 - 2u^3 (``"smoothstep"``: at rest
at every key, Perlin's ease curve); before the first key the first value holds, after the
last the last, or with ``loop`` the keys repeat every last - first seconds. An `Orbit` turns
the camera about the vertical line through what it looks at, once every ``period`` seconds
(a turntable seen from the camera's side). `scene_model.timeline.scene_at_time` applies both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .errors import SceneError
from .fields import COORDINATE, Range, Record, Rule, Vec3, param
from .geometry import axis_angle_matrix

MAX_KEY_TIME = 1e6           # s: the latest key time, as the longest period of a motion
MIN_KEY_GAP = 1e-3           # s: keys closer than this would need a speed beyond any step
KEY_TIMES = Rule(lambda v: all(0 <= t <= MAX_KEY_TIME for t in v),
                 f"must be between 0 and {MAX_KEY_TIME:g} s", f"each in [0, {MAX_KEY_TIME:g}]")


def check_key_times(times) -> None:
    """Raise `SceneError` naming ``times[i]`` where key i is not at least MIN_KEY_GAP after
    key i - 1 (the keyframes here and a keyframed `scene_model.motion.Motion` alike)."""
    for index, (early, late) in enumerate(zip(times, times[1:])):
        if late - early < MIN_KEY_GAP:
            raise SceneError(f"must increase by at least {MIN_KEY_GAP:g} s from key to key "
                             f"(got {early!r} then {late!r})", ("times", index + 1))


@dataclass(frozen=True)
class Keyframes(Record):
    """One animated field: its values at key times, interpolated in between."""
    field: str = param("camera.fov", "The field path, as --set takes it: camera.fov, "
                                     "objects[1].radius, lights[0].position, ...")
    times: tuple[float, ...] = param((0.0, 1.0), "Key times (s), increasing, at least "
                                                 f"{MIN_KEY_GAP:g} s apart.",
                                     KEY_TIMES)
    values: tuple[float, ...] = param((), "The value at each key time, for a number field.",
                                      Rule(lambda v: all(COORDINATE(x) is None for x in v),
                                           "must be within +-1e6", "each in [-1e6, 1e6]"))
    vectors: tuple[Vec3, ...] = param((), "The value at each key time, for a field of three "
                                          "numbers.",
                                      Rule(lambda v: all(COORDINATE(x) is None for p in v
                                                         for x in p),
                                           "components must be within +-1e6",
                                           "each in [-1e6, 1e6]"))
    interpolation: Literal["linear", "smoothstep"] = param(
        "linear", "Between keys: constant speed, or smoothstep (at rest at every key).")
    loop: bool = param(False, "After the last key start over from the first.")

    def check(self):
        if len(self.times) < 1:
            raise SceneError("needs at least one key time", ("times",))
        check_key_times(self.times)
        given = [name for name in ("values", "vectors") if getattr(self, name)]
        if len(given) != 1:
            raise SceneError("give the key values as values (numbers) or vectors (three "
                             "numbers each), one of the two", ("values",))
        count = len(getattr(self, given[0]))
        if count != len(self.times):
            raise SceneError(f"must have one value per key time ({len(self.times)}; got "
                             f"{count})", (given[0],))
        if self.loop and len(self.times) < 2:
            raise SceneError("a loop needs at least two key times", ("loop",))


@dataclass(frozen=True)
class Orbit(Record):
    """The camera turning about the vertical line (along camera.up) through camera.look_at."""
    period: float = param(8.0, "Seconds per turn; negative turns the other way.",
                          Range(-1e6, 1e6))
    start: float = param(0.0, "Time (s) at which the camera is where the scene puts it.",
                         Range(0.0, MAX_KEY_TIME))

    def check(self):
        if abs(self.period) < MIN_KEY_GAP:
            raise SceneError(f"must be at least {MIN_KEY_GAP:g} s either way (got "
                             f"{self.period!r})", ("period",))


def key_fraction(times, t: float, interpolation: str, loop: bool):
    """Where time ``t`` falls among the key ``times``: (i, w, dw/dt) with the value
    v_i + w (v_{i+1} - v_i); i the last key and w = 0 outside the keys (held still)."""
    if loop and t > times[-1]:
        t = times[0] + (t - times[0]) % (times[-1] - times[0])
    if t <= times[0]:
        return 0, 0.0, 0.0
    if t >= times[-1]:
        return len(times) - 1, 0.0, 0.0
    i = int(np.searchsorted(times, t, side="right")) - 1
    span = times[i + 1] - times[i]
    u = (t - times[i]) / span
    if interpolation == "smoothstep":
        return i, u * u * (3 - 2 * u), 6 * u * (1 - u) / span
    return i, u, 1 / span


def keyframe_value(keys: Keyframes, t: float):
    """The value of ``keys`` at time ``t`` (s): a float, or a tuple of three."""
    i, weight, _ = key_fraction(keys.times, t, keys.interpolation, keys.loop)
    values = keys.values or keys.vectors
    here = np.asarray(values[i], np.float64)
    if weight:
        here = here + weight * (np.asarray(values[i + 1], np.float64) - here)
    return float(here) if keys.values else tuple(float(c) for c in here)


def orbit_position(position, look_at, up, orbit: Orbit, t: float) -> tuple:
    """The camera position (3,) at time ``t``: ``position`` turned about the line through
    ``look_at`` along ``up`` by 2 pi (t - start) / period (Rodrigues' formula); its distance
    from that line and its height along it do not change."""
    axis = np.asarray(up, np.float64) / math.sqrt(float(np.dot(up, up)))
    arm = np.asarray(position, np.float64) - np.asarray(look_at, np.float64)
    angle = 2 * math.pi * (t - orbit.start) / orbit.period
    turned = axis_angle_matrix(angle * axis) @ arm
    return tuple(float(c) for c in np.asarray(look_at, np.float64) + turned)
