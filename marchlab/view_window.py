"""The ``marchlab view`` window: imgui-bundle's runner, the gpu renderer behind the panels.

imgui-bundle's runner (hello_imgui: GLFW and OpenGL 3) owns the window; moderngl attaches to
its context in the start-up callback (`moderngl.create_context()`), the scene is drawn by the
gpu backend's `Renderer` into its three planes and shown by the display pass
(`gpu_shader.display`) as the window's background, and the panels are ImGui windows over it.
The state is a `marchlab.view.Viewer`; this module draws it and forwards input to it.

`ViewDrawer` is the GL half (no ImGui), so it can be checked on a headless context too;
`MeshDrawer` is its twin for a scene of triangle meshes (the raster backend's
`MeshRenderer`, its planes turned into the display pass's by `gpu_shader.raster_display`).
The window picks the one for the viewer's scene each frame (`Window.choose_drawer`).
"""

from __future__ import annotations

import dataclasses
import math
import time
import typing
from pathlib import Path

import numpy as np

from scene_model.errors import MarchlabError, SceneError
from scene_model.fields import Record, color_range, field_types
from scene_model.files import write_atomically
from scene_model.sampling import pixel_max_steps
from scene_model.shapes import Node, children, node_kinds
from scene_model import editing

from .recording import Recorder, Turntable
from .view import MARKER_RADIUS, MOVING_SCALES, OVERLAYS, TARGET_FPS, Viewer, verdict

DIFFERENCE_GAIN = 32


class _ShownPlanes:
    """What the two drawers share: the three display planes in `target` (those of
    `gpu_shader.planes`, drawn at the size in `drawn`) shown by the display pass, read
    back, written to a file, picked from."""

    def show(self, viewer: Viewer, viewport) -> None:
        """Draw the picture into the bound framebuffer's ``viewport`` (x, y, w, h)."""
        if self.target is None:
            return
        scene = viewer.history.scene
        self.display.draw(self.target, viewer.overlay, gamma=scene.render.gamma,
                          max_steps=pixel_max_steps(scene.render.max_steps,
                                                    scene.render.samples),
                          depth_range=self.depth,
                          selected=viewer.selected_ids(), viewport=viewport)

    def image(self, viewer: Viewer) -> np.ndarray:
        """The view at full resolution as an (H, W, 3) uint8 picture (no panels, no
        outline), drawn now if the view shows a reduced one: what `screenshot` writes."""
        refine, viewer.refine = viewer.refine, False
        try:
            self.update(viewer, wait=True)
        finally:
            viewer.refine = refine
        return self.shown_image(viewer, outline=False)

    def screenshot(self, viewer: Viewer, path) -> Path:
        """Write the 3D view alone, at full resolution, to a PNG."""
        from PIL import Image
        import io
        buffer = io.BytesIO()
        Image.fromarray(self.image(viewer)).save(buffer, format="PNG")
        write_atomically(path, buffer.getvalue())
        viewer.status = f"saved {path}"
        return Path(path)

    def _draw_target(self, scene, size, viewer: Viewer, draw) -> None:
        """Make the picture of ``scene`` at ``size`` with ``draw()`` (the planes, or an error
        told in the status line), count and time it, and read the depth range the depth
        overlay needs."""
        start = time.perf_counter()
        try:
            self.target = draw()
        except MarchlabError as err:
            viewer.status = f"cannot draw: {err}"
        self.drawn = (scene, size)
        self.renders += 1
        if viewer.overlay == "depth" and self.target is not None:
            self.depth = self.display.read_depth_range(self.target)
        self.render_seconds = time.perf_counter() - start

    def object_id_at(self, viewer: Viewer, x: float, y: float) -> int:
        """The object id under view pixel (x, y) (-1: a miss), from the drawn picture."""
        if self.target is None:
            return -1
        i, j = viewer.texel_at(x, y, *self.drawn[1])
        with self.ctx:
            data = self.target.read(viewport=(i, j, 1, 1), components=4, attachment=2,
                                    dtype="i4")
        return int(np.frombuffer(data, np.int32)[1])


class ViewDrawer(_ShownPlanes):
    """Draws a `Viewer`'s scene with the gpu backend on ``ctx`` and shows it.

    The view renders only when what it shows changed, on the thread that owns the context.
    """

    def __init__(self, ctx, compiler=None):
        from gpu_shader.display import Display
        from gpu_shader.render import Renderer
        self.ctx = ctx
        self.renderer = Renderer(ctx)
        self.display = Display(ctx)
        self.compiler = compiler          # a `BackgroundCompiler`, or None: compile in-frame
        self.drawn = None                 # (scene, size) of the picture in `target`
        self.target = None
        self.depth = (0.0, 1.0)
        self.renders = 0                  # frames rendered (not just shown)
        self.render_seconds = 0.0         # of the last one, CPU side
        self.compiling = False            # the scene shown is not the edited one yet
        self._compiled_scene = None       # the last scene whose program this context has
        self._generated = (None, None, None)

    def update(self, viewer: Viewer, wait: bool = False) -> bool:
        """Render the view again if what it shows changed; whether a new picture is drawn.

        A camera move or a moved object needs no new program (the renderer's cache has it,
        keyed by the text, which holds no camera and no positions). A structural edit does:
        with a `compiler`, and unless ``wait``, it is compiled on the compiler's thread and
        the view keeps drawing the scene it last compiled, from the new camera, until the
        program is ready (`gpu_shader.background_compile`). Without one, or with ``wait``,
        it is compiled in this frame, which holds the frame for as long as the driver takes.
        """
        scene, size = viewer.drawn_scene(), viewer.render_size()
        if self.drawn is not None and self.drawn == (scene, size):
            self.compiling = False
            return False
        try:
            program = self._generate(scene, size)
        except MarchlabError as err:
            viewer.status = f"cannot draw: {err}"
            self.drawn = (scene, size)
            return False
        self.compiling = not wait and self._compile_elsewhere(program)
        if self.compiling:
            # The old program, from the new camera, at the new size (both are parameters).
            scene = dataclasses.replace(self._compiled_scene, camera=scene.camera)
            if self.drawn == (scene, size):
                return False
            program = self._generate(scene, size)
        self._draw(scene, size, program, viewer)
        if not self.compiling:
            self._compiled_scene = scene
        return True

    def _compile_elsewhere(self, program) -> bool:
        """Whether ``program`` is being compiled by the compiler (so not drawn yet)."""
        if self.compiler is None or self._compiled_scene is None \
                or (program.vertex_source, program.source) in self.renderer.programs:
            return False
        self.compiler.request(program)
        return not self.compiler.ready(program)

    def _generate(self, scene, size):
        """The renderer's program of the view (`gpu_shader.render.Renderer.generate`, in the
        renderer's shader stage; the last one kept: while a program
        compiles elsewhere, each frame asks for the same one again)."""
        if self._generated[:2] != (scene, size):
            self._generated = (scene, size, self.renderer.generate(scene, *size))
        return self._generated[2]

    def _draw(self, scene, size, program, viewer: Viewer) -> None:
        self._draw_target(scene, size, viewer,
                          lambda: self.renderer.draw_planes(program, *size))

    def shown_image(self, viewer: Viewer, outline: bool = True) -> np.ndarray:
        """The picture drawn last (at the resolution it was drawn at), read back and encoded
        as `marchlab render` encodes a frame (`gpu_shader.display.overlay_image`), with the
        selection's outline if ``outline``: a frame of a recording."""
        from gpu_shader.display import overlay_image
        scene, (width, height) = self.drawn
        with self.ctx:
            frame = self.renderer.read_frame(self.target, scene, width, height)
        return overlay_image(frame, viewer.overlay, viewer.selected_ids() if outline else ())

    def frame(self, viewer: Viewer):
        """The gpu backend's `Frame` of the view as it draws at rest (the resolution scale
        applied), with path labels: what the check against the reference compares."""
        return self.renderer.render(viewer.drawn_scene(), *viewer.rest_size(),
                                    path_labels=True)


class MeshDrawer(_ShownPlanes):
    """Draws a `Viewer`'s scene of triangle meshes with the raster backend on ``ctx`` and
    shows it with the same display pass as `ViewDrawer`.

    One `gpu_shader.raster_render.MeshRenderer` holds the meshes on the GPU; it is made
    again only when the scene's meshes or materials change (an edit, or a keyframed
    transform, which moves the world's triangles), not when the camera, a light or a render
    setting does. Each frame its planes become the display pass's three
    (`gpu_shader.raster_display`): the overlays, gamma and the selection's outline work as
    they do for a sphere-traced scene; the steps overlay shows zeros (nothing is marched).
    """

    def __init__(self, ctx, display=None):
        from gpu_shader.display import Display
        from gpu_shader.raster_display import RasterDisplayPlanes
        self.ctx = ctx
        self.display = display or Display(ctx)
        self.planes = RasterDisplayPlanes(ctx)
        self.renderer = None              # the MeshRenderer, made for `_made_for`
        self._made_for = None             # (meshes, materials)
        self.compiler = None              # nothing compiles in the background here
        self.compiling = False
        self.drawn = None                 # (scene, size) of the picture in `target`
        self.target = None                # the display planes' framebuffer
        self.depth = (0.0, 1.0)
        self.renders = 0
        self.render_seconds = 0.0

    def update(self, viewer: Viewer, wait: bool = False) -> bool:
        """Draw the view again if what it shows changed; whether a new picture is drawn.
        (``wait`` is `ViewDrawer.update`'s: a mesh scene never waits for a compiler.)"""
        scene, size = viewer.drawn_scene(), viewer.render_size()
        if self.drawn is not None and self.drawn == (scene, size):
            return False
        self._draw_target(scene, size, viewer, lambda: self.planes.convert(
            self._renderer(scene).draw(scene, *size), *size))
        return True

    def _renderer(self, scene):
        """The MeshRenderer for ``scene``'s meshes and materials (made again if they
        changed); a scene the raster backend refuses raises MarchlabError, saying why."""
        from gpu_shader.raster_render import MeshRenderer
        from reference_cpu.raster_render import check_mesh_scene
        check_mesh_scene(scene, "raster")          # a render setting may have been edited
        made_for = (scene.meshes, scene.materials)
        if self.renderer is None or self._made_for != made_for:
            if self.renderer is not None:
                self.renderer.release()
                self.renderer = None
            self.renderer = MeshRenderer(scene, self.ctx)
            self._made_for = made_for
        return self.renderer

    def shown_image(self, viewer: Viewer, outline: bool = True) -> np.ndarray:
        """The picture drawn last, read back and encoded as `marchlab render --backend
        raster` encodes its frame (`gpu_shader.display.overlay_image`), with the selection's
        outline if ``outline``."""
        from gpu_shader.display import overlay_image
        from gpu_shader.planes import frame_from_planes
        scene = self.drawn[0]
        frame = frame_from_planes(self.planes.read(self.target), scene, "raster", "float32")
        return overlay_image(frame, viewer.overlay, viewer.selected_ids() if outline else ())

    def frame(self, viewer: Viewer):
        """The raster backend's `Frame` of the view as it draws at rest, with path labels
        (`MeshRenderer.frame`): what the check against the reference compares."""
        scene = viewer.drawn_scene()
        return self._renderer(scene).frame(scene, *viewer.rest_size())

    def release(self) -> None:
        if self.renderer is not None:
            self.renderer.release()
            self.renderer = None
        self.planes.release()


class Window:
    """The ImGui half: panels, input, the run loop's callbacks."""

    def __init__(self, viewer: Viewer, frames: int | None = None, screenshot=None,
                 actions=(), panels: bool = True):
        self.viewer = viewer
        self.frames_left = frames
        self.screenshot_path = screenshot
        self.actions = list(actions)
        self.panels = panels
        self.drawer: ViewDrawer | MeshDrawer | None = None
        self.drawers: dict[str, ViewDrawer | MeshDrawer] = {}   # made on the first use
        self.ctx = None
        self.error: BaseException | None = None
        self.frame_count = 0
        self.last_time = None
        self.recorder: Recorder | None = None
        self.turntable: Turntable | None = None
        self.turntable_frames = 72
        self.record_path = "view.mp4"
        self.screenshot_name = "view.png"
        self.save_as_name = "edited.toml"
        self.open_name = ""
        self.add_kind = "sphere"
        self.textures = {}
        self._press = (math.nan, math.nan)   # where the left button went down on the view
        self.requests = []           # callables to run on the GL thread (`on_gl_thread`)
        self._drew = True            # the last frame rendered the scene
        self._drew_moving = False    # ... at a reduced resolution while moving

    def on_gl_thread(self, function) -> None:
        """Run ``function`` in the next frame, on the thread that holds the GL context: the
        test engine runs its tests on a thread of their own, where GL calls draw nothing."""
        self.requests.append(function)

    # The runner's callbacks -------------------------------------------------------------

    def post_init(self) -> None:
        import moderngl
        try:
            ctx = moderngl.create_context()
            if ctx.version_code < 330:
                raise MarchlabError(f"OpenGL {ctx.version_code / 100:.1f}: the view needs 3.3")
            self.ctx = ctx
            self.choose_drawer()
        except BaseException as err:     # reported after the loop, which must end cleanly
            self._fail(err)

    def choose_drawer(self):
        """The drawer for the viewer's scene, made on first use: `MeshDrawer` for a scene of
        triangle meshes, `ViewDrawer` (the sphere tracer) for one of SDF objects. Called
        each frame, so that opening or reloading another kind of scene switches it."""
        kind = "mesh" if self.viewer.history.scene.meshes else "sdf"
        if kind not in self.drawers:
            if kind == "mesh":
                self.drawers[kind] = MeshDrawer(self.ctx)
            else:
                self.drawers[kind] = ViewDrawer(self.ctx, compiler=background_compiler())
        if self.drawer is not self.drawers[kind]:
            self.drawer = self.drawers[kind]
            self.drawer.drawn = None          # draw the scene now shown, whatever it was
        return self.drawer

    def before_exit(self) -> None:
        for drawer in self.drawers.values():
            if drawer.compiler is not None:
                drawer.compiler.close()

    def background(self) -> None:
        if self.drawer is None:
            return
        from imgui_bundle import imgui
        try:
            now = time.perf_counter()
            if self.last_time is not None:
                seconds = now - self.last_time
                self.viewer.record_frame_time(seconds, drew=self._drew,
                                              drew_moving=self._drew_moving)
                self.viewer.advance(min(seconds, 0.1))
            self.last_time = now
            if self.frame_count % 30 == 0:
                self.viewer.reload_if_changed()
            while self.requests:
                self.requests.pop(0)()
            self.choose_drawer()
            if self.turntable is not None:
                self._turn()
            elif self.actions:
                from .view_script import perform
                perform(self.actions.pop(0), self.viewer, _Gl(self))
            self.choose_drawer()
            io = imgui.get_io()
            width, height = (int(v) for v in io.display_size)
            scale = io.display_framebuffer_scale
            if width > 0 and height > 0:
                self.viewer.size = (width, height)
            self._drew = self.drawer.update(self.viewer)
            self._drew_moving = self._drew and self.drawer.drawn[1] != self.viewer.size \
                and self.viewer.moving
            ctx = self.drawer.ctx
            screen = ctx.detect_framebuffer(0)      # the window's own, not the last bound
            screen.use()
            ctx.clear(0.0, 0.0, 0.0)
            if self.frame_count == 0:
                # The first selection's display program, drawn once now into this
                # framebuffer, in the state every frame draws in, under the picture.
                self.drawer.display.warm(screen, "color", outline=True)
                screen.use()
            self.drawer.show(self.viewer, (0, 0, int(width * scale.x), int(height * scale.y)))
            if self.recorder is not None:
                self.recorder.add(self.drawer.shown_image(self.viewer))
            self.frame_count += 1
            if self.frames_left is not None and self.frame_count >= self.frames_left \
                    and not self.actions and self.turntable is None:
                self._finish()
        except BaseException as err:
            self._fail(err)

    def gui(self) -> None:
        if self.drawer is None:
            return
        try:
            self.choose_drawer()
            self._input()
            if self.panels:
                self._panels()
                self._markers()
        except BaseException as err:
            self._fail(err)

    def start_turntable(self, path, frames: int) -> None:
        """Record one turn of the camera about its pivot to ``path`` (.mp4 or .gif), one
        full-resolution frame per window frame; the camera comes back where it was."""
        self.turntable = Turntable(path, self.viewer.camera, frames)

    def _turn(self) -> None:
        turntable, viewer = self.turntable, self.viewer
        viewer.camera = turntable.next_camera()
        turntable.add(self.drawer.image(viewer))
        if turntable.finished:
            viewer.camera = turntable.start
            self.turntable = None
            try:
                viewer.status = f"saved {turntable.finish()}"
            except (MarchlabError, OSError) as err:
                viewer.status = f"not saved: {err}"

    def _finish(self) -> None:
        from imgui_bundle import hello_imgui
        if self.screenshot_path is not None:
            self.drawer.screenshot(self.viewer, self.screenshot_path)
        hello_imgui.get_runner_params().app_shall_exit = True

    def _fail(self, err: BaseException) -> None:
        from imgui_bundle import hello_imgui
        if self.error is None:
            self.error = err
        hello_imgui.get_runner_params().app_shall_exit = True

    # Input --------------------------------------------------------------------------------

    def _input(self) -> None:
        from imgui_bundle import imgui
        io = imgui.get_io()
        viewer = self.viewer
        if not io.want_capture_mouse:
            x, y = io.mouse_pos.x, io.mouse_pos.y
            if imgui.is_mouse_clicked(imgui.MouseButton_.left):
                self._press = (x, y)
                viewer.press(x, y, shift=io.key_shift)
            for button, name in ((imgui.MouseButton_.left, "left"),
                                 (imgui.MouseButton_.right, "right"),
                                 (imgui.MouseButton_.middle, "middle")):
                if imgui.is_mouse_dragging(button, 1.0):
                    if name == "left" and viewer.holding is not None:
                        viewer.move_to(x, y)
                    else:
                        viewer.drag(name, io.mouse_delta.x, io.mouse_delta.y)
            if imgui.is_mouse_released(imgui.MouseButton_.left):
                held = viewer.holding
                viewer.let_go()
                if held is None and math.dist(self._press, (x, y)) < 2:   # a click
                    self._click(x, y)
            if io.mouse_wheel:
                viewer.scroll(io.mouse_wheel)
        held = set()
        if not io.want_capture_keyboard:
            for key in "WASDQE":
                if imgui.is_key_down(getattr(imgui.Key, key.lower())):
                    held.add(key)
            if held and io.key_shift:
                held.add("SHIFT")
            if io.key_ctrl and imgui.is_key_pressed(imgui.Key.z):
                viewer.redo() if io.key_shift else viewer.undo()
            if io.key_ctrl and imgui.is_key_pressed(imgui.Key.s):
                self._save()
            if imgui.is_key_pressed(imgui.Key.space):
                viewer.toggle_play()
            if imgui.is_key_pressed(imgui.Key.delete):
                viewer.delete_selected()
            if imgui.is_key_pressed(imgui.Key.tab):
                # The panels away (and back): the whole window for the scene, in front of a
                # class; and on a software rasteriser, a faster frame (docs/viewer.md).
                self.panels = not self.panels
        viewer.hold_keys(held)

    def _click(self, x, y) -> None:
        viewer = self.viewer
        if getattr(self, "probe_mode", False) and not viewer.history.scene.meshes:
            try:
                viewer.probe_pixel(int(x), int(y))
            except MarchlabError as err:
                viewer.status = f"probe: {err}"
            return
        viewer.pick(self.drawer.object_id_at(viewer, x, y))

    def _save(self, path=None) -> None:
        try:
            self.viewer.save(path)
        except (MarchlabError, OSError) as err:
            self.viewer.status = f"not saved: {err}"

    # Panels --------------------------------------------------------------------------------

    def _panels(self) -> None:
        self._menu()
        right = self.viewer.size[0] - 320
        self._panel("Scene", self._scene_panel, (10, 30), (330, 460))
        self._panel("Render", self._render_panel, (right, 30), (310, 420))
        if self.viewer.playback is not None:
            self._panel("Physics", self._physics_panel, (right, 460), (310, 260))
        elif self.viewer.animated:
            self._panel("Animation", self._animation_panel, (right, 460), (310, 110))
        self._panel("Performance", self._performance_panel, (10, 500), (330, 170))
        if self.viewer.probe is not None:
            self._panel("Probe", self._probe_panel)
        if self.viewer.check is not None or self.viewer.check_progress is not None:
            self._panel("Check against the reference", self._check_panel)

    def _panel(self, title: str, draw, position=None, size=None) -> None:
        """One ImGui window, placed at ``position`` with ``size`` when first shown, and
        kept inside the view: a panel pushed past its edge by a smaller window (or by the
        person) comes back, shrunk to fit if it must."""
        from imgui_bundle import imgui
        if position is not None:
            imgui.set_next_window_pos(position, imgui.Cond_.first_use_ever)
            imgui.set_next_window_size(size, imgui.Cond_.first_use_ever)
        if imgui.begin(title)[0]:
            draw()
        (x, y), (w, h) = imgui.get_window_pos(), imgui.get_window_size()
        fitted = panel_inside((x, y, w, h), self.viewer.size)
        if fitted != (x, y, w, h):
            imgui.set_window_pos(fitted[:2])
            imgui.set_window_size(fitted[2:])
        imgui.end()

    def _menu(self) -> None:
        from imgui_bundle import imgui
        viewer = self.viewer
        if not imgui.begin_main_menu_bar():
            return
        if imgui.begin_menu("File"):
            if imgui.menu_item("Save", "Ctrl+S", False)[0]:
                self._save()
            _, self.save_as_name = imgui.input_text("##save as", self.save_as_name)
            imgui.same_line()
            if imgui.button("Save as"):
                self._save(self.save_as_name)
            _, self.open_name = imgui.input_text("##open", self.open_name)
            imgui.same_line()
            if imgui.button("Open"):
                try:
                    viewer.open(self.open_name)
                except MarchlabError as err:
                    viewer.status = f"not opened: {err}"
            _, self.screenshot_name = imgui.input_text("##screenshot", self.screenshot_name)
            imgui.same_line()
            if imgui.button("Screenshot"):
                try:
                    self.drawer.screenshot(viewer, self.screenshot_name)
                except (MarchlabError, OSError) as err:
                    viewer.status = f"no screenshot: {err}"
            _, self.record_path = imgui.input_text("##record", self.record_path)
            imgui.same_line()
            if self.recorder is None:
                if imgui.button("Record"):
                    try:
                        self.recorder = Recorder(self.record_path)
                    except (MarchlabError, ImportError) as err:
                        viewer.status = f"cannot record: {err}"
            elif imgui.button(f"Stop ({len(self.recorder.frames)} frames)"):
                try:
                    viewer.status = f"saved {self.recorder.finish()}"
                except (MarchlabError, OSError) as err:
                    viewer.status = f"not saved: {err}"
                self.recorder = None
            if self.turntable is None:
                if imgui.button("Turntable"):
                    try:
                        self.start_turntable(self.record_path, self.turntable_frames)
                    except MarchlabError as err:
                        viewer.status = f"cannot record: {err}"
                imgui.same_line()
                imgui.set_next_item_width(90)
                _, self.turntable_frames = imgui.input_int("frames##turntable",
                                                           self.turntable_frames)
                self.turntable_frames = min(max(self.turntable_frames, 2), 3600)
            else:
                done = len(self.turntable.recorder.frames) / len(self.turntable.cameras)
                imgui.progress_bar(done, (200, 0), "turntable")
            imgui.end_menu()
        if imgui.begin_menu("Edit"):
            if imgui.menu_item("Undo", "Ctrl+Z", False, viewer.history.can_undo)[0]:
                viewer.undo()
            if imgui.menu_item("Redo", "Ctrl+Shift+Z", False, viewer.history.can_redo)[0]:
                viewer.redo()
            imgui.end_menu()
        if imgui.begin_menu("View"):
            if imgui.menu_item("Hide the panels", "Tab", False)[0]:
                self.panels = False
            imgui.end_menu()
        mark = " (modified)" if viewer.modified else ""
        imgui.text_disabled(f"  {viewer.source}{mark}   {viewer.status}")
        imgui.end_main_menu_bar()

    def _scene_panel(self) -> None:
        from imgui_bundle import imgui
        viewer = self.viewer
        scene = viewer.history.scene
        self._object_tools()
        if imgui.begin_tab_bar("scene tabs"):
            if scene.meshes and imgui.begin_tab_item("Meshes")[0]:
                self._meshes_tab(scene)
                imgui.end_tab_item()
            if not scene.meshes and imgui.begin_tab_item("Objects")[0]:
                for i, node in enumerate(scene.objects):
                    self._tree(node, (i,))
                if viewer.selection is not None:
                    imgui.separator()
                    self._node_editor(viewer.selection)
                imgui.end_tab_item()
            self._shared_tabs(scene)
            imgui.end_tab_bar()

    def _object_tools(self) -> None:
        """Add, duplicate and delete SDF objects, or in a scene of triangle meshes top-level
        mesh nodes (they sit above the tabs, where the test engine finds them by label)."""
        from imgui_bundle import imgui
        viewer = self.viewer
        kinds = (editing.addable_mesh_kinds() if viewer.history.scene.meshes
                 else list(node_kinds()))
        if self.add_kind not in kinds:          # the other kind of scene was loaded
            self.add_kind = "cube" if "cube" in kinds else kinds[0]
        imgui.set_next_item_width(110)
        changed, index = imgui.combo("new", kinds.index(self.add_kind), kinds)
        self.add_kind = kinds[index]
        imgui.same_line()
        if imgui.button("Add"):
            self._guarded(viewer.add_object, self.add_kind)
        imgui.same_line()
        if imgui.button("Duplicate") and viewer.selection:
            self._guarded(viewer.duplicate_selected)
        imgui.same_line()
        if imgui.button("Delete") and viewer.selection:
            self._guarded(viewer.delete_selected)

    def _meshes_tab(self, scene) -> None:
        """The top-level mesh nodes (click to select; a click in the view selects too) and
        the selected one's fields: position, rotation, scale, material, its own numbers."""
        from imgui_bundle import imgui
        viewer = self.viewer
        imgui.text_disabled("add, duplicate and delete meshes with the tools above")
        for i, node in enumerate(scene.meshes):
            label = node.kind + (f" ({node.material})" if getattr(node, "material", None)
                                 else "")
            if imgui.selectable(f"{label}##mesh{i}", viewer.selection == ("mesh", i))[0]:
                viewer.select(("mesh", i))
        if viewer.selection is not None and viewer.selection[0] == "mesh" \
                and viewer.selection[1] < len(scene.meshes):
            imgui.separator()
            i = viewer.selection[1]
            self._record(scene.meshes[i], f"meshes[{i}]")

    def _shared_tabs(self, scene) -> None:
        """The tabs every scene has: materials, lights, camera."""
        from imgui_bundle import imgui
        viewer = self.viewer
        if imgui.begin_tab_item("Materials")[0]:
            if imgui.button("Add material"):
                new, name = editing.add_material(scene)
                viewer.edit(new, f"add material {name}")
            for name, material in scene.materials.items():
                if imgui.tree_node(f"{name}##material"):
                    self._record(material, f"materials.{name}")
                    imgui.tree_pop()
            imgui.end_tab_item()
        if imgui.begin_tab_item("Lights")[0]:
            for kind in ("point", "directional", "spot"):
                if imgui.button(f"Add {kind}"):
                    new, _ = editing.add_light(scene, kind)
                    viewer.edit(new, f"add {kind} light")
                imgui.same_line()
            imgui.new_line()
            for i, light in enumerate(scene.lights):
                opened = imgui.tree_node(f"{i}: {light.kind}##light{i}")
                imgui.same_line()
                if imgui.small_button(f"delete##light{i}"):
                    viewer.edit(editing.delete_light(scene, i), f"delete light {i}")
                    if opened:
                        imgui.tree_pop()
                    break
                if opened:
                    self._record(light, f"lights.{i}")
                    imgui.tree_pop()
            imgui.end_tab_item()
        if imgui.begin_tab_item("Camera")[0]:
            self._record(viewer.camera, "camera")
            if imgui.button("Reset camera"):
                viewer.reset_camera()
            imgui.end_tab_item()

    def _animation_panel(self) -> None:
        """Play, pause and rewind the scene's keyframes (the scene as written until played,
        as `marchlab render` draws it), and the time as a slider."""
        from imgui_bundle import imgui
        viewer = self.viewer
        if imgui.button("Pause##animation" if viewer.animating else "Play##animation"):
            viewer.play_animation(not viewer.animating)
        imgui.same_line()
        if imgui.button("Rewind##animation"):
            viewer.rewind_animation()
        length = max(viewer.animation_length(), 1e-3)
        now = viewer.animation_time
        shown = 0.0 if now is None else now % length
        changed, seconds = imgui.slider_float("time (s)##animation", shown, 0.0, length)
        if changed:
            viewer.set_animation_time(seconds)
        imgui.text_disabled("as written" if now is None else f"t = {now:.2f} s")

    def _guarded(self, function, *args) -> None:
        try:
            function(*args)
        except (SceneError, MarchlabError) as err:
            self.viewer.status = f"not done: {err}"

    def _tree(self, node: Node, path: tuple) -> None:
        from imgui_bundle import imgui
        kids = children(node)
        flags = imgui.TreeNodeFlags_.open_on_arrow | imgui.TreeNodeFlags_.default_open
        if not kids:
            flags |= imgui.TreeNodeFlags_.leaf
        if self.viewer.selection == path:
            flags |= imgui.TreeNodeFlags_.selected
        label = node.kind + (f" ({node.material})" if hasattr(node, "material") else "")
        opened = imgui.tree_node_ex(f"{label}##{path}", flags)
        if imgui.is_item_clicked():
            self.viewer.select(path)
        if imgui.begin_drag_drop_source():
            imgui.set_drag_drop_payload_py_id("node", hash(path) & 0x7FFFFFFF)
            self._dragged = path
            imgui.text(label)
            imgui.end_drag_drop_source()
        if imgui.begin_drag_drop_target():
            if imgui.accept_drag_drop_payload_py_id("node") is not None \
                    and getattr(self, "_dragged", None) is not None:
                self.viewer.reparent(self._dragged, path)
                self._dragged = None
            imgui.end_drag_drop_target()
        if opened:
            for j, child in enumerate(kids):
                self._tree(child, path + (j,))
            imgui.tree_pop()

    def _node_editor(self, path) -> None:
        from imgui_bundle import imgui
        viewer = self.viewer
        node = editing.node_at(viewer.history.scene, path)
        imgui.text(f"{node.kind} at {list(path)}")
        if len(path) > 1 and imgui.button("Move to the top level"):
            viewer.reparent_selected(None)
            return
        imgui.text_disabled("drag a node onto an operator to move it there")
        for name, value in _editable(node):
            new = self._field(name, value, type(node), f"node{path}",
                              materials=list(viewer.history.scene.materials))
            if new is not _UNCHANGED:
                try:
                    replaced = editing.replace_node(viewer.history.scene, path,
                                                    dataclasses.replace(node, **{name: new}))
                except (SceneError, MarchlabError) as err:
                    viewer.status = f"not changed: {err}"
                else:
                    viewer.edit(replaced, f"edit {node.kind}.{name}", coalesce=(path, name))

    def _record(self, record: Record, prefix: str) -> None:
        """An editor for every field of ``record``; a change goes through `Viewer.set_field`
        (validated: a refused value leaves the scene as it is and says why)."""
        from imgui_bundle import imgui
        for name, value in _editable(record):
            if isinstance(value, Record):
                if imgui.tree_node(f"{name}##{prefix}"):
                    self._record(value, f"{prefix}.{name}")
                    imgui.tree_pop()
                continue
            new = self._field(name, value, type(record), prefix,
                              materials=list(self.viewer.history.scene.materials))
            if new is not _UNCHANGED:
                self.viewer.set_field(f"{prefix}.{name}", new)

    def _field(self, name, value, owner, prefix, materials=()):
        from imgui_bundle import imgui
        label = f"{name}##{prefix}"
        hint = field_types(owner).get(name)
        choices = _literal_choices(hint)
        field = {f.name: f for f in dataclasses.fields(owner)}.get(name)
        check = field.metadata.get("check") if field is not None else None
        if choices:
            changed, index = imgui.combo(label, choices.index(value), choices)
            return choices[index] if changed else _UNCHANGED
        if name == "material" and isinstance(value, str):
            names = list(materials)
            changed, index = imgui.combo(label, names.index(value) if value in names else 0,
                                         names)
            return names[index] if changed else _UNCHANGED
        if isinstance(value, bool):
            changed, new = imgui.checkbox(label, value)
        elif isinstance(value, int):
            changed, new = imgui.drag_int(label, value, max(1.0, abs(value) * 0.01))
        elif isinstance(value, float):
            speed = max(abs(value) * 0.01, 1e-4)
            changed, new = imgui.drag_float(label, value, speed, format="%.6g")
            new = float32_value(new)
        elif isinstance(value, tuple) and len(value) == 3 and all(
                isinstance(v, float) for v in value):
            if check is color_range:
                changed, new = imgui.color_edit3(label, list(value))
            else:
                speed = max(max(abs(v) for v in value) * 0.01, 1e-3)
                changed, new = imgui.drag_float3(label, list(value), speed, format="%.4g")
            # Components not touched keep their exact value; a touched one is float32's.
            new = tuple(old if np.float32(old) == np.float32(v) else float32_value(v)
                        for old, v in zip(value, new))
        elif isinstance(value, str):
            changed, new = imgui.input_text(label, value)
        else:
            return _UNCHANGED
        return new if changed else _UNCHANGED

    def _render_panel(self) -> None:
        from imgui_bundle import imgui
        viewer = self.viewer
        changed, index = imgui.combo("overlay", OVERLAYS.index(viewer.overlay), list(OVERLAYS))
        if changed:
            viewer.overlay = OVERLAYS[index]
            self.drawer.drawn = None      # the depth overlay reads its range when drawn
        if viewer.history.scene.meshes:
            imgui.text_disabled("meshes are rasterised: no march to probe, no steps")
        else:
            _, self.probe_mode = imgui.checkbox("probe a pixel on click",
                                                getattr(self, "probe_mode", False))
        if imgui.button("Check against the reference") and viewer.check_progress is None:
            viewer.check_against_reference(self.drawer.frame(viewer))
        imgui.separator()
        self._record(viewer.history.scene.render, "render")
        if viewer.history.scene.physics is not None and imgui.tree_node("physics settings"):
            self._record(viewer.history.scene.physics, "physics")
            imgui.tree_pop()

    def _physics_panel(self) -> None:
        from imgui_bundle import imgui, implot
        playback = self.viewer.playback
        if imgui.button("Pause" if playback.playing else "Play"):
            playback.pause() if playback.playing else playback.play()
        imgui.same_line()
        if imgui.button("Step"):
            playback.step()
        imgui.same_line()
        if imgui.button("Reset"):
            playback.reset()
        imgui.same_line()
        if imgui.button("Kick"):
            playback.kick(1.0)           # the session's generator: each kick differs
        imgui.text(f"t = {playback.time:.3f} s, {playback.steps} steps")
        changed, scale = imgui.slider_float("time scale", playback.time_scale, 0.1, 4.0)
        if changed:
            playback.time_scale = scale
        settings = playback.settings
        changed, gravity = imgui.drag_float3("gravity (m s^-2)", list(settings.gravity), 0.05)
        if changed:
            self._guarded(playback.set_gravity, tuple(
                old if np.float32(old) == np.float32(new) else float32_value(new)
                for old, new in zip(settings.gravity, gravity)))
        for name, setter in (("restitution", playback.set_restitution),
                             ("friction", playback.set_friction)):
            changed, value = imgui.slider_float(name, getattr(settings, name), 0.0, 1.0)
            if changed:
                self._guarded(setter, float32_value(value))
        history = np.asarray(playback.history, np.float64)
        if len(history) > 1 and implot.begin_plot("energy and momentum", (-1, 120)):
            implot.plot_line("energy (J)", history[:, 0].copy(), history[:, 1].copy())
            implot.plot_line("|momentum| (kg m/s)", history[:, 0].copy(), history[:, 2].copy())
            implot.end_plot()

    def _performance_panel(self) -> None:
        from imgui_bundle import imgui, implot
        viewer = self.viewer
        size = viewer.render_size()
        imgui.text(f"{viewer.fps():5.1f} fps, drawing {size[0]}x{size[1]}"
                   f"{' (moving)' if viewer.moving else ''}, "
                   f"{self.drawer.renders} renders")
        changed, scale = imgui.slider_float("resolution", viewer.resolution_scale, 0.1, 1.0)
        if changed:
            viewer.resolution_scale = float32_value(scale)
        _, viewer.refine = imgui.checkbox("reduced resolution while moving", viewer.refine)
        if viewer.refine:
            _, viewer.adapt = imgui.checkbox(f"adapt it to {TARGET_FPS:.0f} fps", viewer.adapt)
            imgui.same_line()
            changed, scale = imgui.slider_float("moving scale", viewer.moving_scale,
                                                MOVING_SCALES[0], MOVING_SCALES[-1])
            if changed:                     # (the widget's float32, only when it is moved)
                viewer.moving_scale = float32_value(scale)
        if self.drawer.compiling:
            imgui.text_colored((1.0, 0.8, 0.3, 1.0), "compiling the edited scene's shader; "
                               "showing the last one until it is ready")
        times = np.asarray(viewer.frame_times, np.float64) * 1e3
        if len(times) > 1 and implot.begin_plot("frame time (ms)", (-1, 90)):
            implot.plot_line("ms", times)
            implot.end_plot()

    def _probe_panel(self) -> None:
        from imgui_bundle import imgui, implot
        probe = self.viewer.probe
        imgui.text(f"pixel {self.viewer.probe_at}: {probe.steps} steps, depth {probe.depth:.5g}")
        t = np.asarray(probe.t, np.float64)
        distance = np.asarray(probe.distance, np.float64)
        if len(t) and implot.begin_plot("march", (-1, 200)):
            steps = np.arange(len(t), dtype=np.float64)
            implot.plot_line("t", steps, t)
            implot.plot_line("distance", steps, distance)
            implot.end_plot()

    def _check_panel(self) -> None:
        from imgui_bundle import imgui
        viewer = self.viewer
        if viewer.check_progress is not None:
            done, total = viewer.check_progress
            imgui.progress_bar(done / max(total, 1), (-1, 0), viewer.check_stage)
            return
        check = viewer.check
        drawn_by = "raster" if check.reference_backend == "numpy-raster" else "gpu"
        imgui.text_wrapped(f"{drawn_by} against {check.reference_backend}: "
                           f"{verdict(check.failures)} ({check.seconds:.1f} s)")
        if check.opencl_failures is not None:
            imgui.text_wrapped(f"OpenCL: {verdict(check.opencl_failures)}")
        size = (check.reference.shape[1] / 2, check.reference.shape[0] / 2)
        names = ("reference", "gpu", "difference") + (("opencl",) if check.opencl is not None
                                                       else ())
        for name in names:
            texture = self._texture(name, getattr(check, name))
            imgui.begin_group()
            imgui.text(name if name != "difference" else f"difference x{DIFFERENCE_GAIN}")
            imgui.image(imgui.ImTextureRef(texture.glo), size)
            imgui.end_group()
            imgui.same_line()
        imgui.new_line()
        if imgui.tree_node("figures"):
            for name, value in check.rows:
                imgui.text(f"{name:24s} {value}")
            imgui.tree_pop()

    def _texture(self, name, image):
        key = (name, id(image))
        if self.textures.get(name, (None,))[0] != key:
            ctx = self.drawer.ctx
            texture = ctx.texture((image.shape[1], image.shape[0]), 3,
                                  np.ascontiguousarray(image).tobytes())
            self.textures[name] = (key, texture)
        return self.textures[name][1]

    def _markers(self) -> None:
        """Each light as a small marker: a point or spot light where it is (drag the marker
        to move it: `Viewer.press`), a directional one at the edge of the view, toward where
        it shines from."""
        from imgui_bundle import imgui
        from scene_model.camera import project
        viewer = self.viewer
        draw = imgui.get_background_draw_list()
        width, height = viewer.size
        lights = viewer.history.scene.lights
        colour = imgui.get_color_u32((1.0, 0.9, 0.2, 1.0))
        held = imgui.get_color_u32((1.0, 1.0, 1.0, 1.0))
        for i, x, y in viewer.light_markers():
            draw.add_circle_filled((x, y), MARKER_RADIUS - 2, colour)
            draw.add_circle((x, y), MARKER_RADIUS, held if viewer.holding == "light" else colour)
            draw.add_text((x + MARKER_RADIUS + 2, y - 8), colour, f"{lights[i].kind} {i}")
        for i, light in enumerate(lights):
            direction = getattr(light, "direction", None)
            if getattr(light, "position", None) is not None or direction is None:
                continue
            far = np.asarray(viewer.camera.look_at) - 1e3 * np.asarray(direction, np.float64)
            x, y, _ = project(viewer.camera, [far], width, height)[0]
            if not math.isfinite(x):
                continue
            x, y = min(max(x, 8), width - 8), min(max(y, 28), height - 8)
            draw.add_triangle_filled((x, y - 6), (x - 6, y + 5), (x + 6, y + 5), colour)
            draw.add_text((x + 8, y - 8), colour, f"{light.kind} {i}")


class _Gl:
    """What a script action asks of the GPU, answered by a window's drawer."""

    def __init__(self, window: Window):
        self.window = window

    def object_id_at(self, x, y) -> int:
        self.window.choose_drawer()
        self.window.drawer.update(self.window.viewer, wait=True)   # pick what the scene has
        return self.window.drawer.object_id_at(self.window.viewer, x, y)

    def screenshot(self, path) -> None:
        self.window.choose_drawer().screenshot(self.window.viewer, path)

    def turntable(self, path, frames: int) -> None:
        self.window.start_turntable(path, frames)


_UNCHANGED = object()


MENU_BAR = 20        # pixels at the top of the window that the menu bar takes


def panel_inside(rectangle, view_size) -> tuple[float, float, float, float]:
    """``rectangle`` (x, y, width, height) of a panel moved, and shrunk where it must be,
    so that it lies inside a view of ``view_size`` (width, height) below the menu bar."""
    x, y, width, height = rectangle
    view_width, view_height = view_size
    width = min(width, view_width)
    height = min(height, view_height - MENU_BAR)
    x = min(max(x, 0), view_width - width)
    y = min(max(y, MENU_BAR), view_height - height)
    return (x, y, width, height)


def float32_value(value) -> float:
    """A value an ImGui float widget returned (a float32) as the shortest decimal that is
    the same float32: a typed 0.004 is stored as 0.004, not 0.004000000189989805."""
    return float(str(np.float32(value)))


def _editable(record) -> list[tuple[str, object]]:
    """(name, value) of the fields a panel edits: all but child nodes and node tuples."""
    out = []
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if isinstance(value, Node) or (isinstance(value, tuple) and value
                                       and isinstance(value[0], Node)):
            continue
        if f.name == "kind":
            continue
        out.append((f.name, value))
    return out


def _literal_choices(hint) -> list | None:
    if typing.get_origin(hint) is typing.Literal:
        return list(typing.get_args(hint))
    return None


def runner_params(window: Window, size, title: str):
    """hello_imgui's parameters for ``window``: its callbacks, the size, no idling (the view
    animates), no ini file (tests and classes start from the same layout)."""
    from imgui_bundle import hello_imgui
    params = hello_imgui.RunnerParams()
    params.app_window_params.window_title = title
    params.app_window_params.window_geometry.size = tuple(size)
    params.app_window_params.restore_previous_geometry = False
    params.callbacks.post_init = window.post_init
    params.callbacks.custom_background = window.background
    params.callbacks.show_gui = window.gui
    params.callbacks.before_exit = window.before_exit
    # No full-window ImGui window over the view: the mouse on the view is the camera's.
    params.imgui_window_params.default_imgui_window_type = \
        hello_imgui.DefaultImGuiWindowType.no_default_window
    params.fps_idling.enable_idling = False
    params.ini_disable = True
    return params


def run(window: Window, size, title: str = "marchlab view", test=None) -> None:
    """Open the window and run until it is closed (or its frames are drawn, or ``test``,
    an `imgui_bundle.immapp.testing` test function, ends)."""
    from imgui_bundle import immapp
    params = runner_params(window, size, title)
    add_ons = immapp.AddOnsParams(with_implot=True)
    if test is None:
        immapp.run(params, add_ons)
    else:
        from imgui_bundle.immapp import testing
        testing.run(test_function=test, runner_params=params, add_ons_params=add_ons)
    if window.error is not None:
        raise window.error


def background_compiler():
    """A `gpu_shader.background_compile.BackgroundCompiler` whose headless context is
    moderngl's default one, which takes the window's driver path (GLX on X11), so that the
    driver caches programs under the keys the window's context looks up."""
    from gpu_shader.background_compile import BackgroundCompiler
    return BackgroundCompiler(backend=None)


def window_problem() -> str | None:
    """None if a window can open here, else one line saying why not and how to fix it."""
    import importlib.util
    import os
    import sys
    for module, extra in (("imgui_bundle", "view"), ("moderngl", "gpu")):
        if importlib.util.find_spec(module) is None:
            return (f"the view needs {module}: pip install 'marchlab[{extra}]' "
                    "(make demo installs it)")
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        return ("no display to open a window on (DISPLAY is not set): run it on a desktop, "
                "or headless as `xvfb-run -a marchlab view ...` (apt-get install xvfb)")
    return None
