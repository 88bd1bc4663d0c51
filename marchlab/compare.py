"""Compare two frames of the same scene: where they disagree, and by how much.

The statistics follow reftest practice (Khronos CTS, Firefox reftests): report everything,
and judge each kind of pixel by what can legitimately differ there.

- **coverage**: pixels whose hit flag differs. Near a silhouette a ray grazes the surface and
  either answer is defensible, so each such pixel is also tested for lying within 1 pixel of
  the reference's silhouette;
- **interior**: pixels hit in both frames and more than ``erode`` pixels from any edge (a
  silhouette, or a boundary between two objects, where depth jumps), where depth, normal and
  colour must agree closely;
- **display**: the 8-bit images as a person sees them, outside the excused coverage pixels;
- **PSNR** of the colour over the whole image, as a trend.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .frame import Frame


@dataclass
class Comparison:
    """What `compare_frames` measured, frame ``b`` against the reference ``a``."""
    pixels: int                  # W * H
    hit_differs: int             # pixels hit in one frame and missed in the other
    hit_differs_far: int         # ... of those, more than 1 pixel from a's silhouette
    object_id_differs: int       # pixels hit in both whose object ids differ
    interior: int                # pixels hit in both, eroded away from silhouettes
    depth_max: float             # max |t_a - t_b| over the interior
    depth_max_relative: float    # max |t_a - t_b| / t_a over the interior
    normal_max_degrees: float    # max angle between the normals over the interior
    color_max: float             # max |colour_a - colour_b| (any channel) over the interior
    display_max: int             # max 8-bit difference outside the excused coverage pixels
    psnr: float                  # of the linear colour over the whole image, in dB (inf: equal)

    def rows(self) -> list[tuple[str, str]]:
        """(name, value) pairs for printing as a table."""
        return [(f.name, _fmt(getattr(self, f.name))) for f in fields(self)]


def _fmt(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def compare_frames(a: Frame, b: Frame, erode: int = 2) -> Comparison:
    """Statistics of frame ``b`` against the reference frame ``a`` (same size and scene)."""
    if a.color.shape != b.color.shape:
        raise ValueError(f"frames differ in size: {a.color.shape[:2]} and {b.color.shape[:2]}")
    differs = a.hit != b.hit
    excused = differs & dilate(boundary(a.hit), 1)
    both = a.hit & b.hit
    interior = both & ~dilate(edges(a) | edges(b), erode)

    ta, tb = a.depth[interior].astype(np.float64), b.depth[interior].astype(np.float64)
    na, nb = a.normal[interior].astype(np.float64), b.normal[interior].astype(np.float64)
    # atan2(|a x b|, a . b) is accurate for small angles, where arccos(a . b) is not.
    angle = np.arctan2(np.linalg.norm(np.cross(na, nb), axis=-1), np.sum(na * nb, axis=-1))
    ca, cb = a.color.astype(np.float64), b.color.astype(np.float64)
    display = np.abs(a.image().astype(np.int16) - b.image().astype(np.int16)).max(axis=-1)
    mse = float(np.mean((ca - cb) ** 2))
    return Comparison(
        pixels=a.hit.size,
        hit_differs=int(differs.sum()),
        hit_differs_far=int((differs & ~excused).sum()),
        object_id_differs=int((both & (a.object_id != b.object_id)).sum()),
        interior=int(interior.sum()),
        depth_max=_max(np.abs(ta - tb)),
        depth_max_relative=_max(np.abs(ta - tb) / np.maximum(np.abs(ta), 1e-30)),
        normal_max_degrees=_max(np.degrees(angle)),
        color_max=_max(np.abs(ca[interior] - cb[interior])),
        display_max=int(display[~excused].max(initial=0)),
        psnr=float("inf") if mse == 0 else float(10 * np.log10(1 / mse)),
    )


def _max(values: np.ndarray) -> float:
    return float(values.max()) if values.size else 0.0


def edges(frame: Frame) -> np.ndarray:
    """Pixels on a silhouette or on a boundary between two objects."""
    return boundary(np.where(frame.hit, frame.object_id, -1))


def boundary(labels: np.ndarray) -> np.ndarray:
    """Pixels (H, W) whose label differs from one of their 8 neighbours'."""
    padded = np.pad(labels, 1, mode="edge")
    h, w = labels.shape
    out = np.zeros(labels.shape, dtype=bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            out |= padded[dy:dy + h, dx:dx + w] != labels
    return out


def dilate(mask: np.ndarray, radius: int) -> np.ndarray:
    """True within ``radius`` pixels (a square neighbourhood) of a True pixel."""
    h, w = mask.shape
    padded = np.pad(mask, radius)
    out = np.zeros_like(mask)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out |= padded[dy:dy + h, dx:dx + w]
    return out
