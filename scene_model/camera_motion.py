"""Moving the camera by hand: orbit, pan, zoom and fly, as a viewer's mouse and keys do.

Each function takes a `Camera` and returns a new one (a camera is plain data), so a viewer, a
notebook widget and a test all move it the same way. The pivot is the camera's ``look_at``:
orbiting turns the eye around it, zooming moves the eye toward it, panning and flying carry
both along. The world's up is the camera's ``up``, normalised.

Motion that depends on time (flying) takes a velocity and the seconds it lasts, so it is
independent of the frame rate: two frames of 1/60 s move the camera exactly as far as one of
1/30 s. Mouse motion (orbit, pan, zoom) is already a distance, not a rate.

A camera always stays valid (scene_model.scene.Camera.check): orbiting stops `POLE_MARGIN`
short of looking straight along ``up`` (where "right" would be undefined), zooming stops
`MIN_DISTANCE` from the pivot, and a motion that would take the camera out of the scene
format's range (|x| <= `MAX_COORDINATE`) is not made.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .camera import camera_basis
from .fields import MAX_COORDINATE
from .geometry import normalize
from .scene import Camera

MIN_DISTANCE = 1e-3      # m: the closest a zoom gets to the pivot
POLE_MARGIN = 1.0        # degrees: an orbit stops this far from looking straight up or down


def orbit(camera: Camera, yaw: float, pitch: float) -> Camera:
    """Turn the eye around the pivot: ``yaw`` degrees about ``up`` (counter-clockwise seen
    from above), then ``pitch`` degrees about the camera's right axis (positive: the eye
    rises). The distance to the pivot and the pivot itself do not change.

    The pitch is clamped so that the eye stays at least `POLE_MARGIN` degrees from the up
    axis through the pivot, on either side.
    """
    up = normalize(np.asarray(camera.up, np.float64))
    pivot = np.asarray(camera.look_at, np.float64)
    offset = rotate_about(np.asarray(camera.position, np.float64) - pivot, up, yaw)
    # The eye's angle from the up axis, 0 straight above the pivot, 180 straight below.
    polar = math.degrees(math.acos(np.clip(offset @ up / np.linalg.norm(offset), -1.0, 1.0)))
    new_polar = min(max(polar - pitch, POLE_MARGIN), 180.0 - POLE_MARGIN)
    # offset x up is the camera's left axis; turning about it carries the eye toward up.
    left = normalize(np.cross(offset, up))
    offset = rotate_about(offset, left, polar - new_polar)
    return _moved(camera, pivot + offset, pivot)


def pan(camera: Camera, right: float, up: float) -> Camera:
    """Slide the camera and its pivot across the view: ``right`` and ``up`` are fractions of
    the view's height at the pivot's distance, so a drag across the whole height of the
    window (``up = 1``) carries the pivot by everything the view shows from top to bottom.

    The pivot then appears at (-2 right, -2 up) tan(fov/2) in the camera's tangent-plane
    coordinates (scene_model.camera: the sx, sy of the pixel that sees it)."""
    forward, right_axis, up_axis = camera_basis(camera)
    position = np.asarray(camera.position, np.float64)
    pivot = np.asarray(camera.look_at, np.float64)
    height = 2.0 * np.linalg.norm(pivot - position) * math.tan(math.radians(camera.fov) / 2)
    shift = height * (right * right_axis + up * up_axis)
    return _moved(camera, position + shift, pivot + shift)


def zoom(camera: Camera, factor: float) -> Camera:
    """Multiply the eye's distance to the pivot by ``factor`` (> 0; < 1 comes closer), along
    the view direction, stopping `MIN_DISTANCE` from the pivot."""
    if not factor > 0:
        raise ValueError(f"a zoom factor must be positive (got {factor!r})")
    pivot = np.asarray(camera.look_at, np.float64)
    offset = np.asarray(camera.position, np.float64) - pivot
    distance = np.linalg.norm(offset)
    return _moved(camera, pivot + offset * max(distance * factor, MIN_DISTANCE) / distance,
                  pivot)


def fly(camera: Camera, velocity, seconds: float) -> Camera:
    """Move the camera and its pivot for ``seconds`` at ``velocity`` = (right, up, forward)
    in m/s: right along the camera's right axis, up along the world's up, forward along the
    view direction (WASD + Q/E). The orientation does not change."""
    forward, right_axis, _ = camera_basis(camera)
    up = normalize(np.asarray(camera.up, np.float64))
    v_right, v_up, v_forward = (float(v) for v in velocity)
    shift = seconds * (v_right * right_axis + v_up * up + v_forward * forward)
    return _moved(camera, np.asarray(camera.position, np.float64) + shift,
                  np.asarray(camera.look_at, np.float64) + shift)


def rotate_about(v: np.ndarray, axis: np.ndarray, degrees: float) -> np.ndarray:
    """``v`` (3,) turned by ``degrees`` about the unit vector ``axis`` (right-handed), by
    Rodrigues' formula: v cos a + (k x v) sin a + k (k . v)(1 - cos a)."""
    a = math.radians(degrees)
    return (v * math.cos(a) + np.cross(axis, v) * math.sin(a)
            + axis * (axis @ v) * (1.0 - math.cos(a)))


def _moved(camera: Camera, position: np.ndarray, look_at: np.ndarray) -> Camera:
    """``camera`` at ``position`` looking at ``look_at``, or ``camera`` itself where that
    would leave the scene format's range of coordinates."""
    if max(np.max(np.abs(position)), np.max(np.abs(look_at))) > MAX_COORDINATE:
        return camera
    return dataclasses.replace(camera, position=tuple(float(x) for x in position),
                               look_at=tuple(float(x) for x in look_at))
