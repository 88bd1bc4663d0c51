"""Camera path presets for animations: the moves a teacher would otherwise key by hand.

Each preset turns a scene's camera into plain animation data, which the scene then carries
and saves like any other (`scene_model.keyframes`): a turntable is an `Orbit`; a dolly, a
crane and a fly-by are `Keyframes` of ``camera.position``, the camera looking at its
``look_at`` throughout. Over ``seconds``, with d the distance from the eye to ``look_at`` and
forward, right, up the camera's basis (`scene_model.camera.camera_basis`)::

    turntable   once round the vertical through look_at (an orbit of period seconds)
    dolly       half way in toward look_at and back, at rest at each end (smoothstep)
    crane       up by d / 2 along up and back down (smoothstep)
    flyby       from d / 2 to the left of the eye to d / 2 to its right, at constant speed

`marchlab animate SCENE --camera-path NAME` applies one.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .camera import camera_basis
from .errors import SceneError
from .keyframes import Keyframes, Orbit
from .scene import Scene

PRESETS = ("turntable", "dolly", "crane", "flyby")


def camera_path(scene: Scene, name: str, seconds: float) -> Scene:
    """``scene`` with its camera moved by the preset ``name`` over ``seconds`` s.

    A scene whose camera already moves (an orbit, or keyframes of a camera field) is refused
    in one line: two motions of one camera would fight.
    """
    if name not in PRESETS:
        raise SceneError(f"unknown camera path {name!r} (one of: {', '.join(PRESETS)})")
    moving = [k.field for k in scene.keyframes if k.field.startswith("camera.")]
    if scene.orbit is not None or moving:
        what = "an [orbit]" if scene.orbit is not None else f"keyframes of {moving[0]}"
        raise SceneError(f"the scene already moves its camera ({what}); a camera path would "
                         "fight it")
    if name == "turntable":
        return dataclasses.replace(scene, orbit=Orbit(period=seconds))
    eye = np.asarray(scene.camera.position, float)
    target = np.asarray(scene.camera.look_at, float)
    _, right, up = camera_basis(scene.camera)
    d = float(np.linalg.norm(target - eye))
    if name == "flyby":
        path = [eye - 0.5 * d * right, eye + 0.5 * d * right]
        keys = Keyframes(field="camera.position", times=(0.0, seconds),
                         vectors=tuple(tuple(map(float, p)) for p in path))
    else:
        far = eye + 0.5 * (target - eye) if name == "dolly" else eye + 0.5 * d * up
        keys = Keyframes(field="camera.position", times=(0.0, seconds / 2, seconds),
                         vectors=tuple(tuple(map(float, p)) for p in (eye, far, eye)),
                         interpolation="smoothstep")
    return dataclasses.replace(scene, keyframes=scene.keyframes + (keys,))
