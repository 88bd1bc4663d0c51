"""Lights drawn as small marks on a picture: a yellow dot ringed in black on each point or
spot light, where the camera sees it.

A light is a point, which no ray can hit, so the renderers never draw it; a teacher moving a
light wants to see where it is. The notebook view marks every light (a place to press and
drag it, `marchlab.widgets`); a rendered picture marks only the lights the camera can see,
not one behind a solid (`marchlab render --mark-lights`, `marchlab animate --mark-lights`).
"""

from __future__ import annotations

import math

import numpy as np

from scene_model.camera import project

MARKER_COLOR = np.array([255, 230, 50], np.uint8)


def light_marks(scene, width: int, height: int, depth: np.ndarray | None = None):
    """(index, x, y) of each point or spot light in a ``width`` x ``height`` picture of
    ``scene``, in pixels from the top-left corner; lights behind the eye are left out, and
    with ``depth`` (the frame's (H, W) depth, inf on a miss) those behind a surface too."""
    out = []
    for i, light in enumerate(scene.lights):
        position = getattr(light, "position", None)
        if position is None:
            continue
        x, y, ahead = project(scene.camera, [position], width, height)[0]
        if not (math.isfinite(x) and ahead > 0):
            continue
        if depth is not None:
            column, row = int(x), int(y)
            inside = 0 <= row < depth.shape[0] and 0 <= column < depth.shape[1]
            distance = math.dist(position, scene.camera.position)
            if inside and depth[row, column] < distance:
                continue
        out.append((i, float(x), float(y)))
    return out


def draw_marks(image: np.ndarray, marks, radius: float) -> np.ndarray:
    """``image`` (H, W, 3) uint8 with a dot of ``radius`` pixels, ringed in black, at each
    (index, x, y) of ``marks``; the image itself is left alone (a copy is drawn on)."""
    height, width = image.shape[:2]
    ring = radius + 1.5
    out = image
    for _, cx, cy in marks:
        # Only the pixels near the mark: the notebook view draws marks on every frame.
        top, bottom = max(int(cy - ring), 0), min(int(cy + ring) + 1, height)
        left, right = max(int(cx - ring), 0), min(int(cx + ring) + 1, width)
        if top >= bottom or left >= right:
            continue
        rows, cols = np.mgrid[top:bottom, left:right] + 0.5
        distance = np.hypot(cols - cx, rows - cy)
        if distance.min() > ring:
            continue
        out = out.copy() if out is image else out
        patch = out[top:bottom, left:right]
        patch[distance <= ring] = 0
        patch[distance <= radius] = MARKER_COLOR
    return out


def mark_lights(image: np.ndarray, scene, frame=None) -> np.ndarray:
    """A rendered ``image`` of ``scene`` with its visible lights marked (`light_marks`, given
    the ``frame``'s depth when there is one), dots sized to the picture (3 px at 640 wide)."""
    height, width = image.shape[:2]
    marks = light_marks(scene, width, height, None if frame is None else frame.depth)
    return draw_marks(image, marks, max(2.0, 3.0 * width / 640))
