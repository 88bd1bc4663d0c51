"""The mouse and keys of a live view, turned into camera motion.

The viewer window (`marchlab.view`) and the notebook widget share this mapping, so a drag
moves the camera the same way in both. The motion itself is `scene_model.camera_motion`'s;
this module only says how far each input moves it:

* left drag: orbit about the pivot. A drag across the whole height of the view turns the eye
  by `ORBIT_DEGREES`, sideways about the up axis (dragging right carries the eye to the left,
  so the scene turns with the mouse) and up and down about the camera's right axis (dragging
  down raises the eye);
* right or middle drag: pan. The pivot follows the cursor: a drag across the whole height
  carries it by the whole height of what the view shows at the pivot's distance;
* wheel: zoom, each click toward the pivot multiplies the distance by `ZOOM_PER_CLICK`;
* W/S, A/D, E/Q held: fly forward/back, right/left, up/down at `FLY_SPEED` view distances
  (the eye's distance to the pivot) per second, `FAST` times that with shift. The distance
  moved depends on the seconds held, never on the frame rate.
"""

from __future__ import annotations

import numpy as np

from scene_model.camera_motion import fly, orbit, pan, zoom
from scene_model.scene import Camera

ORBIT_DEGREES = 180.0     # a drag across the whole view height turns the eye this much
ZOOM_PER_CLICK = 0.9      # one wheel click toward the pivot
FLY_SPEED = 1.0           # view distances per second
FAST = 4.0                # shift held

# Key -> (right, up, forward) direction of flight.
FLY_KEYS = {"W": (0, 0, 1), "S": (0, 0, -1), "D": (1, 0, 0), "A": (-1, 0, 0),
            "E": (0, 1, 0), "Q": (0, -1, 0)}
BUTTONS = ("left", "right", "middle")


def drag(camera: Camera, button: str, dx: float, dy: float, view_height: int) -> Camera:
    """The camera after a mouse drag of (``dx``, ``dy``) pixels (y down, as on a screen) in
    a view ``view_height`` pixels high: orbit with the left button, pan with the others."""
    if button not in BUTTONS:
        raise ValueError(f"unknown mouse button {button!r} (one of {', '.join(BUTTONS)})")
    fx, fy = dx / view_height, dy / view_height
    if button == "left":
        return orbit(camera, yaw=-ORBIT_DEGREES * fx, pitch=ORBIT_DEGREES * fy)
    return pan(camera, right=-fx, up=fy)


def scroll(camera: Camera, clicks: float) -> Camera:
    """The camera after ``clicks`` wheel clicks (positive: toward the pivot)."""
    return zoom(camera, ZOOM_PER_CLICK ** clicks)


def fly_keys(camera: Camera, keys, seconds: float, fast: bool = False) -> Camera:
    """The camera after flying ``seconds`` with ``keys`` held (any of `FLY_KEYS`; opposite
    keys cancel), at `FLY_SPEED` view distances per second (`FAST` times that if ``fast``)."""
    direction = np.zeros(3)
    for key in keys:
        direction += FLY_KEYS.get(key.upper(), (0, 0, 0))
    if not direction.any() or seconds <= 0:
        return camera
    distance = np.linalg.norm(np.subtract(camera.look_at, camera.position))
    speed = FLY_SPEED * distance * (FAST if fast else 1.0)
    return fly(camera, speed * direction, seconds)


def turntable(camera: Camera, frames: int) -> list[Camera]:
    """``frames`` cameras a whole turn about the pivot, counter-clockwise seen from above:
    frame k is ``camera`` orbited by 360 k / frames degrees about its up axis (each from the
    first, so the turn does not drift), and a turntable played in a loop has no seam."""
    if frames < 1:
        raise ValueError(f"a turntable has at least one frame (got {frames})")
    return [orbit(camera, yaw=360.0 * k / frames, pitch=0.0) for k in range(frames)]
