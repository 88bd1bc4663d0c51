"""A scene at a time t: its keyframed fields and camera orbit applied (keyframes.py).

`scene_at_time(scene, t)` is the still a renderer draws at time t; only numbers change from
one time to the next (a field path cannot name a node's kind), so a generated shader's text,
and the GPU's compiled program, stay the same for every frame. `check_keyframes` refuses, in
one line naming ``keyframes[i].field``, a path that names nothing, or a field whose kind (a
number, three numbers) is not the kind of its key values.
"""

from __future__ import annotations

import dataclasses
import numbers

from .editing import get_field, set_field
from .errors import SceneError
from .keyframes import keyframe_value, orbit_position
from .scene import Scene


def check_keyframes(scene: Scene) -> Scene:
    """``scene``, after checking that every keyframed field exists and takes its values."""
    for index, keys in enumerate(scene.keyframes):
        at = ("keyframes", index, "field")
        try:
            current = get_field(scene, keys.field)
        except SceneError as err:
            raise SceneError(f"names no field of the scene: {err}", at) from None
        is_vector = isinstance(current, tuple) and len(current) == 3
        is_number = isinstance(current, numbers.Real) and not isinstance(current, bool)
        if keys.values and not is_number:
            raise SceneError(f"{keys.field!r} is not a number (it holds {current!r}): give its "
                             "keys as vectors", at)
        if keys.vectors and not is_vector:
            raise SceneError(f"{keys.field!r} is not three numbers (it holds {current!r}): "
                             "give its keys as values", at)
        # Every key value must be one the field accepts (a radius of -1 would draw nothing).
        for key in range(len(keys.times)):
            try:
                set_field(scene, keys.field, _typed(current, (keys.values or keys.vectors)[key]))
            except SceneError as err:
                raise SceneError(f"key {key}: {err}", ("keyframes", index,
                                                       "values" if keys.values else "vectors"))
    return scene


def scene_at_time(scene: Scene, t: float) -> Scene:
    """The still of ``scene`` at time ``t`` (s): the camera turned by its orbit, then every
    keyframed field set to its value at t (later entries win). Keyframes and orbit are then
    done with and dropped."""
    if scene.orbit is not None:
        camera = scene.camera
        scene = dataclasses.replace(scene, camera=dataclasses.replace(
            camera, position=orbit_position(camera.position, camera.look_at, camera.up,
                                            scene.orbit, t)))
    for keys in scene.keyframes:
        current = get_field(scene, keys.field)
        scene = set_field(scene, keys.field, _typed(current, keyframe_value(keys, t)))
    return dataclasses.replace(scene, keyframes=(), orbit=None)


def _typed(current, value):
    """An interpolated value in the field's own kind: an integer field (max_steps) gets the
    nearest integer."""
    if isinstance(current, int) and not isinstance(current, bool):
        return int(round(value))
    return value
