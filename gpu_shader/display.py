"""The display pass: the picture a person sees, drawn on the GPU from the planes a program drew.

`gpu_shader.render.Renderer` leaves three planes in a framebuffer (`gpu_shader.planes`);
`Display.draw` turns them into 8-bit colours in whatever framebuffer is bound (a window, or an
offscreen one for a screenshot) with one full-screen draw of ``glsl/display.frag``. Each
overlay is what `scene_model.frame.Frame.image` gives for the same buffer, within one level
of 255, with two additions for a live view: ``object_id`` (a colour per object, `id_colors`)
and an outline around the selected objects (`outline_mask`). The NumPy functions here are the
shader's twins, with the same names, so the tests can hold one against the other.

The depth overlay grades from the nearest to the farthest hit, which a shader drawing one
pixel cannot know: the caller reads plane 1 back and passes `depth_range` of it, and only
needs to while the depth overlay is shown (`Display.read_depth_range` does both).
"""

from __future__ import annotations

import numpy as np

from scene_model.colormaps import HEAT_COLORS, HEAT_STOPS
from scene_model.errors import MarchlabError
from scene_model.frame import AOVS, to_uint8

from .library import fill_template, glsl_file

OVERLAYS = (*AOVS, "object_id")   # what `Display.draw` can show: the Frame's AOVs, then ids
MAX_SELECTED = 64                 # selected object ids the outline can follow
OUTLINE_COLOR = (1.0, 0.55, 0.0)  # bright orange


# --- the NumPy twins of the shader ----------------------------------------------------------

def depth_range(depth: np.ndarray, hit: np.ndarray | None = None) -> tuple[float, float]:
    """The nearest and farthest hit depth, the ends of the depth overlay's grey ramp.

    Parameters
    ----------
    depth : (H, W) ndarray
        Depth t per pixel (plane 1's fourth channel, or `Frame.depth`); inf on a miss.
    hit : (H, W) bool ndarray, optional
        Which pixels hit; by default those of finite depth.

    Returns
    -------
    (near, far) : floats, as `Frame.image("depth")` takes them; (0, 1) when nothing was hit.
    """
    hit = np.isfinite(depth) if hit is None else hit
    if not hit.any():
        return 0.0, 1.0
    t = depth[hit]
    return float(t.min()), float(t.max())


def id_colors(object_id: np.ndarray) -> np.ndarray:
    """A colour per object id: (H, W) int ids to (H, W, 3) uint8, black where id is -1.

    The "lowbias32" integer hash (Chris Wellons, "Prospecting for Hash Functions", 2018,
    https://nullprogram.com/blog/2018/07/31/) spreads neighbouring ids far apart; its low
    three bytes are the colour, each mapped into 64..255 so that no object is as black as a
    miss. The shader's ``id_colors`` computes the same bytes.
    """
    x = np.asarray(object_id).astype(np.uint32)       # unsigned 32-bit: products wrap
    x ^= x >> 16
    x *= np.uint32(0x7FEB352D)
    x ^= x >> 15
    x *= np.uint32(0x846CA68B)
    x ^= x >> 16
    channels = np.stack([(x >> shift) & 0xFF for shift in (0, 8, 16)], axis=-1)
    colors = (64 + ((channels * 3) >> 2)).astype(np.uint8)
    return np.where((np.asarray(object_id) >= 0)[..., None], colors, np.uint8(0))


def outline_mask(object_id: np.ndarray, selected) -> np.ndarray:
    """Pixels of the selection outline: (H, W) ids to an (H, W) bool mask.

    A pixel is on the outline when it is not selected but one of its four neighbours (up,
    down, left, right, inside the image) is, so the outline hugs the selection from outside.

    Parameters
    ----------
    object_id : (H, W) int ndarray
        Object id per pixel (-1 on a miss).
    selected : iterable of int
        The selected object ids.
    """
    inside = np.isin(object_id, list(selected))
    near = np.zeros_like(inside)
    near[1:, :] |= inside[:-1, :]         # the pixel above is selected
    near[:-1, :] |= inside[1:, :]         # ... below
    near[:, 1:] |= inside[:, :-1]         # ... to the left
    near[:, :-1] |= inside[:, 1:]         # ... to the right
    return near & ~inside


def overlay_image(frame, aov: str = "color", selected=(),
                  outline: tuple[float, float, float] = OUTLINE_COLOR) -> np.ndarray:
    """The whole display pass in NumPy: ``frame``'s picture of ``aov`` (`Frame.image`, or
    `id_colors` for "object_id") with the outline of the ``selected`` ids painted over it,
    as an (H, W, 3) uint8 array. A screenshot of the view is this, exactly as `marchlab
    render` encodes the same frame."""
    if aov not in OVERLAYS:
        raise MarchlabError(f"unknown overlay {aov!r} (one of: {', '.join(OVERLAYS)})")
    image = id_colors(frame.object_id) if aov == "object_id" else frame.image(aov)
    if len(selected):
        image = image.copy()
        image[outline_mask(frame.object_id, selected)] = to_uint8(np.asarray(outline))
    return image


# --- the pass on the GPU --------------------------------------------------------------------

def display_source(aov: str, outline: bool) -> str:
    """The display pass's fragment shader for one overlay, with or without the selection's
    outline (``glsl/display.frag`` filled in: only that overlay's code is in it)."""
    if aov not in OVERLAYS:
        raise MarchlabError(f"unknown overlay {aov!r} (one of: {', '.join(OVERLAYS)})")
    return fill_template("display.frag", overlay=aov, outline=outline,
                         heat_stop_count=len(HEAT_STOPS), max_selected=MAX_SELECTED)


class Display:
    """The display programs on one moderngl context (one per overlay and outline, made when
    first drawn), and offscreen targets for `image`."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.programs: dict[tuple[str, bool], tuple] = {}
        self.offscreen: dict[tuple[int, int], object] = {}

    def _program(self, aov: str, outline: bool):
        """(program, vertex array) for ``aov`` with or without the outline; the context is
        current."""
        key = (aov, outline)
        if key not in self.programs:
            program = self.ctx.program(vertex_shader=glsl_file("fullscreen.vert"),
                                       fragment_shader=display_source(aov, outline))
            for unit, name in enumerate(("color_hit", "normal_depth", "steps_id")):
                if name in program:
                    program[name].value = unit
            if "heat_stops" in program:
                program["heat_stops"].write(HEAT_STOPS.astype(np.float32).tobytes())
                program["heat_colors"].write(HEAT_COLORS.astype(np.float32).tobytes())
            self.programs[key] = (program, self.ctx.vertex_array(program, []))
        return self.programs[key]

    def draw(self, target, aov: str = "color", *, gamma: float = 2.2, max_steps: int = 256,
             depth_range: tuple[float, float] = (0.0, 1.0), selected=(),
             outline: tuple[float, float, float] = OUTLINE_COLOR, viewport=None) -> None:
        """Draw the picture of ``target`` into the bound framebuffer.

        Parameters
        ----------
        target : moderngl.Framebuffer or three textures
            The planes, as `Renderer.target` holds them after a draw.
        aov : str
            One of `OVERLAYS`.
        gamma, max_steps : float, int
            As in `Frame` (the scene's ``render.gamma``, and ``render.max_steps`` times
            the primary rays a pixel shoots: `scene_model.sampling.pixel_max_steps`).
        depth_range : (near, far)
            The ends of the depth overlay's ramp: `depth_range` of plane 1.
        selected : iterable of int
            Object ids to outline (at most `MAX_SELECTED`); empty: no outline.
        outline : (r, g, b) in [0, 1]
            The outline's colour, painted over any overlay.
        viewport : (x, y, width, height), optional
            Where to draw, in the framebuffer's pixels (default: its current viewport). A
            target smaller than that is enlarged, nearest texel; the image's top row is drawn
            at the top, as a window shows it.

        Enable flags (blending, depth test) are left as they are (the pass writes opaque
        pixels), and so is the framebuffer's viewport.
        """
        if aov not in OVERLAYS:
            raise MarchlabError(f"unknown overlay {aov!r} (one of: {', '.join(OVERLAYS)})")
        ids = sorted({int(i) for i in selected})
        if len(ids) > MAX_SELECTED:
            raise MarchlabError(f"{len(ids)} objects selected; the outline follows at most "
                                f"{MAX_SELECTED}")
        with self.ctx:
            program, vao = self._program(aov, outline=bool(ids))
            values = {"gamma": float(gamma), "max_steps": float(max_steps),
                      "depth_range": tuple(float(d) for d in depth_range),
                      "selected_count": len(ids),
                      "outline_color": tuple(float(c) for c in outline)}
            for name, value in values.items():
                if name in program:              # each program has only what it uses
                    program[name].value = value
            if "selected" in program:
                padded = np.resize(np.array(ids + [-1], np.int32), MAX_SELECTED)
                program["selected"].write(padded.tobytes())
            for unit, texture in enumerate(_planes(target)):
                texture.use(location=unit)
            previous = self.ctx.viewport
            if viewport is not None:
                self.ctx.viewport = viewport
            program["viewport"].value = tuple(int(v) for v in self.ctx.viewport)
            try:
                vao.render(vertices=3)
            finally:
                self.ctx.viewport = previous

    def warm(self, framebuffer, aov: str = "color", outline: bool = True) -> None:
        """Make the program for ``aov`` (with the outline or not) and draw it once, into one
        pixel of ``framebuffer``, so that a driver which compiles at the first draw
        (llvmpipe: about 0.1 s, for each format of framebuffer drawn into) has done so
        before a live view needs it, e.g. on the click that first selects an object. The
        pixel is left for the caller's next clear."""
        with self.ctx:
            # 3 x 3: a driver may compile apart for power-of-two sizes (llvmpipe does).
            planes = [self.ctx.texture((3, 3), 4, dtype=dtype) for dtype in ("f4", "f4", "i4")]
            framebuffer.use()
        try:
            self.draw(planes, aov, selected=(0,) if outline else (), viewport=(0, 0, 1, 1))
        finally:
            with self.ctx:
                for texture in planes:
                    texture.release()

    def image(self, target, aov: str = "color", **settings) -> np.ndarray:
        """The picture `draw` makes, at the target's size, as an (H, W, 3) uint8 array, top
        row first. ``settings``: those of `draw` but ``viewport``. The framebuffer bound
        before is bound again after."""
        width, height = _planes(target)[0].size
        fbo = self._offscreen(width, height)
        with self.ctx:           # a `with` does not nest, so `draw` has its own
            previous = self.ctx.fbo
            fbo.use()
            self.ctx.clear(0.0, 0.0, 0.0, 1.0)
        self.draw(target, aov, viewport=(0, 0, width, height), **settings)
        with self.ctx:
            # Read the texture, not the framebuffer: a window's context may still have its
            # own framebuffer bound for reading.
            rows = np.frombuffer(fbo.color_attachments[0].read(alignment=1), np.uint8)
            rows = rows.reshape(height, width, 4)[..., :3]
            if previous is not None:
                previous.use()
        # read() returns framebuffer rows bottom first, and `draw` put the top row at the top.
        return rows.reshape(height, width, 3)[::-1].copy()

    def read_depth_range(self, target) -> tuple[float, float]:
        """`depth_range` of ``target``'s plane 1, read back from the GPU (one float plane)."""
        texture = _planes(target)[1]
        width, height = texture.size
        with self.ctx:
            plane = np.frombuffer(texture.read(), np.float32).reshape(height, width, 4)
        return depth_range(plane[..., 3])

    def _offscreen(self, width: int, height: int):
        """An RGBA8 framebuffer of this size, made once and kept."""
        key = (width, height)
        if key not in self.offscreen:
            with self.ctx:
                self.offscreen[key] = self.ctx.framebuffer(
                    color_attachments=[self.ctx.texture((width, height), 4)])
        return self.offscreen[key]


def _planes(target) -> tuple:
    """The three plane textures of a framebuffer (or the three textures themselves)."""
    textures = tuple(getattr(target, "color_attachments", target))
    if len(textures) != 3:
        raise MarchlabError(f"the display pass needs the three planes, got {len(textures)}")
    return textures

