"""Surface textures as data: the texels of a material's image and where they lie in the atlas.

A `scene_model.scene.Texture` names an image file (read as an environment's images are:
`scene_model.environment.read_image`, sRGB decoded to linear, refused in one line when it
cannot be read, is empty or holds NaN) or a built-in image made here. Every backend samples
the texels with the same code (reference_cpu/texture.py, gpu_shader/glsl/texture.glsl):

- `texture_image` gives a texture's texels, (H, W, 3) float32 linear RGB, row 0 the image's
  top row, read once while the file is unchanged;
- `texture_atlas` stacks a program's images (an environment's first, then each texture's)
  top to bottom into one array, as wide as the widest, each image in columns 0 to its width
  (the rest of its rows is never read);
- `surface_mapping` says how a primitive finds its place in its texture.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from .environment import _stamp, read_image, rgba_rows
from .scene import BUILTIN_TEXTURES, Texture

# How a textured object is mapped, coded in its material rows (0: no texture).
MAPPING_CODES = {"triplanar": 1, "sphere": 2, "cube": 3}


def surface_mapping(texture: Texture, kind: str) -> str:
    """How a primitive of ``kind`` ("sphere", "box", ...) is mapped by ``texture``:
    "triplanar"; or, for ``mapping = "uv"``, "sphere" (latitude and longitude of the normal)
    on a sphere and "cube" (the projection along the world axis nearest the normal) on any
    other primitive."""
    if texture.mapping == "triplanar":
        return "triplanar"
    return "sphere" if kind == "sphere" else "cube"


def texture_wrap(mapping: str) -> float:
    """The ``wrap`` of a mapping's texture (reference_cpu/texture.py): 2, repeated both ways,
    as the planar projections repeat it every ``scale``; 1 for the sphere, whose latitude runs
    from pole to pole once (its rows are clamped, its columns go round)."""
    return 1.0 if mapping == "sphere" else 2.0


# --- Images ----------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TextureImage:
    """The texels of one texture's image: (H, W, 3) float32 linear RGB, read-only."""
    texels: np.ndarray


def uv_grid(size: int = 32) -> np.ndarray:
    """(size, size, 3) float32: marchlab's built-in test image, linear RGB.

    Red follows sin 2 pi u and blue cos 2 pi u across, green sin 2 pi v down (so a mirrored
    or turned image shows), darkened by soft grid lines every quarter (a Gaussian of one
    texel). Every term is periodic, so the image repeats without a seam, and its texels
    change by at most 0.15 from one to the next: bilinear filtering shows no blocks.
    """
    centres = (np.arange(size) + 0.5) / size
    v, u = np.meshgrid(centres, centres, indexing="ij")      # row j: v, column i: u
    color = np.stack([0.5 + 0.3 * np.sin(2 * np.pi * u), 0.5 + 0.3 * np.sin(2 * np.pi * v),
                      0.5 + 0.3 * np.cos(2 * np.pi * u)], axis=-1)

    def line(x):                    # 1 on a grid line, falling off over a texel or so
        off = (x * 4 + 0.5) % 1.0 - 0.5                        # in quarters of the image
        return np.exp(-0.5 * (off * size / 4) ** 2)

    shade = 1 - 0.35 * np.maximum(line(u), line(v))
    return (color * shade[:, :, None]).astype(np.float32)


BUILTIN = {"uv_grid": uv_grid}
assert set(BUILTIN) == set(BUILTIN_TEXTURES)


def texture_image(texture: Texture) -> TextureImage:
    """The texels of ``texture``'s image: a built-in one, or its file (MarchlabError naming
    the file where it cannot be used), read once while the file is unchanged."""
    if texture.image in BUILTIN:
        return _builtin(texture.image)
    return _from_file(texture.image, _stamp(texture.image))


@lru_cache(maxsize=4)
def _builtin(name: str) -> TextureImage:
    return _image(BUILTIN[name]())


@lru_cache(maxsize=16)
def _from_file(path: str, stamp) -> TextureImage:
    return _image(read_image(path))


def _image(texels: np.ndarray) -> TextureImage:
    texels = np.ascontiguousarray(texels, dtype=np.float32)
    texels.setflags(write=False)          # shared by every frame: nobody may change it
    return TextureImage(texels)


# --- The atlas -------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Atlas:
    """Images stacked into one array of texels.

    Attributes
    ----------
    texels : (R, W, 3) float32 ndarray
        Image k in rows ``first[k]`` to ``first[k] + height - 1``, columns 0 to its width - 1;
        read-only.
    first : tuple of int
        The first row of each image.
    sizes : tuple of (int, int)
        The height and width of each image.
    """
    texels: np.ndarray
    first: tuple[int, ...]
    sizes: tuple[tuple[int, int], ...]

    @cached_property
    def rgba(self) -> np.ndarray:
        """(R, W, 4) float32: `rgba_rows` of the texels, made once, so that every frame
        hands on the same array."""
        return rgba_rows(self.texels)

    def image(self, k: int, wrap: float) -> tuple[float, float, float, float]:
        """Image k as the samplers take it: (first row, width, height, wrap)."""
        height, width = self.sizes[k]
        return (float(self.first[k]), float(width), float(height), float(wrap))


@lru_cache(maxsize=8)
def texture_atlas(parts: tuple) -> Atlas:
    """The atlas of ``parts``, each with the attribute ``texels`` (R, W, 3): an
    `EnvironmentMap`, `TextureImage` s. The same parts (the same objects, which the image
    caches hand out again) give the same atlas, so that a GPU uploads it once for many
    frames."""
    sizes = tuple(p.texels.shape[:2] for p in parts)
    texels = np.zeros((sum(h for h, _ in sizes), max(w for _, w in sizes), 3), np.float32)
    first, row = [], 0
    for part, (height, width) in zip(parts, sizes):
        texels[row:row + height, :width] = part.texels
        first.append(row)
        row += height
    texels.setflags(write=False)
    return Atlas(texels, tuple(first), sizes)
