"""The live view: what the ``marchlab view`` window shows and edits, without the window.

`Viewer` holds the scene being edited (with its undo history), the camera, the render
settings a person changes with sliders, the selection, the overlay, the physics playing, the
resolution the view draws at and its frame times. The window (`marchlab.view_window`) draws
it with ImGui and forwards the mouse and keys to it; a ``--script`` replays actions on it
(`marchlab.view_script`); the tests drive it directly. Nothing here imports a GUI or OpenGL:
drawing is `ViewDrawer`'s, which the window makes once it has a context.

Drawing on demand. The view renders only when what it shows changes (the camera, the scene,
a body, the size), so a still view costs nothing; while the camera moves it renders at
`moving_scale` of the resolution, and at full resolution again `SETTLE_SECONDS` after the
motion stops (the teacher's target, docs/viewer.md: 30 frames per second while orbiting,
full resolution within 0.5 s of stopping). The moving scale adapts to the frame rate
(`adapt_moving_scale`): a heavy scene moves at a coarser picture, a light one at a finer.
"""

from __future__ import annotations

import collections
import dataclasses
import math
import os
import threading
import time
from pathlib import Path

import numpy as np

from scene_model.camera import camera_basis, pixel_ray
from scene_model.errors import MarchlabError, SceneError
from scene_model.files import write_atomically
from scene_model.scene import Scene, rendered_scene, scene_at
from scene_model.scenefile import load_scene, scene_path, scene_to_toml
from scene_model.timeline import scene_at_time
from scene_model import editing

from . import camera_control

MOVING_SCALE = 0.35         # of each side, while the camera moves (where it starts)
MOVING_SCALES = (0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5)   # what it adapts between
TARGET_FPS = 30.0           # while moving
MARKER_RADIUS = 8.0         # pixels: a press this close to a light's marker takes hold of it
SETTLE_SECONDS = 0.25       # after the last motion, the view refines to full resolution
OVERLAYS = ("color", "steps", "depth", "normal", "object_id")
FRAME_HISTORY = 240         # frame times kept for the plot
MIN_SCALE, MAX_SCALE = 0.1, 1.0


@dataclasses.dataclass
class CheckResult:
    """The view checked against the reference (`Viewer.check_against_reference`)."""
    reference: np.ndarray        # (H, W, 3) uint8, the NumPy reference's picture
    gpu: np.ndarray              # (H, W, 3) uint8, the gpu backend's
    difference: np.ndarray       # (H, W, 3) uint8, |a - b| amplified
    failures: list[str]          # one line per gate failed; empty: every gate passes
    rows: list[tuple[str, str]]  # the comparison's figures, as `marchlab compare` prints them
    seconds: float
    opencl: np.ndarray | None = None          # (H, W, 3) uint8, the OpenCL backend's, where
    opencl_failures: list[str] | None = None  # it runs, and its gates against the reference
    reference_backend: str = "numpy"          # numpy-raster for a scene of meshes


class Viewer:
    """The state of a live view of one scene.

    Parameters
    ----------
    source : str, os.PathLike or Scene
        A bundled scene's name or a scene file (`scene_model.scenefile.load_scene`), or a
        scene made in Python.
    size : (int, int)
        The view's size in pixels, width by height.
    clock : callable, optional
        Seconds, monotonic (default `time.perf_counter`); tests pass a fake one.
    """

    def __init__(self, source, size=(640, 480), clock=time.perf_counter):
        self.clock = clock
        self.size = tuple(int(s) for s in size)
        self.overlay = "color"
        self.selection: tuple | None = None
        self.resolution_scale = 1.0
        self.moving_scale = MOVING_SCALE
        self.adapt = True            # adapt moving_scale to the frame rate
        self._idle_times = collections.deque(maxlen=60)   # of frames that rendered nothing
        self.refine = True           # draw at reduced resolution while moving
        self.frame_times = collections.deque(maxlen=FRAME_HISTORY)
        self.status = ""
        self.check: CheckResult | None = None
        self.check_progress = None   # (done, total) while a check runs
        self.check_stage = ""        # what it is rendering then
        self.probe = None
        self._last_motion = -math.inf
        self._held_keys: set[str] = set()
        self._holding = None         # what a left drag carries (`press`)
        self._gesture = 0            # one undo step per drag
        self.animation_time: float | None = None   # the keyframes' clock (None: as written)
        self.animating = False       # the clock runs
        self.open(source)

    # --- the scene -------------------------------------------------------------------------

    def open(self, source) -> None:
        """Show another scene file (or bundled scene, or a `Scene` made in Python, which
        has no file until it is saved under a name); its camera is the start."""
        if isinstance(source, Scene):
            scene, self.source, self.path = source, "a scene made in Python", None
        else:
            scene = load_scene(source)
            self.source, self.path = str(source), scene_path(source)
        self._mtime = _mtime(self.path)
        self.history = editing.History(scene)
        self.camera = scene.camera
        self.selection = None
        self.saved_scene = scene
        self._reset_playback()
        self.rewind_animation()
        self.status = f"opened {self.source}"

    @property
    def scene(self) -> Scene:
        """The edited scene, with the view's camera."""
        return dataclasses.replace(self.history.scene, camera=self.camera)

    @property
    def modified(self) -> bool:
        return self.scene != self.saved_scene

    def edit(self, scene: Scene, label: str, coalesce=None) -> None:
        """Make ``scene`` the edited scene, one undo step (``coalesce``: steps with the same
        key in a row, as one slider drag makes, are one step). The view's camera is not
        ``scene``'s: it moves with the mouse and with `set_field` ("camera.fov")."""
        self.history.push(dataclasses.replace(scene, camera=self.history.scene.camera), label,
                          coalesce=coalesce)
        self._sync_playback()

    def set_field(self, path: str, value) -> bool:
        """Set one field (``"render.epsilon"``, ``"materials.red.kd"``, ``"camera.fov"``) as
        a drag or a typed number does; a value the scene refuses leaves it unchanged and says
        why in `status`. Returns whether the scene changed."""
        try:
            scene = editing.set_field(self.scene, path, value)
        except (SceneError, MarchlabError) as err:
            self.status = f"not changed: {err}"
            return False
        if path.startswith("camera."):
            self.camera = scene.camera
            return True
        if scene != self.scene:
            self.edit(scene, f"set {path}", coalesce=path)
        return True

    def undo(self) -> None:
        if self.history.can_undo:
            self.history.undo()
            self._after_history()

    def redo(self) -> None:
        if self.history.can_redo:
            self.history.redo()
            self._after_history()

    def _after_history(self, restart_physics: bool = False) -> None:
        if self.selection is not None and not _exists(self.history.scene, self.selection):
            self.selection = None
        if restart_physics:
            self._reset_playback()
        else:
            self._sync_playback()

    def save(self, path=None) -> Path:
        """Write the scene, with the view's camera, as TOML (to its own file by default; a
        bundled scene must be saved under a new name)."""
        if path is None:
            if self.path is None:
                raise MarchlabError("this scene has no file yet: save it under a name")
            if _is_bundled(self.path):
                raise MarchlabError(f"{self.source} is a bundled scene: save it under a new "
                                    "name (File > Save as)")
            path = self.path
        path = Path(path)
        if path.suffix.lower() != ".toml":
            raise MarchlabError(f"{path}: a scene file must end in .toml")
        scene = self.scene
        write_atomically(path, scene_to_toml(scene).encode("utf-8"))
        self.saved_scene = scene
        if self.path is None or path.resolve() == self.path.resolve() \
                or _is_bundled(self.path):
            self.path, self.source = path, str(path)
        self._mtime = _mtime(self.path)
        self.status = f"saved {path}"
        return path

    def reload_if_changed(self) -> bool:
        """Read the scene file again if it changed on disk since it was read or saved (an
        undoable step; the camera stays where it is). A file that no longer reads leaves the
        scene as it is and says why."""
        mtime = _mtime(self.path)
        if mtime == self._mtime or mtime is None:
            return False
        self._mtime = mtime
        try:
            scene = load_scene(self.path)
        except SceneError as err:
            self.status = f"not reloaded: {err}"
            return False
        self.history.push(scene, "reload from disk")
        self.saved_scene = dataclasses.replace(scene, camera=self.camera)
        self._after_history(restart_physics=True)
        self.status = f"reloaded {self.path.name}"
        return True

    # --- the objects ---------------------------------------------------------------------

    def select(self, path) -> None:
        self.selection = None if path is None else tuple(path)

    def selected_ids(self) -> tuple[int, ...]:
        """Object ids of the selected node's primitives (what the outline surrounds); of a
        selected mesh, ``("mesh", i)``, those of its parts and its children's."""
        if self.selection is None:
            return ()
        if self.selection[0] == "mesh":
            return mesh_ids(self.history.scene, self.selection[1])
        return editing.primitive_ids(self.history.scene, self.selection)

    def pick(self, object_id: int) -> None:
        """Select the object a click hit (its object id; -1: nothing): in a scene of
        triangle meshes the top-level mesh node ``("mesh", i)`` that holds it."""
        scene = self.history.scene
        if scene.meshes:
            index = mesh_holding(scene, object_id)
            self.selection = None if index is None else ("mesh", index)
            return
        path = editing.object_path(scene, object_id) if object_id >= 0 else None
        self.selection = path if isinstance(path, tuple) and path and path[0] != "body" else None

    def add_object(self, kind: str) -> None:
        """Add a new node of ``kind`` into the selected operator, or else at the top level.
        A scene of triangle meshes takes a top-level mesh node of a procedural kind
        (`scene_model.editing.add_mesh`) and refuses an SDF object, saying so."""
        scene = self.history.scene
        if scene.meshes:
            if kind not in editing.addable_mesh_kinds():
                raise MarchlabError(f"cannot add a {kind}: this scene is made of triangle "
                                    "meshes (add one of: "
                                    f"{', '.join(editing.addable_mesh_kinds())}), and SDF "
                                    "objects are drawn by the sphere tracer")
            scene, index = editing.add_mesh(scene, kind)
            self.edit(scene, f"add {kind} mesh")
            self.selection = ("mesh", index)
            return
        node = editing.default_node(kind)
        try:
            scene, path = editing.add_object(self.history.scene, node, self.selection)
        except SceneError:
            scene, path = editing.add_object(self.history.scene, node, None)
        self.edit(scene, f"add {kind}")
        self.selection = path

    def duplicate_selected(self) -> None:
        if self._mesh_selected():
            scene, index = editing.duplicate_mesh(self.history.scene, self.selection[1])
            self.edit(scene, "duplicate mesh")
            self.selection = ("mesh", index)
        elif self.selection is not None:
            scene, path = editing.duplicate(self.history.scene, self.selection)
            self.edit(scene, "duplicate")
            self.selection = path

    def delete_selected(self) -> None:
        """Delete the selected node; a scene's last mesh stays (saying so)."""
        if self._mesh_selected():
            try:
                scene = editing.delete_mesh(self.history.scene, self.selection[1])
            except SceneError as err:
                self.status = f"not deleted: {err}"
                return
            self.edit(scene, "delete mesh")
            self.selection = None
        elif self.selection is not None:
            self.edit(editing.delete(self.history.scene, self.selection), "delete")
            self.selection = None

    def _mesh_selected(self) -> bool:
        """Whether the selection is a top-level mesh node ``("mesh", i)``."""
        return self.selection is not None and self.selection[0] == "mesh"

    def reparent_selected(self, parent) -> None:
        if self.selection is not None:
            self.reparent(self.selection, parent)

    def reparent(self, path, parent) -> None:
        """Move the node at ``path`` into the operator at ``parent`` (None: the top level)
        and select it there; a move the scene refuses changes nothing (not the selection
        either) and says why."""
        try:
            scene, moved = editing.reparent(self.history.scene, tuple(path), parent)
        except SceneError as err:
            self.status = f"not moved: {err}"
            return
        self.edit(scene, "re-parent")
        self.selection = moved

    # --- the camera ------------------------------------------------------------------------

    def drag(self, button: str, dx: float, dy: float) -> None:
        """A mouse drag of (dx, dy) pixels on the view (`marchlab.camera_control`)."""
        if dx or dy:
            self.camera = camera_control.drag(self.camera, button, dx, dy, self.size[1])
            self._moved()

    def scroll(self, clicks: float) -> None:
        if clicks:
            self.camera = camera_control.scroll(self.camera, clicks)
            self._moved()

    def fly(self, keys, seconds: float, fast: bool = False) -> None:
        camera = camera_control.fly_keys(self.camera, keys, seconds, fast)
        if camera != self.camera:
            self.camera = camera
            self._moved()

    def reset_camera(self) -> None:
        self.camera = self.saved_scene.camera
        self._moved()

    def _moved(self) -> None:
        self._last_motion = self.clock()

    @property
    def moving(self) -> bool:
        return self.clock() - self._last_motion < SETTLE_SECONDS

    def rest_size(self) -> tuple[int, int]:
        """The size the view renders at when still: `resolution_scale` of the window."""
        return self._scaled_size(1.0)

    def render_size(self) -> tuple[int, int]:
        """The size the view renders at now: `rest_size`, times `moving_scale` while the
        camera moves."""
        return self._scaled_size(self.moving_scale if self.refine and self.moving else 1.0)

    def _scaled_size(self, factor: float) -> tuple[int, int]:
        scale = min(max(self.resolution_scale, MIN_SCALE), MAX_SCALE) * factor
        return tuple(max(1, round(side * scale)) for side in self.size)

    def texel_at(self, x: float, y: float, width: int, height: int) -> tuple[int, int]:
        """The pixel (column, row) of a ``width`` x ``height`` picture of the view (drawn at
        a reduced size, say) under view pixel (x, y)."""
        return (min(max(int(x * width / self.size[0]), 0), width - 1),
                min(max(int(y * height / self.size[1]), 0), height - 1))

    # --- physics -----------------------------------------------------------------------------

    def _sync_playback(self) -> None:
        """Start the physics again from the edited scene if its bodies or its [physics]
        settings changed: the playback simulates the scene it was made from."""
        scene = self.history.scene
        if (scene.bodies, scene.physics) != self._played:
            self._reset_playback()

    def _reset_playback(self) -> None:
        scene = self.history.scene
        self._played = (scene.bodies, scene.physics)
        if scene.bodies:
            from .playback import Playback
            self.playback = Playback(scene)
        else:
            self.playback = None

    def advance(self, seconds: float) -> None:
        """One frame of ``seconds``: play the physics and the keyframes, fly with the keys
        held."""
        if self.playback is not None:
            self.playback.advance(seconds)
        if self.animating:
            self.animation_time = (self.animation_time or 0.0) + seconds
        if self._held_keys:
            self.fly(self._held_keys - {"SHIFT"}, seconds, fast="SHIFT" in self._held_keys)

    def grab_ball(self, x: float, y: float) -> bool:
        """Take hold of the body under view pixel (x, y), if any: while held it follows
        `drag_ball` in the plane through its centre facing the camera, and is thrown with
        the drag's velocity when released."""
        if self.playback is None:
            return False
        origin, direction = pixel_ray(self.camera, x, y, *self.size)
        index = self.playback.pick(origin, direction)
        if index is None:
            return False
        self.playback.grab(index)
        centre = self.playback.positions()[index]
        self._grab_plane = (centre, camera_basis(self.camera)[0])
        return True

    def drag_ball(self, x: float, y: float) -> None:
        if self.playback is None or getattr(self, "_grab_plane", None) is None:
            return
        point = self._on_plane(x, y, *self._grab_plane)
        if point is not None:
            self.playback.drag_to(point)

    def release_ball(self) -> None:
        if self.playback is not None and getattr(self, "_grab_plane", None) is not None:
            self.playback.release()
        self._grab_plane = None

    def _on_plane(self, x: float, y: float, point, normal):
        """Where the ray through view pixel (x, y) meets the plane through ``point`` with
        ``normal`` (None: parallel to it, or behind the eye)."""
        origin, direction = pixel_ray(self.camera, x, y, *self.size)
        denominator = direction @ normal
        if abs(denominator) < 1e-9:
            return None
        t = ((np.asarray(point) - origin) @ normal) / denominator
        return origin + t * direction if t > 0 else None

    # --- keyframes ----------------------------------------------------------------------------

    @property
    def animated(self) -> bool:
        """Whether the scene has keyframes to play."""
        return bool(self.history.scene.keyframes)

    def play_animation(self, playing: bool = True) -> None:
        """Run (or stop) the keyframes' clock; it starts at 0 s from the scene as written."""
        if playing and self.animation_time is None:
            self.animation_time = 0.0
        self.animating = bool(playing) and self.animated

    def set_animation_time(self, seconds: float) -> None:
        """Show the keyframed scene at ``seconds`` (the clock goes on from there if it runs)."""
        self.animation_time = max(float(seconds), 0.0)

    def rewind_animation(self) -> None:
        """Stop the clock and show the scene as written again (as `marchlab render` draws
        it: keyframes are applied only once the clock has started)."""
        self.animation_time, self.animating = None, False

    def toggle_play(self) -> None:
        """Space: play or pause the physics, or else the keyframes."""
        if self.playback is not None:
            self.playback.pause() if self.playback.playing else self.playback.play()
        elif self.animated:
            self.play_animation(not self.animating)

    def animation_length(self) -> float:
        """The last key time of any keyframed field (s): one loop of the animation."""
        return max((max(keys.times) for keys in self.history.scene.keyframes), default=0.0)

    # --- dragging things in the view -------------------------------------------------------

    def light_markers(self) -> list[tuple[int, float, float]]:
        """(index, x, y): where each light with a position (point, spot) is marked in the
        view, in view pixels (lights behind the eye are left out)."""
        from .light_marks import light_marks
        return light_marks(dataclasses.replace(self.history.scene, camera=self.camera),
                           *self.size)

    def press(self, x: float, y: float, shift: bool = False) -> str | None:
        """The left button went down on view pixel (x, y): take hold of what is there, for
        `move_to` to carry. A light's marker (within `MARKER_RADIUS` pixels) comes first;
        with ``shift``, the selected top-level object; else a body. Returns "light",
        "object", "ball", or None (nothing: the drag orbits)."""
        self.let_go()
        near = [(math.hypot(mx - x, my - y), i) for i, mx, my in self.light_markers()]
        near = [item for item in near if item[0] <= MARKER_RADIUS]
        if near:
            path = f"lights.{min(near)[1]}.position"
        elif shift and self.selection is not None and self.selection[0] == "mesh":
            path = f"meshes[{self.selection[1]}].position"
        elif shift and self.selection is not None and len(self.selection) == 1:
            path = f"objects[{self.selection[0]}].position"
        elif self.grab_ball(x, y):
            self._holding = ("ball",)
            return "ball"
        else:
            return None
        start = np.asarray(editing.get_field(self.history.scene, path) or (0.0, 0.0, 0.0),
                           np.float64)
        normal = camera_basis(self.camera)[0]
        hit = self._on_plane(x, y, start, normal)
        if hit is None:
            return None
        self._gesture += 1
        self._holding = (path, start, hit, normal)
        return "light" if path.startswith("lights") else "object"

    def move_to(self, x: float, y: float) -> None:
        """Carry what `press` took hold of under view pixel (x, y): a light or an object
        moves in the plane through where it was, facing the camera, so the point pressed
        stays under the cursor; the whole drag is one undo step."""
        if self._holding is None:
            return
        if self._holding[0] == "ball":
            self.drag_ball(x, y)
            return
        path, start, hit, normal = self._holding
        now = self._on_plane(x, y, start, normal)
        if now is None:
            return
        position = tuple(float(v) for v in start + (now - hit))
        try:
            scene = editing.set_field(self.history.scene, path, position)
        except (SceneError, MarchlabError) as err:
            self.status = f"not moved: {err}"
            return
        self.edit(scene, f"move {path.rsplit('.', 1)[0]}", coalesce=(path, self._gesture))

    def let_go(self) -> None:
        """The left button went up: a ball is thrown, a light or object stays."""
        if self._holding is not None and self._holding[0] == "ball":
            self.release_ball()
        self._holding = None

    @property
    def holding(self) -> str | None:
        """What a drag carries now: "light", "object", "ball", or None."""
        if self._holding is None:
            return None
        return self._holding[0] if self._holding[0] == "ball" else \
            ("light" if self._holding[0].startswith("lights") else "object")

    def hold_keys(self, keys) -> None:
        self._held_keys = {k.upper() for k in keys}

    # --- what is drawn -----------------------------------------------------------------------

    def drawn_scene(self) -> Scene:
        """The scene as the renderer draws it: the view's camera, the bodies where the
        physics has them, the bodies turned into objects."""
        return rendered_scene(self.scene_now())

    def record_frame_time(self, seconds: float, drew: bool = True,
                          drew_moving: bool = False) -> None:
        """One frame's wall time. ``drew``: it rendered the scene; a frame that did not
        measures the frame's fixed part (panels, display, swap). ``drew_moving``: it rendered
        a reduced picture while moving, so its time says whether `moving_scale` suits this
        scene (`adapt_moving_scale`)."""
        self.frame_times.append(seconds)
        if not drew:
            self._idle_times.append(seconds)
        if drew_moving and self.adapt:
            fixed = min(self._idle_times) if self._idle_times else 0.0
            self.moving_scale = adapt_moving_scale(self.moving_scale, seconds, fixed)

    def fps(self) -> float:
        """Frames per second over the frame times kept (0 before any)."""
        if not self.frame_times:
            return 0.0
        return len(self.frame_times) / max(sum(self.frame_times), 1e-9)

    # --- seeing the algorithm ----------------------------------------------------------------

    def probe_pixel(self, x: int, y: int) -> None:
        """March one pixel of the full-resolution view on the reference (`marchlab.probe`);
        (x, y) in view pixels, row 0 at the top."""
        from .probe import probe
        if self.history.scene.meshes:
            raise MarchlabError("probing a march needs a scene of SDF objects: a scene of "
                                "triangle meshes is rasterised, not marched")
        width, height = self.size
        self.probe = probe(self.scene_now(), int(x), int(y), width, height)
        self.probe_at = (int(x), int(y))

    def scene_now(self) -> Scene:
        """The edited scene with the view's camera, its keyframed fields at the animation's
        time once its clock has started (`scene_model.timeline.scene_at_time`; the view's
        camera stays the person's: a camera orbit or keyed camera field is not applied) and
        the bodies where the physics has them (what the probe and the reference check look
        at)."""
        scene = self.scene
        if scene.keyframes and self.animation_time is not None:
            still = scene_at_time(dataclasses.replace(scene, orbit=None), self.animation_time)
            scene = dataclasses.replace(still, camera=self.camera)
        if self.playback is not None:
            from .simulation import drawn_poses
            world = self.playback.world
            positions, rotations = drawn_poses(scene, self.playback.positions(),
                                               world.orientation)
            scene = scene_at(scene, positions, world.time, rotations)
        return scene

    def check_against_reference(self, gpu_frame, background: bool = True):
        """Render the view with the NumPy reference and compare ``gpu_frame`` (the gpu
        backend's frame of the same view, with path labels) to it under the equivalence
        gates, and the OpenCL backend's frame too where it runs; in a thread when
        ``background``, so the window keeps drawing. Sets `check`."""
        scene = self.scene_now()
        height, width = gpu_frame.height, gpu_frame.width
        self.check = None
        self.check_stage, self.check_progress = "NumPy reference rendering", (0, width * height)

        def work():
            try:
                check()
            except Exception as err:       # the thread's end: say why in the window
                self.status = f"check failed: {type(err).__name__}: {err}"
            finally:
                self.check_progress = None

        def check():
            start = time.perf_counter()
            from .compare import compare_frames, failures, gates_against, reference_around
            from .render import backend_problem, reference_backend, render
            reference_name = reference_backend(scene)

            def progress(stage):
                def report(done, total):
                    self.check_stage, self.check_progress = stage, (done, total)
                return report

            reference = render(scene, width, height, backend=reference_name,
                               path_labels=True, progress=progress("NumPy reference rendering"))
            gates = gates_against("float64", meshes=bool(scene.meshes))

            def against_reference(frame):
                # A hardware rasteriser samples off the pixel centres (marchlab.compare).
                around = reference_around(scene, width, height, reference_name, frame.subpixel)
                comparison = compare_frames(reference, frame, epsilon=scene.render.epsilon,
                                            around=around)
                return comparison, failures(comparison, gates)

            comparison, gpu_failures = against_reference(gpu_frame)
            a, b = reference.image(), gpu_frame.image()
            difference = np.clip(np.abs(a.astype(int) - b.astype(int)) * 32, 0, 255)
            opencl = opencl_failures = None
            if not scene.meshes and backend_problem("opencl") is None:   # the third, here
                frame = render(scene, width, height, backend="opencl", path_labels=True,
                               progress=progress("OpenCL rendering"))
                opencl, opencl_failures = frame.image(), against_reference(frame)[1]
            self.check = CheckResult(a, b, difference.astype(np.uint8), gpu_failures,
                                     comparison.rows(), time.perf_counter() - start,
                                     opencl, opencl_failures, reference_name)

        if not background:
            try:
                check()
            finally:
                self.check_progress = None
            return None
        thread = threading.Thread(target=work, name="marchlab-check", daemon=True)
        thread.start()
        return thread


def verdict(failures) -> str:
    """A check's verdict in a few words: every gate passes, or which fail."""
    return "every gate passes" if not failures else "FAILS: " + "; ".join(failures)


def adapt_moving_scale(scale: float, frame_seconds: float, fixed_seconds: float = 0.0,
                       target_fps: float = TARGET_FPS) -> float:
    """The moving scale for the next frame, after one at ``scale`` that took
    ``frame_seconds`` (dynamic resolution, as game engines do it).

    One step down `MOVING_SCALES` when the frame missed ``target_fps``. One step up when the
    next step would still keep it: a frame is a fixed part (panels, display pass, buffer
    swap), at least ``fixed_seconds``, plus a render that grows with the picture's area, so
    the next step's frame is predicted as ``fixed + (frame - fixed) * (next / scale)**2``.
    With ``fixed_seconds`` a lower bound of the fixed part (0 when unknown) the prediction is
    an upper bound, so a step up is never undone by the next frame: the scale settles instead
    of flickering between two steps.
    """
    budget = 1.0 / target_fps
    steps = MOVING_SCALES
    here = min(range(len(steps)), key=lambda i: abs(steps[i] - scale))
    fixed = min(max(fixed_seconds, 0.0), frame_seconds)
    if frame_seconds > budget:
        here = max(here - 1, 0)
    elif here + 1 < len(steps) and \
            fixed + (frame_seconds - fixed) * (steps[here + 1] / steps[here]) ** 2 <= budget:
        here += 1
    return steps[here]


def _mtime(path: Path | None):
    if path is None:
        return None
    try:
        return os.stat(path).st_mtime_ns
    except OSError:
        return None


def _is_bundled(path: Path) -> bool:
    return path.parent.name == "scenes" and path.parent.parent.name == "scene_model"


def _mesh_count(node) -> int:
    """How many meshes (object ids) a mesh node and its children make (`scene_meshes`)."""
    from scene_model.mesh_world import node_parts
    return len(node_parts(node)) + sum(_mesh_count(child) for child in node.children)


def mesh_ids(scene: Scene, index: int) -> tuple[int, ...]:
    """The object ids of top-level mesh node ``index``: its parts' and its children's, as
    `scene_model.mesh_world.scene_meshes` numbers them (depth first)."""
    first = sum(_mesh_count(node) for node in scene.meshes[:index])
    return tuple(range(first, first + _mesh_count(scene.meshes[index])))


def mesh_holding(scene: Scene, object_id: int) -> int | None:
    """The top-level mesh node that object id ``object_id`` is part of (None: a miss)."""
    first = 0
    for index, node in enumerate(scene.meshes):
        first += _mesh_count(node)
        if 0 <= object_id < first:
            return index
    return None


def _exists(scene: Scene, path) -> bool:
    if path[0] == "mesh":
        return path[1] < len(scene.meshes)
    try:
        editing.node_at(scene, path)
    except (SceneError, IndexError, KeyError):
        return False
    return True

