"""Anti-aliasing by supersampling: where in a pixel its rays go. Part of marchlab's contract.

With ``render.samples = n`` every pixel shoots n x n rays instead of one through its centre,
and its colour is their mean: an edge that crosses the pixel shows as the fraction of the
samples that saw each side, instead of a staircase (supersampling; Akenine-Moller, Haines
and Hoffman, *Real-Time Rendering*, 4th ed., 2018, section 5.4.2). Offsets are in pixels from
the pixel's centre, x to the right and y down (rows count from the top), so sample k of pixel
(column, row) is the image point ``(column + 0.5 + dx_k, row + 0.5 + dy_k)`` that
`scene_model.camera.camera_rays` aims through. Every backend takes these numbers from
`sample_offsets` (the generated programs hold them as literals), so all of them shoot the
same rays.

regular
    The n x n grid of the pixel's cells' centres, (dx, dy) = ((i + 0.5) / n - 0.5,
    (j + 0.5) / n - 0.5), for row j = 0 .. n-1 and, in each, column i = 0 .. n-1.

rotated
    The same grid turned by theta = atan(1 / n) about the pixel's centre and stretched by
    1 / cos(theta) = sqrt(1 + n^2) / n: the rotated-grid supersampling (RGSS) of graphics
    hardware (Akeley, "RealityEngine Graphics", SIGGRAPH 1993; *Real-Time Rendering*,
    section 5.4.2). With u = i - (n - 1) / 2 and v = j - (n - 1) / 2 the turn and stretch
    come out as whole numbers over n^2::

        dx = (n u - v) / n^2        dy = (u + n v) / n^2

    n u - v and u + n v each take n^2 different values one apart, so the n^2 samples fall
    in n^2 different columns and n^2 different rows of the pixel, every one of them once (the
    "n-rooks" property: Shirley, "Discrepancy as a quality measure for sample
    distributions", Eurographics 1991): a nearly vertical or horizontal edge, where a regular
    grid has only n + 1 shades, gets n^2 + 1. Every |dx|, |dy| is at most
    (n^2 - 1) / (2 n^2) < 1/2, so the samples stay inside the pixel. For n = 2 this is
    (+-1/8, +-3/8) and (+-3/8, -+1/8): Direct3D's standard 4-sample pattern.

The other buffers of a `Frame` (depth, normal, object id, hit) keep their one-ray meaning:
they are those of the ray through the pixel's centre. For odd n the centre is a sample
(u = v = 0); for even n it is not, and `ray_offsets` adds it as one more ray whose colour is
not used. The steps buffer counts the SDF evaluations of all of a pixel's primary rays.
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np

SamplePattern = Literal["regular", "rotated"]
PATTERNS = get_args(SamplePattern)
MAX_SAMPLES = 8          # 8 x 8 = 64 rays a pixel: far past where an 8-bit image stops changing


def sample_offsets(n: int, pattern: str = "regular") -> np.ndarray:
    """The n x n sample positions of one pixel.

    Parameters
    ----------
    n : int
        Samples per side, ``render.samples``.
    pattern : {"regular", "rotated"}
        ``render.sample_pattern`` (see the module's docstring for both).

    Returns
    -------
    (n * n, 2) float64 ndarray
        (dx, dy) of each sample in pixels from the pixel's centre, x right and y down;
        row j of the grid, then column i: sample k = j n + i. For n = 1, the centre (0, 0).
    """
    if pattern not in PATTERNS:
        raise ValueError(f"unknown sample pattern {pattern!r} (one of: {', '.join(PATTERNS)})")
    u = np.arange(n, dtype=np.float64) - (n - 1) / 2       # cell index from the centre
    v, u = (a.reshape(-1) for a in np.meshgrid(u, u, indexing="ij"))
    if pattern == "regular":
        return np.stack([u / n, v / n], axis=-1)
    return np.stack([(n * u - v) / n**2, (u + n * v) / n**2], axis=-1)


def centre_sample(n: int) -> int:
    """The index, in `ray_offsets`, of the ray through the pixel's centre: the middle sample
    (n^2 - 1) / 2 for odd n, the extra ray n^2 for even n."""
    return (n * n - 1) // 2 if n % 2 else n * n


def ray_offsets(n: int, pattern: str = "regular") -> np.ndarray:
    """(R, 2) float64: the offsets of every primary ray a pixel shoots, its `sample_offsets`
    and, for even n, the centre (0, 0) last, for the buffers other than colour."""
    offsets = sample_offsets(n, pattern)
    return offsets if n % 2 else np.concatenate([offsets, np.zeros((1, 2))])


def rays_per_pixel(n: int) -> int:
    """How many primary rays a pixel shoots with ``render.samples = n``: n^2, plus one for
    even n (the centre, `centre_sample`)."""
    return n * n + (1 - n % 2)


def pixel_max_steps(max_steps: int, n: int) -> int:
    """The most SDF evaluations a pixel's primary rays can take together, ``render.max_steps``
    each: the top of a `Frame`'s steps scale, whose buffer sums them."""
    return max_steps * rays_per_pixel(n)
