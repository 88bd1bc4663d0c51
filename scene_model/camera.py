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

import dataclasses
import math

import numpy as np

from .errors import MarchlabError
from .geometry import normalize
from .scene import Camera

MAX_SIDE = 16384      # the usual largest GPU texture; far beyond what a lesson needs

# The memory an image may take. A NumPy render holds the Frame's buffers (57 bytes a pixel in
# float64: colour 12, depth 8, normal 24, steps, object id and path label 4 each, hit 1) and
# the primary rays' directions while it runs: about 85 bytes a pixel measured at 2000x2000,
# 100 with the 8-bit picture made when it is saved. 4 GiB of that is 42,949,672 pixels, so
# 8K UHD (7680x4320) fits and 10000x10000 does not. Anti-aliasing (render.samples > 1) adds
# the running sum of the samples' colours, 24 bytes a pixel more in float64.
MAX_IMAGE_BYTES = 4 * 2**30
BYTES_PER_PIXEL = 100
MAX_PIXELS = MAX_IMAGE_BYTES // BYTES_PER_PIXEL


def check_image_size(width, height, allow_large: bool = False) -> None:
    """Raise `MarchlabError` unless ``width`` and ``height`` are integers from 1 to MAX_SIDE
    and, unless ``allow_large``, the image has at most MAX_PIXELS pixels."""
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_SIDE:
            raise MarchlabError(f"{name} must be an integer from 1 to {MAX_SIDE} (got {value!r})")
    problem = image_size_problem(width, height)
    if problem and not allow_large:
        raise MarchlabError(f"{problem}; pass allow_large=True to go ahead")


def image_size_problem(width: int, height: int) -> str | None:
    """None if a ``width`` x ``height`` image fits in MAX_PIXELS, else one line saying so
    (without saying how to lift the limit: that depends on who asks)."""
    if width * height <= MAX_PIXELS:
        return None
    return (f"{width}x{height} is {width * height:,} pixels, more than the limit of "
            f"{MAX_PIXELS:,} (its buffers would take about "
            f"{BYTES_PER_PIXEL * width * height / 2**30:.0f} GiB)")


def camera_basis(camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(forward, right, up')``, three orthonormal float64 (3,) vectors."""
    forward = normalize(np.subtract(camera.look_at, camera.position, dtype=np.float64))
    right = normalize(np.cross(forward, np.asarray(camera.up, dtype=np.float64)))
    return forward, right, np.cross(right, forward)


def camera_rays(camera: Camera, width: int, height: int, dtype=np.float64,
                offset=(0.0, 0.0)):
    """The primary ray of every pixel: through its centre, or through the point ``offset``
    from it (an anti-aliasing sample, `scene_model.sampling`).

    Parameters
    ----------
    camera : Camera
    width, height : int
        Image size W, H in pixels.
    dtype : numpy dtype
        float32 or float64 for the per-pixel arithmetic.
    offset : (dx, dy) floats
        In pixels from the pixel's centre, x right and y down: pixel (x, y)'s ray goes
        through the image point (x + 0.5 + dx, y + 0.5 + dy), added in ``dtype`` in that
        order (as the generated programs add them). (0, 0) changes no bit.

    Returns
    -------
    origin : (3,) ndarray
        The camera position, shared by all rays.
    directions : (H, W, 3) ndarray
        Unit direction of the ray through pixel (x, y) at ``directions[y, x]``.
    """
    dtype = np.dtype(dtype)
    dx, dy = (dtype.type(v) for v in offset)
    x = np.arange(width, dtype=dtype) + dtype.type(0.5) + dx
    y = np.arange(height, dtype=dtype) + dtype.type(0.5) + dy
    directions = image_rays(camera, x[None, :], y[:, None], width, height, dtype)
    return np.asarray(camera.position, dtype=dtype), directions


def image_rays(camera: Camera, x, y, width: int, height: int, dtype=np.float64):
    """The unit directions of the rays through the image points (``x``, ``y``), in pixels
    from the top-left corner (pixel (i, j)'s centre is (i + 0.5, j + 0.5)), computed in
    ``dtype`` with the operations, in the order, of ``camera_ray`` in glsl/camera.glsl.

    Parameters
    ----------
    x, y : array_like
        Image coordinates; any shapes that broadcast together to S.

    Returns
    -------
    directions : (S..., 3) ndarray of ``dtype``
    """
    dtype = np.dtype(dtype)
    forward, right, up = (v.astype(dtype) for v in camera_basis(camera))
    half_height = math.tan(math.radians(camera.fov) / 2)
    x, y = np.asarray(x, dtype), np.asarray(y, dtype)
    sx = (2 * x / dtype.type(width) - 1) * dtype.type(half_height * width / height)
    sy = (1 - 2 * y / dtype.type(height)) * dtype.type(half_height)
    return normalize(forward + sx[..., None] * right + sy[..., None] * up)


def pixel_ray(camera: Camera, x: float, y: float, width: int, height: int):
    """The ray through the point (``x``, ``y``) of the image, in pixels from its top-left
    corner: pixel (i, j)'s centre is (i + 0.5, j + 0.5), where `camera_rays` aims. A viewer
    asks for the ray under the mouse with it.

    Returns
    -------
    origin, direction : (3,) float64 ndarrays
        The camera position and the unit direction.
    """
    forward, right, up = camera_basis(camera)
    half_height = math.tan(math.radians(camera.fov) / 2)
    sx = (2 * x / width - 1) * half_height * width / height
    sy = (1 - 2 * y / height) * half_height
    return np.asarray(camera.position, np.float64), normalize(forward + sx * right + sy * up)


def project(camera: Camera, points, width: int, height: int) -> np.ndarray:
    """Where ``points`` appear in the image: the inverse of `pixel_ray`.

    Parameters
    ----------
    points : (N, 3) array_like
        World positions.

    Returns
    -------
    (N, 3) float64 ndarray
        x, y in pixels from the image's top-left corner, and the depth along the view
        direction; x and y are nan for a point not in front of the camera (depth <= 0).
    """
    view = to_camera(points, camera)
    with np.errstate(divide="ignore", invalid="ignore"):
        image = view_to_image(view, camera, width, height)
    behind = ~(view[:, 2] > 0)
    image[behind] = np.nan
    return np.concatenate([image, view[:, 2:]], axis=-1)


def to_camera(points, camera: Camera) -> np.ndarray:
    """World points (N, 3) in the camera's frame: their (right, up, forward) coordinates
    (N, 3) float64, the last one the depth along the view direction."""
    forward, right, up = camera_basis(camera)
    offset = np.asarray(points, np.float64).reshape(-1, 3) - np.asarray(camera.position)
    return np.stack([offset @ right, offset @ up, offset @ forward], axis=-1)


def view_to_image(view: np.ndarray, camera: Camera, width: int, height: int) -> np.ndarray:
    """Where points given in the camera's frame (N, 3) (`to_camera`, depth > 0) appear in the
    image: (N, 2) x, y in pixels from its top-left corner, the inverse of `pixel_ray`."""
    half_height = math.tan(math.radians(camera.fov) / 2)
    sx = view[:, 0] / view[:, 2]
    sy = view[:, 1] / view[:, 2]
    x = (sx / (half_height * width / height) + 1) * width / 2
    y = (1 - sy / half_height) * height / 2
    return np.stack([x, y], axis=-1)


def turned(camera: Camera, dx: float, dy: float, width: int, height: int) -> Camera:
    """The camera turned so that its W x H picture moves by (``dx``, ``dy``) pixels (x right,
    y down) at the centre: it looks along the original's ray through the image point
    (W / 2 + dx, H / 2 + dy), up unchanged.

    A turn is not a shift: away from the centre a point moves by up to 1 / cos^2 of its angle
    from the axis times as much, and a little across (for a small turn, to first order). A
    comparison samples a reference around each pixel's centre with it
    (`marchlab.compare.reference_around`)."""
    forward, right, up = camera_basis(camera)
    half_height = math.tan(math.radians(camera.fov) / 2)
    sx = 2 * dx / width * half_height * width / height
    sy = -2 * dy / height * half_height
    direction = forward + sx * right + sy * up
    distance = math.dist(camera.look_at, camera.position)
    look_at = np.asarray(camera.position, np.float64) + distance * normalize(direction)
    return dataclasses.replace(camera, look_at=tuple(float(v) for v in look_at))
