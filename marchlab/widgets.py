"""A scene you can turn with the mouse in a notebook: ``marchlab.widgets.View``.

    from marchlab.widgets import View
    View("classroom", controls=["render.epsilon", "materials.red.shininess"])

The picture is the gpu backend's frame of the view, shown by jupyter-rfb (a remote frame
buffer: the kernel renders, the browser shows the image and sends back the mouse and keys,
JPEG while moving and PNG at rest). Left drag orbits, right drag pans, the wheel zooms and
W A S D Q E fly, with the mapping of the ``marchlab view`` window (`marchlab.camera_control`,
through the same `marchlab.view.Viewer`). Beside the picture: a slider or picker for each
field named in ``controls``, the overlay (colour, steps heat map, depth, normals, object
ids), the shading mode, the backend that draws it, the time the last frame took, and "Check
against the reference".

Saved or shown without a kernel (nbconvert, the docs site, GitHub), a View shows a PNG of its
first frame instead of the widget's text.

Needs the ``[lessons]`` extra (ipywidgets, jupyter-rfb) and the gpu backend.
"""

from __future__ import annotations

import base64
import dataclasses
import io
import math
import time
import typing

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.fields import Range, color_range, field_types, unit_interval
from scene_model import editing

from .light_marks import draw_marks
from .view import OVERLAYS, SETTLE_SECONDS, Viewer, verdict

WHEEL_NOTCH = 100.0        # a browser's deltaY for one notch of a mouse wheel
KEY_SECONDS = 0.1          # how long one press of a flying key flies
BUTTONS = {1: "left", 2: "right", 3: "middle"}


def _remote_frame_buffer():
    try:
        from jupyter_rfb import RemoteFrameBuffer
    except ImportError:
        raise MarchlabError("the notebook view needs jupyter-rfb: pip install "
                            "'marchlab[lessons]' (make lessons installs it)") from None
    return RemoteFrameBuffer


class _Canvas:
    """The picture and the mouse: made a jupyter-rfb `RemoteFrameBuffer` by `canvas`."""

    def __init__(self, viewer: Viewer, markers: bool = True, backend: str = "gpu", **traits):
        super().__init__(**traits)
        self.viewer = viewer
        self.backend = backend
        self.markers = markers            # mark point and spot lights (drag them to move)
        self.frame = None                 # the last gpu Frame drawn
        self.seconds = 0.0                # the last frame's render time
        self.on_draw = []                 # called with the canvas after each frame
        self._pointer = None              # (button, x, y) while a button is down
        self._moved = False

    # --- jupyter-rfb's two methods ------------------------------------------------------

    def get_frame(self) -> np.ndarray:
        """The view, rendered now by the canvas's backend (at reduced resolution while it
        moves) and encoded as `marchlab render` encodes a frame: (H, W, 3) uint8."""
        from gpu_shader.display import overlay_image
        from .render import render
        viewer = self.viewer
        start = time.perf_counter()
        self.frame = render(viewer.drawn_scene(), *viewer.render_size(), backend=self.backend)
        image = overlay_image(self.frame, viewer.overlay, viewer.selected_ids())
        if self.markers:
            image = mark_lights(image, viewer)
        self.seconds = time.perf_counter() - start
        if viewer.moving:
            self._refine_later()
        for callback in self.on_draw:
            callback(self)
        return image

    def handle_event(self, event: dict) -> None:
        """A jupyter-rfb event (pointer, wheel, key or resize), as the window's input."""
        kind, viewer = event.get("type") or event.get("event_type"), self.viewer
        if kind == "resize":
            viewer.size = (max(1, round(event["width"])), max(1, round(event["height"])))
        elif kind == "pointer_down":
            button = BUTTONS.get(event.get("button"), "left")
            self._pointer, self._moved = (button, event["x"], event["y"]), False
            if button == "left":
                viewer.press(event["x"], event["y"], shift="Shift" in event.get("modifiers", ()))
        elif kind == "pointer_move" and self._pointer is not None:
            button, x, y = self._pointer
            dx, dy = event["x"] - x, event["y"] - y
            self._pointer, self._moved = (button, event["x"], event["y"]), True
            if button == "left" and viewer.holding is not None:
                viewer.move_to(event["x"], event["y"])
            else:
                viewer.drag(button, dx, dy)
        elif kind == "pointer_up" and self._pointer is not None:
            if (event["x"], event["y"]) != self._pointer[1:]:
                # jupyter-rfb throttles moves: the last stretch of a quick drag may arrive
                # only as the release's position.
                self.handle_event(dict(event, type="pointer_move"))
            button, held = self._pointer[0], viewer.holding
            viewer.let_go()
            if button == "left" and held is None and not self._moved:
                viewer.pick(self.object_id_at(event["x"], event["y"]))
            self._pointer = None
        elif kind == "wheel":
            viewer.scroll(-event.get("dy", 0.0) / WHEEL_NOTCH)
        elif kind == "key_down" and event.get("key", "").upper() in "WASDQE" \
                and len(event.get("key", "")) == 1:
            viewer.fly({event["key"].upper()}, KEY_SECONDS,
                       fast="Shift" in event.get("modifiers", ()))
        else:
            return
        self.request_draw()

    # --- helpers -----------------------------------------------------------------------

    def object_id_at(self, x: float, y: float) -> int:
        """The object id under view pixel (x, y) in the last frame drawn (-1: nothing)."""
        if self.frame is None:
            return -1
        height, width = self.frame.object_id.shape
        i, j = self.viewer.texel_at(x, y, width, height)
        return int(self.frame.object_id[j, i])

    def _refine_later(self) -> None:
        """Draw again once the motion has settled, at full resolution."""
        call_later(SETTLE_SECONDS * 1.05, self.request_draw)


def call_later(seconds: float, callback):
    """``callback()`` after ``seconds`` on the kernel's event loop; None (and nothing
    scheduled) where there is no loop, as outside a kernel."""
    import asyncio
    try:
        return asyncio.get_event_loop().call_later(seconds, callback)
    except RuntimeError:
        return None


def mark_lights(image: np.ndarray, viewer: Viewer) -> np.ndarray:
    """``image`` with a yellow dot on each point or spot light (`Viewer.light_markers`),
    ringed in black, sized to the picture: where to press to drag the light."""
    scale = image.shape[1] / viewer.size[0]
    marks = [(i, x * scale, y * scale) for i, x, y in viewer.light_markers()]
    return draw_marks(image, marks, max(2.0, 5.0 * scale))


def canvas(viewer: Viewer, **traits):
    """A jupyter-rfb canvas showing ``viewer`` (the class is made when first asked for, so
    that importing this module needs no jupyter-rfb)."""
    global Canvas
    if Canvas is None:
        Canvas = type("Canvas", (_Canvas, _remote_frame_buffer()), {"__doc__": _Canvas.__doc__})
    return Canvas(viewer, **traits)


Canvas = None


# --- the controls ------------------------------------------------------------------------

def field_control(viewer: Viewer, path: str):
    """An ipywidgets control for the scene field at ``path``, which sets it through
    `Viewer.set_field` (validated; a refused value is put back and the reason shown)."""
    import ipywidgets as widgets
    scene = viewer.scene
    value = editing.get_field(scene, path)
    hint, check = _field_rules(scene, path)
    label = path.rsplit(".", 1)[-1]
    style = {"description_width": "initial"}
    if typing.get_origin(hint) is typing.Literal:
        control = widgets.Dropdown(options=list(typing.get_args(hint)), value=value,
                                   description=label, style=style)
    elif isinstance(value, bool):
        control = widgets.Checkbox(value=value, description=label)
    elif check is color_range and isinstance(value, tuple):
        control = widgets.ColorPicker(value=_hex(value), description=label, style=style)
    elif isinstance(value, int):
        low, high = _span(value, check)
        control = widgets.IntSlider(value=value, min=int(low), max=int(high),
                                    description=label, style=style)
    elif isinstance(value, float):
        low, high = _span(value, check)
        if low > 0 and high / low >= 100:           # decades apart: a log slider
            control = widgets.FloatLogSlider(value=value, base=10, min=math.log10(low),
                                             max=math.log10(high), description=label,
                                             style=style, readout_format=".3g")
        else:
            control = widgets.FloatSlider(value=value, min=low, max=high,
                                          step=(high - low) / 200, description=label,
                                          style=style, readout_format=".3g")
    else:
        raise MarchlabError(f"View controls: {path} is a {type(value).__name__}, which has "
                            "no control (numbers, choices, colours and switches have)")

    def changed(change):
        new = change["new"]
        if isinstance(control, widgets.ColorPicker):
            new = _rgb(new)
        if not viewer.set_field(path, new):
            control.value = change["old"]

    control.observe(changed, names="value")
    return control


def _field_rules(scene, path: str):
    """(type hint, check) of the field at ``path`` where it is a field of a record, else
    (None, None)."""
    if "." not in path:
        return None, None
    parent, name = path.rsplit(".", 1)
    record = editing.get_field(scene, parent)
    if not dataclasses.is_dataclass(record):
        return None, None
    fields = {f.name: f for f in dataclasses.fields(record)}
    if name not in fields:
        return None, None
    return field_types(type(record)).get(name), fields[name].metadata.get("check")


def _span(value, check) -> tuple[float, float]:
    """A slider's ends: the field's own range where it is finite, else around ``value``."""
    if check is unit_interval:          # a weight or a share (ka, kd, kr, transparency)
        return 0.0, 1.0
    low, high = (check.lo, check.hi) if isinstance(check, Range) else (-math.inf, math.inf)
    if not math.isfinite(low):
        low = min(0.0, value * 4)
    if not math.isfinite(high):
        high = max(abs(value) * 4, 1.0)
    if isinstance(check, Range) and check.positive and low <= 0:
        low = min(value, high) / 1000 if value > 0 else 1e-6
    return low, high


def _png(image: np.ndarray) -> bytes:
    from PIL import Image
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG")
    return buffer.getvalue()


def _hex(rgb) -> str:
    return "#" + "".join(f"{round(min(max(c, 0.0), 1.0) * 255):02x}" for c in rgb)


def _rgb(text: str) -> tuple[float, float, float]:
    return tuple(int(text[i:i + 2], 16) / 255 for i in (1, 3, 5))


# --- the view --------------------------------------------------------------------------------

class View:
    """A scene in a notebook: the gpu backend's picture, turned with the mouse, beside
    controls for the fields a lesson names.

    Parameters
    ----------
    scene : str, os.PathLike or Scene
        A bundled scene's name, a scene file, or a scene made in Python.
    controls : sequence of str
        Field paths to give a control each (``"render.epsilon"``, ``"lights.0.intensity"``,
        ``"materials.red.color"``), as `marchlab render --set` names them.
    size : (int, int)
        The picture's size in pixels, width by height.
    overlay : str
        What the picture shows first: one of `marchlab.view.OVERLAYS`.
    markers : bool
        Mark point and spot lights with a dot (press on it and drag to move the light).
    backend : str, optional
        The backend that draws the picture; by default the fastest here
        (`marchlab.render.fastest_backend`: the gpu backend where it runs).
    """

    def __init__(self, scene, controls=(), size=(480, 360), overlay: str = "color",
                 markers: bool = True, backend: str | None = None):
        import ipywidgets as widgets
        if overlay not in OVERLAYS:
            raise MarchlabError(f"unknown overlay {overlay!r} (one of: {', '.join(OVERLAYS)})")
        self.viewer = Viewer(scene, size)
        self.viewer.overlay = overlay
        from IPython.utils.capture import capture_output
        from .render import fastest_backend_for
        # jupyter-rfb displays an output area of its own (for errors in its callbacks) when
        # a canvas is made; it goes into this view's layout instead, so that a notebook saved
        # without widgets shows the PNG below and not "RFBOutputContext()".
        with capture_output(display=True):
            self.canvas = canvas(self.viewer, markers=markers,
                                 backend=backend or fastest_backend_for(self.viewer.scene),
                                 css_width=f"{size[0]}px",
                                 css_height=f"{size[1]}px", resizable=False)
        # The shading mode is always offered; a lesson's own controls come first.
        controls = list(controls) + ["render.shading"] * ("render.shading" not in controls)
        self.controls = [field_control(self.viewer, path) for path in controls]
        for control in self.controls:
            control.observe(lambda _: self.canvas.request_draw(), names="value")
        self.overlay = widgets.Dropdown(options=list(OVERLAYS), value=overlay,
                                        description="overlay")
        self.overlay.observe(self._set_overlay, names="value")
        from .render import backend_problem, scene_backends
        self.backend = widgets.Dropdown(
            options=[name for name in scene_backends(self.viewer.scene)
                     if backend_problem(name) is None],
            value=self.canvas.backend, description="backend")
        self.backend.observe(self._set_backend, names="value")
        self.timing = widgets.Label("")
        self.canvas.on_draw.append(self._show_timing)
        self.check_button = widgets.Button(description="Check against the reference")
        self.check_button.on_click(lambda _: self.check())
        self.verdict = widgets.Label("")
        self.check_images = widgets.HBox([])      # reference, gpu, difference after a check
        self.widget = widgets.VBox([widgets.HBox([self.canvas, widgets.VBox(
            [*self.controls, self.overlay, self.backend, self.timing, self.check_button,
             self.verdict])]),
            self.check_images, self.canvas._output_context])
        self._first_png = None

    def _set_overlay(self, change) -> None:
        self.viewer.overlay = change["new"]
        self.canvas.request_draw()

    def _set_backend(self, change) -> None:
        """Draw with another backend: the same view, computed another way."""
        self.canvas.backend = change["new"]
        self.canvas.request_draw()

    def _show_timing(self, canvas) -> None:
        width, height = canvas.frame.width, canvas.frame.height
        self.timing.value = (f"{canvas.seconds * 1e3:.0f} ms a frame at {width}x{height} "
                             f"({canvas.backend})")

    def image(self) -> np.ndarray:
        """The picture as it stands, (H, W, 3) uint8 (a frame drawn now)."""
        return self.canvas.get_frame()

    def check(self):
        """Render the view with the NumPy reference (and OpenCL where it runs) and give the
        equivalence gates' verdict (`Viewer.check_against_reference`); returns it."""
        from .render import render
        viewer = self.viewer
        shown = render(viewer.drawn_scene(), *viewer.rest_size(), backend=self.canvas.backend,
                       path_labels=True)
        viewer.check_against_reference(shown, background=False)
        result = viewer.check
        self.verdict.value = f"{self.canvas.backend}: {verdict(result.failures)}" + (
            "" if result.opencl_failures is None else
            f"; OpenCL: {verdict(result.opencl_failures)}")
        import ipywidgets as widgets
        reference = {"numpy": "NumPy reference", "numpy-raster": "NumPy rasteriser"}
        pictures = [(reference[result.reference_backend], result.reference),
                    (self.canvas.backend, result.gpu),
                    ("difference x32", result.difference)]
        if result.opencl is not None:
            pictures.append(("OpenCL", result.opencl))
        self.check_images.children = [
            widgets.VBox([widgets.Label(name), widgets.Image(value=_png(image), format="png")])
            for name, image in pictures]
        return result

    def _repr_mimebundle_(self, **kwargs):
        """The widget, and a PNG of its first frame for where widgets do not show."""
        bundle = self.widget._repr_mimebundle_(**kwargs)
        data = bundle[0] if isinstance(bundle, tuple) else bundle
        if self._first_png is None:
            self._first_png = base64.b64encode(_png(self.image())).decode("ascii")
        data["image/png"] = self._first_png
        data["text/plain"] = f"marchlab View of {self.viewer.source}"
        return bundle


# --- physics ---------------------------------------------------------------------------------

TICK_SECONDS = 1 / 30      # how often a playing physics view advances and draws


def sparkline(values: np.ndarray, size=(240, 60), color=(40, 90, 200)) -> np.ndarray:
    """``values`` (N,) as a line across an (H, W, 3) uint8 picture of ``size`` (W, H), the
    smallest value at the bottom and the largest at the top: a live plot too cheap to
    matter beside the render (no plotting library per frame)."""
    width, height = size
    image = np.full((height, width, 3), 255, np.uint8)
    values = np.asarray(values, np.float64)
    if len(values) < 2:
        return image
    low, high = values.min(), values.max()
    span = high - low if high > low else 1.0
    columns = np.linspace(0, width - 1, len(values))
    rows = (height - 1) - (values - low) / span * (height - 1)
    x = np.arange(width)
    y = np.interp(x, columns, rows)
    for column, row in zip(x, np.rint(y).astype(int)):
        image[max(row - 1, 0):row + 1, column] = color
    return image


class PhysicsView(View):
    """`View` of a scene with bodies, and its physics playing: play/pause, step, reset,
    kick; restitution, friction and gravity sliders; the energy plotted as it plays. The
    simulation steps with its fixed dt (`marchlab.playback.Playback`), however often the
    notebook draws; a left drag on a ball throws it.

    Parameters are `View`'s; the scene must have ``[[bodies]]``.
    """

    def __init__(self, scene, controls=(), size=(480, 360), **options):
        import ipywidgets as widgets
        super().__init__(scene, controls, size, **options)
        playback = self.viewer.playback
        if playback is None:
            raise MarchlabError(f"{self.viewer.source}: a physics view needs a scene with "
                                "[[bodies]]")
        self.play_button = widgets.Button(description="Play")
        self.step_button = widgets.Button(description="Step")
        self.reset_button = widgets.Button(description="Reset")
        self.kick_button = widgets.Button(description="Kick")
        self.play_button.on_click(lambda _: self.toggle())
        self.step_button.on_click(lambda _: self._then_draw(self.viewer.playback.step))
        self.reset_button.on_click(lambda _: self._then_draw(self.reset))
        self.kick_button.on_click(lambda _: self._then_draw(self.viewer.playback.kick, 1.0))
        settings = playback.settings
        self.restitution = widgets.FloatSlider(value=settings.restitution, min=0.0, max=1.0,
                                               step=0.01, description="restitution")
        self.friction = widgets.FloatSlider(value=settings.friction, min=0.0, max=1.0,
                                            step=0.01, description="friction")
        self.gravity = widgets.FloatSlider(value=settings.gravity[1], min=-20.0, max=0.0,
                                           step=0.1, description="gravity y (m s^-2)")
        self.restitution.observe(lambda c: self._then_draw(
            self.viewer.playback.set_restitution, c["new"]), names="value")
        self.friction.observe(lambda c: self._then_draw(
            self.viewer.playback.set_friction, c["new"]), names="value")
        self.gravity.observe(lambda c: self._then_draw(
            self.viewer.playback.set_gravity,
            (settings.gravity[0], c["new"], settings.gravity[2])), names="value")
        self.clock = widgets.Label("")
        self.energy_plot = widgets.Image(format="png")
        self.widget.children = (*self.widget.children, widgets.HBox(
            [widgets.VBox([widgets.HBox([self.play_button, self.step_button,
                                         self.reset_button, self.kick_button]),
                           self.restitution, self.friction, self.gravity, self.clock]),
             widgets.VBox([widgets.Label("energy (J)"), self.energy_plot])]))
        self._handle = None
        self._show_state()

    def toggle(self) -> None:
        """Play if paused, pause if playing."""
        playback = self.viewer.playback
        if playback.playing:
            playback.pause()
        else:
            playback.play()
            self._schedule()
        self.play_button.description = "Pause" if playback.playing else "Play"

    def reset(self) -> None:
        """Back to the scene as written, sliders too."""
        playback = self.viewer.playback
        playback.reset()
        settings = playback.settings
        self.restitution.value, self.friction.value = settings.restitution, settings.friction
        self.gravity.value = settings.gravity[1]

    def tick(self, seconds: float = TICK_SECONDS) -> None:
        """One beat of the clock: ``seconds`` of wall time pass, the physics takes the fixed
        steps they hold (`Playback.advance`), and the picture is drawn again."""
        self.viewer.advance(seconds)
        self._show_state()
        self.canvas.request_draw()

    def _schedule(self) -> None:
        self._handle = call_later(TICK_SECONDS, self._beat)

    def _beat(self) -> None:
        if self.viewer.playback.playing:
            self.tick(TICK_SECONDS)
            self._schedule()

    def _then_draw(self, action, *args) -> None:
        try:
            action(*args)
        except MarchlabError as err:
            self.verdict.value = str(err)
        self._show_state()
        self.canvas.request_draw()

    def _show_state(self) -> None:
        playback = self.viewer.playback
        self.clock.value = (f"t = {playback.time:.3f} s, {playback.steps} steps of "
                            f"{playback.settings.dt:g} s")
        history = playback.history
        self.energy_plot.value = _png(sparkline(history[:, 1] if len(history) else []))
