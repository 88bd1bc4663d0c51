"""`Frame`: what every backend returns, one array per output buffer, and how it is saved."""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .colormaps import heat
from .errors import MarchlabError
from .files import write_atomically

AOVS = ("color", "depth", "normal", "steps")


@dataclass(repr=False)
class Frame:
    """One rendered image and its auxiliary buffers, for an image of H rows and W columns.

    Attributes
    ----------
    color : (H, W, 3) float32 ndarray
        Linear RGB in [0, 1] (gamma is applied only when saving).
    depth : (H, W) ndarray
        Distance t along the primary ray to the hit; inf on a miss.
    normal : (H, W, 3) ndarray
        Unit surface normal at the hit; 0 on a miss.
    steps : (H, W) int32 ndarray
        SDF evaluations the primary ray took; with anti-aliasing (``render.samples`` > 1),
        the sum over all the pixel's primary rays (`scene_model.sampling`), whose centre ray
        gives depth, normal, object_id and hit, while color is the mean of the samples'.
    object_id : (H, W) int32 ndarray
        Depth-first index of the primitive hit (`scene_model.shapes.primitives`); -1 on a miss.
    hit : (H, W) bool ndarray
    gamma : float
        Display gamma used by `image` and `save`.
    max_steps : int
        The top of the steps colour scale: the march limit, times the primary rays a pixel
        shoots (`scene_model.sampling.pixel_max_steps`).
    backend, precision : str
        Which renderer made the frame, at which floating-point precision.
    path : (H, W) uint32 ndarray or None
        A label of what the pixel's paths saw: the object ids, checker cells and hard-shadow
        states along the primary ray and its mirror and glass rays (docs/reflections.md,
        "Path labels"). Where it changes between
        neighbours the image is discontinuous (a reflected checker edge, a shadow edge), and
        two correct renderers may disagree there. A 24-bit hash; None where a backend
        does not compute it.
    subpixel : float
        How far from a pixel's centre, in pixels along each axis, the surface the frame shows
        there may have been sampled: 0 where every value is computed for the ray through the
        centre; 2^-(b + 1) for a hardware rasteriser that snaps vertices to b sub-pixel bits
        (`gpu_shader.context.subpixel_shift`; docs/equivalence.md, "Sub-pixel precision").
    """
    color: np.ndarray
    depth: np.ndarray
    normal: np.ndarray
    steps: np.ndarray
    object_id: np.ndarray
    hit: np.ndarray
    gamma: float = 2.2
    max_steps: int = 256
    backend: str = ""
    precision: str = ""
    path: np.ndarray | None = None
    dither: bool = False
    subpixel: float = 0.0

    @property
    def height(self) -> int:
        return self.color.shape[0]

    @property
    def width(self) -> int:
        return self.color.shape[1]

    def image(self, aov: str = "color") -> np.ndarray:
        """An 8-bit (H, W, 3) picture of one buffer.

        ``color`` is encoded with the frame's gamma; ``depth`` is grey from white (nearest
        hit) to black (farthest hit); ``normal`` maps each component from [-1, 1] to [0, 1];
        ``steps`` uses the heat ramp up to ``max_steps``. Misses are black in depth and normal.
        """
        if aov == "color":
            offsets = dither_offsets(self.height, self.width) if self.dither else None
            return to_uint8(self.color ** (1 / self.gamma), offsets)
        if aov == "depth":
            t = np.where(self.hit, self.depth, np.nan)
            near, far = (np.nanmin(t), np.nanmax(t)) if self.hit.any() else (0.0, 1.0)
            grey = np.where(self.hit, 1 - (t - near) / max(far - near, 1e-12), 0)
            return to_uint8(np.repeat(grey[..., None], 3, axis=-1))
        if aov == "normal":
            return to_uint8(np.where(self.hit[..., None], 0.5 + 0.5 * self.normal, 0))
        if aov == "steps":
            return to_uint8(heat(self.steps / self.max_steps))
        raise MarchlabError(f"unknown AOV {aov!r} (one of: {', '.join(AOVS)})")

    def png(self, aov: str = "color") -> bytes:
        """The PNG file of `image` (``aov``), as bytes."""
        return png_bytes(self.image(aov))

    def _repr_png_(self) -> bytes:
        """A notebook shows a frame as its picture (IPython's rich display protocol)."""
        return self.png()

    def __repr__(self) -> str:
        """One line, not every buffer: ``Frame(640x480, numpy float64, 206,426 of 307,200
        pixels hit)``."""
        return (f"Frame({self.width}x{self.height}, {self.backend} {self.precision}, "
                f"{int(self.hit.sum()):,} of {self.hit.size:,} pixels hit)")

    def save(self, path, aov: str = "color") -> None:
        """Write a PNG (8-bit, of ``aov``) or an .npz (every buffer), never half-written."""
        path = Path(path)
        buffer = io.BytesIO()
        if path.suffix.lower() == ".png":
            buffer.write(self.png(aov))
        elif path.suffix.lower() == ".npz":
            np.savez_compressed(buffer, color=self.color, depth=self.depth, normal=self.normal,
                                steps=self.steps, object_id=self.object_id, hit=self.hit,
                                gamma=self.gamma, max_steps=self.max_steps,
                                backend=self.backend, precision=self.precision,
                                dither=self.dither, subpixel=self.subpixel,
                                **({} if self.path is None else {"path": self.path}))
        else:
            raise MarchlabError(f"{path}: unsupported output format {path.suffix!r} "
                                "(use .png or .npz)")
        write_atomically(path, buffer.getvalue())

    @classmethod
    def load(cls, path) -> "Frame":
        """Read a frame written by ``save(path)`` with an .npz suffix."""
        with np.load(path) as data:
            arrays = {k: data[k] for k in ("color", "depth", "normal", "steps", "object_id", "hit")}
            return cls(**arrays, gamma=float(data["gamma"]), max_steps=int(data["max_steps"]),
                       backend=str(data["backend"]), precision=str(data["precision"]),
                       path=data["path"] if "path" in data else None,
                       dither=bool(data["dither"]) if "dither" in data else False,
                       subpixel=float(data["subpixel"]) if "subpixel" in data else 0.0)


def png_bytes(image: np.ndarray) -> bytes:
    """The PNG file of an 8-bit (H, W, 3) picture, as bytes."""
    from PIL import Image
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG")
    return buffer.getvalue()


def to_uint8(x: np.ndarray, offsets: np.ndarray | None = None) -> np.ndarray:
    """[0, 1] floats to 0..255, rounding half up: floor(255 x + 0.5); with ``offsets``
    (H, W) in levels, in (-1/2, 1/2) (`dither_offsets`), floor(255 x + 0.5 + offset): ordered
    dithering, so a smooth ramp shows a fine pattern instead of bands."""
    level = np.clip(x, 0, 1) * 255 + 0.5
    if offsets is not None:
        level = level + (offsets[..., None] if level.ndim == 3 else offsets)
    return np.clip(np.floor(level), 0, 255).astype(np.uint8)


def bayer_matrix(size: int = 8) -> np.ndarray:
    """Bayer's ordered-dither index matrix (size, size) of 0..size^2 - 1, size a power of two
    (Bayer, "An optimum method for two-level rendition of continuous-tone pictures", IEEE
    ICC 1973): M_2n = [[4 M_n, 4 M_n + 2], [4 M_n + 3, 4 M_n + 1]] from M_1 = [[0]]."""
    matrix = np.zeros((1, 1), np.int64)
    while len(matrix) < size:
        matrix = np.block([[4 * matrix, 4 * matrix + 2], [4 * matrix + 3, 4 * matrix + 1]])
    return matrix


def dither_offsets(height: int, width: int) -> np.ndarray:
    """The offset (H, W) in 8-bit levels added before rounding at each pixel: the 8x8 Bayer
    matrix tiled from the top-left pixel, (index + 1/2) / 64 - 1/2, in (-1/2, 1/2). Over each
    8x8 tile the offsets are spread evenly, so a flat colour's mean level is kept (to 1/64 of
    a level) while the rounding error is moved to a fine, regular pattern."""
    tile = (bayer_matrix(8) + 0.5) / 64 - 0.5
    reps = (-(-height // 8), -(-width // 8))
    return np.tile(tile, reps)[:height, :width]
