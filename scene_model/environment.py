"""Environment maps as data: the linear RGB texels of a cube map or of a panorama.

A background of type ``cubemap``, ``equirect`` or ``studio`` (`scene_model.scene`) names its
images, or how to compute them; `environment_map` turns it into an `EnvironmentMap`, one
float32 array of texels that every backend samples with the same code
(reference_cpu/environment.py, gpu_shader/glsl/environment.glsl):

- a cube map of side S is its six faces stacked top to bottom, (6 S, S, 3): face f (in the
  order +x, -x, +y, -y, +z, -z) in rows f S to f S + S - 1;
- a panorama of W x H pixels is (H, W, 3);
- row 0 of every image is its top row, as an image file stores it.

Which texel a direction sees is the OpenGL rule: OpenGL 4.6 core spec, section 8.13 "Cube
Map Texture Selection", table 8.19 (`cube_face_directions` is its inverse). Colours: 8- and
16-bit images hold sRGB-encoded values and are decoded to linear light (IEC 61966-2-1, the
sRGB standard); floating-point images (a ``.npy`` array, a 32-bit TIFF) are taken as linear.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from .errors import MarchlabError
from .scene import CUBE_FACES, Background

CUBE_KINDS = ("cubemap", "studio")                 # the backgrounds that are cube maps
ENVIRONMENT_KINDS = CUBE_KINDS + ("equirect",)


@dataclass(frozen=True, eq=False)
class EnvironmentMap:
    """The texels of an environment and where its images lie in them.

    Attributes
    ----------
    texels : (R, W, 3) float32 ndarray
        Linear RGB, read-only: the six faces stacked (R = 6 W) or the panorama (R = H).
    cube : bool
        A cube map (True) or an equirectangular panorama.
    """
    texels: np.ndarray
    cube: bool

    @property
    def texture(self) -> tuple[float, float, float, float]:
        """The texture of the first face (of the panorama) as the samplers take it: (first
        row, width, height, wrap). A panorama wraps around left to right (wrap 1); a face is
        clamped at its edges (wrap 0); face f starts at row f * width."""
        rows, width, _ = self.texels.shape
        return (0.0, float(width), float(width if self.cube else rows), 0.0 if self.cube else 1.0)

    @cached_property
    def rgba(self) -> np.ndarray:
        """(R, W, 4) float32: `rgba_rows` of the texels, made once, so that every frame
        hands on the same array."""
        return rgba_rows(self.texels)


def rgba_rows(texels: np.ndarray) -> np.ndarray:
    """(R, W, 4) float32, read-only: texels (R, W, 3) with a fourth channel of 0, as a GPU's
    rows of four hold them."""
    rgba = np.zeros(texels.shape[:2] + (4,), np.float32)
    rgba[:, :, :3] = texels
    rgba.setflags(write=False)
    return rgba


def turn(degrees: float) -> tuple[float, float]:
    """(cos, sin) of a ``rotation`` in degrees, in float64: what every backend rounds."""
    angle = math.radians(degrees)
    return math.cos(angle), math.sin(angle)


# --- Directions of texel centres -------------------------------------------------------------

def cube_face_directions(size: int) -> np.ndarray:
    """(6, S, S, 3) float64: the unit direction through the centre of every texel of a cube
    map of side S, face by face (+x, -x, +y, -y, +z, -z), row 0 at the top.

    Table 8.19 of the OpenGL 4.6 core spec gives, for the face of the major axis, the face
    coordinates sc, tc of a direction and s = (sc / |ma| + 1) / 2, t = (tc / |ma| + 1) / 2;
    here it is read backwards, from sc = 2 s - 1 and tc = 2 t - 1 at each texel centre.
    """
    centres = (np.arange(size) + 0.5) / size * 2 - 1
    tc, sc = np.meshgrid(centres, centres, indexing="ij")      # row j: tc, column i: sc
    one = np.ones_like(sc)
    faces = [(one, -tc, -sc), (-one, -tc, sc),                 # +x, -x
             (sc, one, tc), (sc, -one, -tc),                   # +y, -y
             (sc, -tc, one), (-sc, -tc, -one)]                 # +z, -z
    d = np.stack([np.stack(face, axis=-1) for face in faces])
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def equirect_directions(width: int, height: int) -> np.ndarray:
    """(H, W, 3) float64: the unit direction through the centre of every pixel of a
    panorama, the inverse of u = atan2(x, -z) / 2 pi + 1/2, v = acos(y) / pi: the middle
    column looks along -z, the right quarter along +x, row 0 straight up."""
    azimuth = ((np.arange(width) + 0.5) / width - 0.5) * 2 * np.pi
    polar = (np.arange(height) + 0.5) / height * np.pi
    polar, azimuth = np.meshgrid(polar, azimuth, indexing="ij")
    return np.stack([np.sin(polar) * np.sin(azimuth), np.cos(polar),
                     -np.sin(polar) * np.cos(azimuth)], axis=-1)


# --- The studio: marchlab's own environment ---------------------------------------------------

SUN = np.array([-0.45, 0.55, -0.7]) / np.linalg.norm([-0.45, 0.55, -0.7])
# Soft boxes: (azimuth in degrees from -z toward +x, linear colour).
PANELS = ((90.0, (0.95, 0.22, 0.12)), (-90.0, (0.15, 0.75, 0.3)), (180.0, (0.15, 0.35, 1.0)),
          (35.0, (1.0, 0.8, 0.15)))


def _smoothstep(edge0, edge1, x):
    u = np.clip((x - edge0) / (edge1 - edge0), 0, 1)
    return u * u * (3 - 2 * u)


def studio_radiance(d: np.ndarray) -> np.ndarray:
    """(N, 3) linear colour the studio shows in the unit directions ``d`` (N, 3).

    A grey floor below the horizon, a sky from pale at the horizon to blue overhead, a sun
    disc (half-angle 3 degrees, soft over 2 more) and four coloured soft boxes (30 degrees
    wide, from 8 to 38 degrees above the horizon, soft over 3 degrees): smooth enough that
    bilinear filtering of 64 texels a face shows no blocks, and different in every
    direction, so that a mirror shows where it reflects.
    """
    y = d[:, 1:2]
    sky = np.array([0.85, 0.88, 0.92]) + (np.array([0.25, 0.45, 0.85])
                                          - np.array([0.85, 0.88, 0.92])) * np.sqrt(np.abs(y))
    ground = np.array([0.42, 0.4, 0.37]) - 0.22 * np.sqrt(np.abs(y))
    color = ground + (sky - ground) * _smoothstep(-0.03, 0.03, y)
    sun = _smoothstep(math.cos(math.radians(5.0)), math.cos(math.radians(3.0)), d @ SUN)
    color = color + sun[:, None] * np.array([3.0, 2.8, 2.4])
    azimuth = np.degrees(np.arctan2(d[:, 0], -d[:, 2]))
    elevation = np.degrees(np.arcsin(np.clip(d[:, 1], -1, 1)))
    rise = _smoothstep(5.0, 8.0, elevation) * (1 - _smoothstep(38.0, 41.0, elevation))
    for centre, panel in PANELS:
        off = np.abs((azimuth - centre + 180.0) % 360.0 - 180.0)
        weight = rise * (1 - _smoothstep(15.0, 18.0, off))
        color = color + weight[:, None] * (np.array(panel) - color)
    return color


def studio_faces(size: int) -> np.ndarray:
    """(6, S, S, 3) float32: the studio's cube map, each texel the colour at its centre."""
    d = cube_face_directions(size).reshape(-1, 3)
    return studio_radiance(d).reshape(6, size, size, 3).astype(np.float32)


# --- Images from files -----------------------------------------------------------------------

def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] to linear light (IEC 61966-2-1): c / 12.92 up to
    0.04045, ((c + 0.055) / 1.055)^2.4 above."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def read_image(path: str) -> np.ndarray:
    """(H, W, 3) float32 linear RGB of an image file, or MarchlabError naming the file.

    A ``.npy`` file is a float array (H, W, 3) or (H, W) read as it is; any other file is
    read with imageio: 8- and 16-bit values are sRGB-decoded, floats kept; grey becomes
    RGB; an alpha channel is dropped. Refused in one line: a file that cannot be read, an
    image of 0 pixels, and NaN, infinite or negative values.
    """
    try:
        if path.endswith(".npy"):
            pixels = np.load(path, allow_pickle=False)
        else:
            import imageio.v3 as iio
            pixels = iio.imread(path)
    except ImportError:
        raise _refused(path, "reading an image needs imageio (pip install imageio), or "
                             "save it as a .npy array") from None
    except OSError as err:
        if err.errno is not None:                  # the file system's: missing, a folder...
            raise _refused(path, f"cannot read: {err.strerror}") from None
        raise _refused(path, f"not an image marchlab can read ({_first_line(err)})") from None
    except Exception as err:        # noqa: BLE001 - each image format fails in its own way
        raise _refused(path, f"not an image marchlab can read ({_first_line(err)})") from None
    return _linear_rgb(np.asarray(pixels), path)


def _refused(path: str, problem: str) -> MarchlabError:
    """The one-line error for an image file: its name, then what is wrong with it."""
    return MarchlabError(f"{_shown(path)}: {problem}")


def _shown(path: str) -> str:
    """A file name for a one-line message: as written, or quoted where it holds a line break
    or another character that does not print, and cut short past 200 characters."""
    text = path if path.isprintable() else json.dumps(path)
    return text if len(text) <= 200 else f"{text[:120]}...{text[-60:]}"


def _first_line(err: Exception) -> str:
    lines = str(err).strip().splitlines()
    return f"{type(err).__name__}: {lines[0][:120] if lines else ''}".rstrip(": ")


def _linear_rgb(pixels: np.ndarray, path: str) -> np.ndarray:
    """``pixels`` as (H, W, 3) float32 linear RGB; MarchlabError where they cannot be."""
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    if pixels.ndim != 3 or pixels.shape[2] not in (1, 3, 4):
        raise _refused(path, "is not an image of grey, RGB or RGBA pixels (array of shape "
                             f"{pixels.shape})")
    if pixels.shape[0] == 0 or pixels.shape[1] == 0:
        raise _refused(path, f"is empty ({pixels.shape[1]} x {pixels.shape[0]} pixels)")
    rgb = pixels[:, :, :3] if pixels.shape[2] >= 3 else np.repeat(pixels, 3, axis=2)
    if rgb.dtype.kind in "ui":
        top = np.iinfo(rgb.dtype).max
        rgb = srgb_to_linear(rgb.astype(np.float64) / top)
    elif rgb.dtype.kind != "f":
        raise _refused(path, f"holds {rgb.dtype} values, not numbers of colour")
    bad = ~np.isfinite(rgb)
    if bad.any():
        row, column, _ = np.argwhere(bad)[0]
        raise _refused(path, f"has NaN or infinite values (the first at row {row}, column "
                             f"{column})")
    if (rgb < 0).any():
        row, column, _ = np.argwhere(rgb < 0)[0]
        raise _refused(path, f"has negative values (the first at row {row}, column {column})")
    rgb = rgb.astype(np.float32)
    if not np.isfinite(rgb).all():
        raise _refused(path, "has values too large for float32")
    return rgb


def cube_faces(paths) -> np.ndarray:
    """(6, S, S, 3) float32: the six images of a cube map, which must be square and of one
    size (MarchlabError naming the face that is not)."""
    faces = []
    for name, path in zip(CUBE_FACES, paths):
        image = read_image(path)
        height, width, _ = image.shape
        if width != height:
            raise _refused(path, f"cube map face {name} is {width} x {height} pixels; each "
                                 "face must be square")
        if faces and image.shape != faces[0].shape:
            size = faces[0].shape[0]
            raise _refused(path, f"cube map face {name} is {width} x {height} pixels, but face "
                                 f"+x ({_shown(paths[0])}) is {size} x {size}; all six faces "
                                 "must be the same size")
        faces.append(image)
    return np.stack(faces)


# --- Backgrounds to texels -------------------------------------------------------------------

def environment_map(background: Background) -> EnvironmentMap:
    """The texels of an environment background (``cubemap``, ``equirect`` or ``studio``).

    Images are read once and kept while their files are unchanged (the same background
    renders every frame of a view or an animation without reading them again).
    """
    files = {"cubemap": lambda b: b.faces, "equirect": lambda b: (b.image,)}
    if background.kind == "studio":
        return _studio(background.size)
    if background.kind not in files:
        raise ValueError(f"{background.kind} is not an environment background")
    paths = tuple(files[background.kind](background))
    return _from_files(background.kind, paths, tuple(_stamp(p) for p in paths))


def _stamp(path: str):
    """What tells a changed file from the one read before: its time and size (None if it
    cannot be seen: reading it will say why)."""
    try:
        status = os.stat(path)
    except (OSError, ValueError):
        return None
    return status.st_mtime_ns, status.st_size


@lru_cache(maxsize=4)
def _studio(size: int) -> EnvironmentMap:
    return _environment(studio_faces(size).reshape(6 * size, size, 3), cube=True)


@lru_cache(maxsize=4)
def _from_files(kind: str, paths: tuple, stamps: tuple) -> EnvironmentMap:
    if kind == "cubemap":
        faces = cube_faces(paths)
        return _environment(faces.reshape(-1, faces.shape[2], 3), cube=True)
    return _environment(read_image(paths[0]), cube=False)


def _environment(texels: np.ndarray, cube: bool) -> EnvironmentMap:
    texels = np.ascontiguousarray(texels, dtype=np.float32)
    texels.setflags(write=False)          # shared by every frame: nobody may change it
    return EnvironmentMap(texels, cube)
