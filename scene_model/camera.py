"""The camera model: which ray each pixel shoots. This is part of marchlab's contract.

Pixel (column x, row y), row 0 at the top, of a W x H image shoots from the camera position
along (docs/scene-format.md)::

    sx = (2 (x + 0.5) / W - 1) tan(fov / 2) W / H
    sy = (1 - 2 (y + 0.5) / H) tan(fov / 2)
    forward = normalize(look_at - position)
    right   = normalize(forward x up)
    up'     = right x forward
    dir     = normalize(forward + sx right + sy up')

The basis is computed once in float64; the per-pixel arithmetic runs in the requested dtype, as a
shader does with a basis passed in as uniforms.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import MarchlabError
from .geometry import normalize
from .scene import Camera

MAX_SIDE = 16384      # the usual largest GPU texture; far beyond what a lesson needs


def check_image_size(width, height) -> None:
    """Raise `MarchlabError` unless ``width`` and ``height`` are integers from 1 to MAX_SIDE."""
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_SIDE:
            raise MarchlabError(f"{name} must be an integer from 1 to {MAX_SIDE} (got {value!r})")


def camera_basis(camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(forward, right, up')``, three orthonormal float64 (3,) vectors."""
    forward = normalize(np.subtract(camera.look_at, camera.position, dtype=np.float64))
    right = normalize(np.cross(forward, np.asarray(camera.up, dtype=np.float64)))
    return forward, right, np.cross(right, forward)


def camera_rays(camera: Camera, width: int, height: int, dtype=np.float64):
    """The primary ray of every pixel.

    Parameters
    ----------
    camera : Camera
    width, height : int
        Image size W, H in pixels.
    dtype : numpy dtype
        float32 or float64 for the per-pixel arithmetic.

    Returns
    -------
    origin : (3,) ndarray
        The camera position, shared by all rays.
    directions : (H, W, 3) ndarray
        Unit direction of the ray through pixel (x, y) at ``directions[y, x]``.
    """
    dtype = np.dtype(dtype)
    forward, right, up = (v.astype(dtype) for v in camera_basis(camera))
    half_height = math.tan(math.radians(camera.fov) / 2)
    x = np.arange(width, dtype=dtype)
    y = np.arange(height, dtype=dtype)
    sx = (2 * (x + dtype.type(0.5)) / dtype.type(width) - 1) * dtype.type(half_height * width / height)
    sy = (1 - 2 * (y + dtype.type(0.5)) / dtype.type(height)) * dtype.type(half_height)
    directions = forward + sx[None, :, None] * right + sy[:, None, None] * up
    return np.asarray(camera.position, dtype=dtype), normalize(directions)

