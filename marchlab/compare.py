"""Compare two frames of the same scene: where they disagree, and by how much.

The statistics follow reftest practice (Khronos CTS, Firefox reftests): report everything,
and judge each kind of pixel by what can legitimately differ there.

- **coverage**: pixels whose hit flag differs. Near a silhouette a ray grazes the surface and
  either answer is defensible, so each such pixel is also tested for lying within 1 pixel of
  the reference's silhouette;
- **interior**: pixels hit in both frames and more than ``erode`` pixels from any edge (a
  silhouette, or a boundary between two objects, where depth jumps), where depth, normal and
  colour must agree closely;
- **display**: the 8-bit images as a person sees them, outside the excused pixels;
- **PSNR** and **SSIM** of the colour over the whole image, as trends.

Colour and display also excuse pixels whose path labels differ (`Frame.path`: the two
renderers saw a different surface, checker cell or hard-shadow state along the pixel's path,
at a reflected checker edge or a shadow edge), as long as they lie within 1 px of a jump in
the reference's label; like coverage pixels they are counted and limited, not hidden.
A hardware rasteriser samples a pixel's surface up to a small fraction of a pixel from its
centre (`Frame.subpixel`): its picture is then measured from the range of the reference's
values around the centre (``around``, `reference_around`), not from the one at the centre
(docs/equivalence.md, "Sub-pixel precision").
`failures` applies the gates (`Gates`) and says in one line each what failed; `gate_notes`
labels each figure a gate (with its limit) or a trend, as ``marchlab compare`` prints them.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from scene_model.camera import turned
from scene_model.files import write_together
from scene_model.frame import Frame
from scene_model.geometry import angle_between


@dataclass
class Comparison:
    """What `compare_frames` measured, frame ``b`` against the reference ``a``."""
    pixels: int                  # W * H
    hit_differs: int             # pixels hit in one frame and missed in the other
    hit_differs_far: int         # ... of those, more than 1 pixel from a's silhouette
    object_id_differs: int       # pixels hit in both whose object ids differ
    interior: int                # pixels hit in both, eroded away from silhouettes
    path_differs: int            # pixels hit (or missed) in both whose path labels differ
    path_differs_far: int        # ... of those, more than 1 px from a jump in a's path label
    depth_max: float             # max |t_a - t_b| over the interior
    depth_max_relative: float    # max |t_a - t_b| / t_a over the interior
    depth_excess: float          # max |t_a - t_b| / max(2 epsilon, 1e-5 t_a): <= 1 passes
    normal_max_degrees: float    # max angle between the normals over the interior, off jumps
    color_max: float             # max |colour_a - colour_b| over the interior, off discontinuities
    color_max_path_differs: float  # the same where the path labels differ (reported)
    path_straddles: int          # pixels a label jump passes within b's sub-pixel precision of
    display_max: int             # max 8-bit difference outside all excused pixels
    psnr: float                  # of the linear colour over the whole image, in dB (inf: equal)
    ssim: float                  # structural similarity of the colour (nan without scikit-image)

    def rows(self) -> list[tuple[str, str]]:
        """(name, value) pairs for printing as a table."""
        return [(f.name, _fmt(getattr(self, f.name))) for f in fields(self)]


@dataclass(frozen=True)
class Gates:
    """The limits a backend must meet against the reference: coverage, interior and display
    (docs/equivalence.md, "The gates")."""
    coverage_fraction: float = 0.0005     # hit flags may differ on at most 0.05% of pixels
    path_fraction: float = 0.0005         # ... and path labels (near a jump) on at most this
    depth_excess: float = 1.0             # |dt| <= max(2 epsilon, 1e-5 t)
    normal_degrees: float = 0.5
    color: float = 1 / 255
    display: int = 1


# Pictures of triangle meshes jump at every edge between two smooth patches (a cube's edges,
# a cone's apex), where two rasterisers' rounding may pick either side: far more pixels lie on
# such a jump than on a sphere-traced picture's silhouettes, shadows and checker edges.
MESH_PATH_FRACTION = 0.002


def gates_against(reference_precision: str, meshes: bool = False) -> Gates:
    """The gates for a float32 candidate against a reference in ``reference_precision``.

    Against the float64 reference the colour may differ by 2/255: the candidate's float32
    rounding is then one more source of difference than against the float32 reference.
    Two pictures of triangle ``meshes`` may differ in path on `MESH_PATH_FRACTION` of the
    pixels, each within a pixel of a jump.
    """
    color = (2 if reference_precision == "float64" else 1) / 255
    if meshes:
        return Gates(color=color, path_fraction=MESH_PATH_FRACTION)
    return Gates(color=color)


def failures(c: Comparison, gates: Gates) -> list[str]:
    """One line per gate that ``c`` fails; empty when it passes them all."""
    out = []
    if c.hit_differs_far:
        out.append(f"coverage: {c.hit_differs_far} pixels differ in hit more than 1 px from "
                   "the reference silhouette")
    if c.hit_differs > gates.coverage_fraction * c.pixels:
        out.append(f"coverage: {c.hit_differs} pixels differ in hit "
                   f"(limit {gates.coverage_fraction:.2%} = "
                   f"{gates.coverage_fraction * c.pixels:.1f})")
    if c.path_differs_far:
        out.append(f"paths: {c.path_differs_far} pixels saw different surfaces, checker cells or "
                   "shadows more than 1 px from a discontinuity of the reference")
    if c.path_differs > gates.path_fraction * c.pixels:
        out.append(f"paths: {c.path_differs} pixels saw different surfaces, checker cells or "
                   f"shadows (limit {gates.path_fraction:.2%} = "
                   f"{gates.path_fraction * c.pixels:.1f})")
    if not c.depth_excess <= gates.depth_excess:
        out.append(f"interior depth: |dt| reaches {c.depth_excess:.3g} x max(2 epsilon, 1e-5 t)")
    if not c.normal_max_degrees <= gates.normal_degrees:
        out.append(f"interior normal: {c.normal_max_degrees:.3g} deg > {gates.normal_degrees} deg")
    if not c.color_max <= gates.color:
        out.append(f"interior colour: {c.color_max:.4g} > {gates.color:.4g} "
                   f"({c.color_max * 255:.2f}/255)")
    if c.display_max > gates.display:
        out.append(f"display: 8-bit images differ by {c.display_max} levels > {gates.display}")
    return out


GATE_LEGEND = ("gate: the comparison fails beyond the limit shown; "
               "trend: measured to watch, never failed")


def gate_notes(gates: Gates, pixels: int) -> dict[str, str]:
    """Each `Comparison` field's role, for the table ``marchlab compare`` prints: a gate with
    its limit (what `failures` checks) or a trend (measured, never failed)."""
    share = f"{gates.coverage_fraction * pixels:.1f} ({gates.coverage_fraction:.2%} of pixels)"
    path_share = f"{gates.path_fraction * pixels:.1f} ({gates.path_fraction:.2%} of pixels)"
    notes = {f.name: "trend" for f in fields(Comparison)}
    notes.update(
        pixels="", interior="",
        hit_differs=f"gate: <= {share}", hit_differs_far="gate: 0",
        path_differs=f"gate: <= {path_share}", path_differs_far="gate: 0",
        depth_excess=f"gate: <= {gates.depth_excess:g}",
        normal_max_degrees=f"gate: <= {gates.normal_degrees:g}",
        color_max=f"gate: <= {gates.color:.4g} ({gates.color * 255:.0f}/255)",
        display_max=f"gate: <= {gates.display}")
    return notes


def _fmt(value) -> str:
    """A figure as printed; nan, a figure that could not be measured here, is ``n/a``."""
    if isinstance(value, float):
        return "n/a" if np.isnan(value) else f"{value:.6g}"
    return str(value)


def compare_frames(a: Frame, b: Frame, erode: int = 2, epsilon: float | None = None,
                   around: tuple[Frame, ...] = ()) -> Comparison:
    """Statistics of frame ``b`` against the reference frame ``a`` (same size and scene).

    ``epsilon`` is the scene's hit threshold, which scales the depth gate; without it
    ``depth_excess`` is nan. Where both frames carry path labels, pixels whose hit flags
    agree but whose labels differ saw a different surface, checker cell or shadow state
    along their path (a reflected checker edge, a shadow edge; with anti-aliasing, a sample
    that grazed an edge in one frame only, even where the centre's ray missed in both):
    like pixels whose hit flags differ, they are excused from
    the colour and display statistics if they lie within 1 px of a jump in the reference's
    label, and counted in ``path_differs``.

    ``around`` holds the reference drawn again with its picture moved by a fraction of a
    pixel (`reference_around`), for a candidate that samples off the centres
    (`Frame.subpixel`). ``b``'s depth, normal, colour and 8-bit picture are then measured
    from the nearest value any of ``a`` and ``around`` shows at the pixel (the colours from
    the range they span, channel by channel), and its path label differs only where it
    differs from all of theirs. Without ``around`` each is measured from ``a`` alone.
    """
    if a.color.shape != b.color.shape:
        raise ValueError(f"frames differ in size: {a.color.shape[:2]} and {b.color.shape[:2]}")
    references = (a, *around)
    differs, excused, path_differs, near_jump = disagreements(a, b, around)
    straddles = straddling(a, around)
    both = a.hit & b.hit
    interior = both & ~dilate(edges(a) | edges(b), erode)
    smooth = interior & ~path_differs & ~straddles

    ta = a.depth[interior].astype(np.float64)
    depth_error = outside_range(b.depth[interior].astype(np.float64),
                                [r.depth[interior] for r in references])
    # Normals, like colours, may jump where the path labels do (a mesh's edge between two
    # smooth patches, `reference_cpu.raster_render.path_labels`).
    nb = b.normal[smooth].astype(np.float64)
    angle = np.min([angle_between(r.normal[smooth].astype(np.float64), nb)
                    for r in references], axis=0)
    ca, cb = a.color.astype(np.float64), b.color.astype(np.float64)
    color_diff = outside_range(cb, [r.color for r in references]).max(axis=-1)
    display = outside_range(b.image().astype(np.int16),
                            [r.image().astype(np.int16) for r in references]).max(axis=-1)
    mse = float(np.mean((ca - cb) ** 2))
    depth_bound = (np.maximum(2 * epsilon, 1e-5 * np.abs(ta)) if epsilon is not None else None)
    return Comparison(
        pixels=a.hit.size,
        hit_differs=int(differs.sum()),
        hit_differs_far=int((differs & ~excused).sum()),
        object_id_differs=int((both & (a.object_id != b.object_id)).sum()),
        interior=int(interior.sum()),
        path_differs=int(path_differs.sum()),
        path_differs_far=int((path_differs & ~near_jump).sum()),
        depth_max=_max(depth_error),
        depth_max_relative=_max(depth_error / np.maximum(np.abs(ta), 1e-30)),
        depth_excess=(_max(depth_error / depth_bound) if depth_bound is not None
                      else float("nan")),
        normal_max_degrees=_max(np.degrees(angle)),
        color_max=_max(color_diff[smooth]),
        color_max_path_differs=_max(color_diff[interior & path_differs]),
        path_straddles=int(straddles.sum()),
        display_max=int(display[~excused & ~path_differs & ~straddles].max(initial=0)),
        psnr=float("inf") if mse == 0 else float(10 * np.log10(1 / mse)),
        ssim=_ssim(ca, cb),
    )


def outside_range(values: np.ndarray, references) -> np.ndarray:
    """How far each of ``values`` lies outside the range the ``references`` (arrays of its
    shape) span there: 0 inside it, |value - reference| for one reference."""
    references = np.asarray(references, np.float64)
    low, high = references.min(axis=0), references.max(axis=0)
    with np.errstate(invalid="ignore"):            # inf - inf where all missed: no distance
        distance = np.maximum(np.maximum(values - high, low - values), 0.0)
    return np.nan_to_num(distance, nan=0.0)


def reference_around(scene, width: int, height: int, backend: str, subpixel: float,
                     precision: str | None = None) -> tuple[Frame, ...]:
    """The reference drawn four more times, its camera turned (`scene_model.camera.turned`)
    by (+-2 s, +-2 s) pixels, s = ``subpixel``, for a candidate that samples each pixel up
    to s pixels from its centre along each axis (`Frame.subpixel`).

    At every pixel the four turned samples enclose the square of side 2 s about the centre
    (a turn moves a point off the axis by more than it moves the centre, and a little
    across; tests/test_subpixel_compare.py checks the enclosure), so where the surface
    changes one way across that square, whatever the candidate samples in it lies within
    the range the centre's and the turned samples' values span. Empty for s = 0."""
    if subpixel <= 0:
        return ()
    from .render import render                    # the backends, only when needed
    turn = 2 * subpixel
    return tuple(
        render(replace(scene, camera=turned(scene.camera, dx, dy, width, height)),
               width, height, backend=backend, precision=precision, path_labels=True)
        for dx in (-turn, turn) for dy in (-turn, turn))


def _ssim(a: np.ndarray, b: np.ndarray) -> float:
    """Structural similarity of two colour images in [0, 1] (nan if it cannot be computed:
    without scikit-image, or under 3 pixels a side).

    The window is Wang et al.'s 7x7, or the largest odd one that fits a smaller image."""
    try:
        from skimage.metrics import structural_similarity
    except ImportError:
        return float("nan")
    side = min(a.shape[:2])
    window = min(7, side if side % 2 else side - 1)
    if window < 3:
        return float("nan")
    return float(structural_similarity(a, b, channel_axis=-1, data_range=1.0, win_size=window))


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


def disagreements(a: Frame, b: Frame, around: tuple[Frame, ...] = ()):
    """Where ``b`` saw something else than the reference ``a``, as four (H, W) bool masks.

    Returns ``(hit_differs, hit_excused, path_differs, near_jump)``: hit flags that differ,
    those of them within 1 px of a's silhouette, pixels whose hit flags agree but whose path
    labels differ (all False unless both frames have labels), and pixels within 1 px of a
    jump in a's label. Pixels missed in both count too: with anti-aliasing the label folds
    in every sample's (`reference_cpu.render.add_ray`), and a pixel whose centre misses may
    still have samples that hit. With ``around`` (`compare_frames`), a label differs only
    where it differs from each of theirs too.
    """
    differs = a.hit != b.hit
    excused = differs & dilate(boundary(a.hit), 1)
    if a.path is not None and b.path is not None:
        path_differs = ~differs & (a.path != b.path)
        for other in around:
            path_differs &= other.path != b.path
        near_jump = dilate(boundary(a.path.astype(np.int64)), 1)
    else:
        path_differs = near_jump = np.zeros_like(differs)
    return differs, excused, path_differs, near_jump


def straddling(a: Frame, around: tuple[Frame, ...]) -> np.ndarray:
    """(H, W): pixels where a label of ``around`` differs from ``a``'s: a jump of the picture
    lies within the square a candidate may sample (`Frame.subpixel`), so the pixel may show
    either side or a blend, which no range of the references encloses where two jumps cross
    (a checker's corner). All False without ``around`` or labels."""
    out = np.zeros(a.hit.shape, bool)
    if a.path is not None:
        for other in around:
            if other.path is not None:
                out |= (other.path != a.path) | (other.hit != a.hit)
    return out


def error_mask(a: Frame, b: Frame, gates: Gates, around: tuple[Frame, ...] = ()) -> np.ndarray:
    """Pixels (H, W) the gates do not excuse: a hit flag or path label that differs away from
    an edge of the reference, or a colour off by more than ``gates.color`` elsewhere (from
    the range of ``a``'s and ``around``'s, as `compare_frames` measures it)."""
    differs, excused, path_differs, near_jump = disagreements(a, b, around)
    color = outside_range(b.color.astype(np.float64),
                          [r.color for r in (a, *around)]).max(axis=-1) > gates.color
    return ((differs & ~excused) | (path_differs & ~near_jump)
            | (color & ~excused & ~path_differs & ~straddling(a, around)))


def write_difference_images(a: Frame, b: Frame, gates: Gates, directory,
                            around: tuple[Frame, ...] = ()) -> list:
    """Write a.png, b.png, the difference amplified x16 and the error mask; return the paths."""
    from PIL import Image                      # only when images are asked for
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    diff = np.clip(np.abs(a.color.astype(np.float64) - b.color) * 16, 0, 1)
    images = {
        f"a-{a.backend}-{a.precision}.png": a.image(),
        f"b-{b.backend}-{b.precision}.png": b.image(),
        "difference-x16.png": np.floor(diff * 255 + 0.5).astype(np.uint8),
        "error-mask.png": np.repeat(error_mask(a, b, gates, around)[..., None] * np.uint8(255),
                                    3, axis=-1),
    }
    payloads = {}
    for name, pixels in images.items():
        buffer = io.BytesIO()
        Image.fromarray(pixels).save(buffer, format="PNG")
        payloads[directory / name] = buffer.getvalue()
    write_together(payloads)             # all four, or none
    return list(payloads)
