"""The window halves of tests/view/test_view_window.py, each run in a process of its own:
``python tests/view/window_checks.py CHECK OUTDIR`` opens the window, does CHECK, writes
what it saw into OUTDIR/result.npz (arrays) and OUTDIR/result.json (state), and exits.

A process of its own because a window's GLX context and the gpu backend's headless EGL
context do not mix in one process (X error BadAccess in glXMakeCurrent), and because a
window that fails ends its process: pytest carries on and reports it.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from marchlab.view import Viewer
from marchlab.view_window import Window, run

SIZE = (160, 120)        # a view for image checks
PANEL_SIZE = (780, 560)  # room for the panels and free space between them, inside the
                         # 800x600 screen Xvfb has by default
CHECK_SIZE = (340, 240)  # room for the Render panel's button; the NumPy reference of a view
                         # this size takes about a second
WAIT_SECONDS = 30        # for what takes frames of its own: a playing clock, a check


class ScreenWindow(Window):
    """A window that also reads back what it put on the screen each frame (before ImGui
    draws the panels over it)."""

    def background(self):
        super().background()
        drawer = self.drawer
        if drawer is None or drawer.target is None:
            return
        width, height = self.viewer.size
        with drawer.ctx:
            raw = drawer.ctx.detect_framebuffer(0).read(viewport=(0, 0, width, height),
                                                        components=3)
        self.screen = np.frombuffer(raw, np.uint8).reshape(height, width, 3)[::-1]


def screen(out: Path, name: str) -> None:
    """What the window shows of scene ``name`` (no panels)."""
    shown = ScreenWindow(Viewer(name, SIZE), frames=4, panels=False)
    run(shown, SIZE)
    np.savez(out / "result.npz", screen=shown.screen)


def edit(out: Path) -> None:
    """Set max_steps in the Render panel; the view's full-resolution picture after it."""
    viewer = Viewer("classroom", SIZE)
    window = Window(viewer)
    shots = {}

    def set_max_steps(ctx):
        ctx.set_ref("//Render")
        ctx.item_input_value("max_steps##render", 24)
        ctx.yield_(2)
        window.on_gl_thread(lambda: shots.update(view=window.drawer.image(viewer)))
        ctx.yield_(2)

    run(window, SIZE, test=set_max_steps)
    np.savez(out / "result.npz", view=shots["view"])
    _state(out, max_steps=viewer.scene.render.max_steps)


def drive(out: Path) -> None:
    """Sliders, combos, a drag and the wheel on the view, the object tree, then save."""
    viewer = Viewer("classroom", PANEL_SIZE)
    viewer.resolution_scale = 0.25          # the checks are about state, not pixels
    seen = {}

    def camera(key):
        seen[key] = [list(viewer.camera.position), list(viewer.camera.look_at)]

    def moves(ctx):
        ctx.set_ref("//Render")
        ctx.item_input_value("epsilon##render", 0.004)
        seen["epsilon"] = viewer.scene.render.epsilon
        ctx.combo_click("overlay/steps")
        seen["overlay"] = viewer.overlay
        ctx.combo_click("shadows##render/soft")
        seen["shadows"] = viewer.scene.render.shadows
        ctx.mouse_move_to_pos((390.0, 300.0))          # clear of the panels
        camera("before drag")
        ctx.mouse_drag_with_delta((56.0, 0.0), 0)
        camera("after drag")
        ctx.mouse_move_to_pos((390.0, 300.0))
        ctx.mouse_wheel_y(1.0)
        ctx.yield_(2)
        camera("after wheel")
        ctx.set_ref("//Scene")
        seen["objects"] = len(viewer.history.scene.objects)
        ctx.combo_click("new/torus")
        ctx.item_click("Add")
        seen["added"] = viewer.history.scene.objects[-1].kind
        seen["objects after add"] = len(viewer.history.scene.objects)
        ctx.item_click("Delete")
        seen["objects after delete"] = len(viewer.history.scene.objects)
        ctx.item_click("Add")
        seen["objects at the end"] = len(viewer.history.scene.objects)

    run(Window(viewer), PANEL_SIZE, test=moves)
    viewer.save(out / "edited.toml")
    _state(out, **seen)


def undo_redo(out: Path) -> None:
    """Set epsilon in the Render panel, undo and redo it with the Edit menu and with Ctrl+Z
    / Ctrl+Shift+Z, then Add an object and undo that: epsilon and the objects after each."""
    from imgui_bundle import imgui
    viewer = Viewer("classroom", PANEL_SIZE)
    viewer.resolution_scale = 0.25
    seen = {}
    undo_key = imgui.Key.mod_ctrl | imgui.Key.z
    redo_key = imgui.Key.mod_ctrl | imgui.Key.mod_shift | imgui.Key.z

    def epsilon(key):
        seen[key] = viewer.history.scene.render.epsilon

    def steps(ctx):
        epsilon("at the start")
        ctx.set_ref("//Render")
        ctx.item_input_value("epsilon##render", 0.004)
        epsilon("after the edit")
        ctx.menu_click("//##MainMenuBar/Edit/Undo")
        epsilon("after Edit > Undo")
        ctx.menu_click("//##MainMenuBar/Edit/Redo")
        epsilon("after Edit > Redo")
        ctx.key_press(undo_key)
        ctx.yield_(2)
        epsilon("after Ctrl+Z")
        ctx.key_press(redo_key)
        ctx.yield_(2)
        epsilon("after Ctrl+Shift+Z")
        seen["objects before add"] = _kinds(viewer.history.scene.objects)
        ctx.set_ref("//Scene")
        ctx.combo_click("new/torus")
        ctx.item_click("Add")
        seen["objects after add"] = _kinds(viewer.history.scene.objects)
        ctx.menu_click("//##MainMenuBar/Edit/Undo")
        seen["objects after undo"] = _kinds(viewer.history.scene.objects)

    run(Window(viewer), PANEL_SIZE, test=steps)
    viewer.save(out / "edited.toml")
    _state(out, **seen)


def reparent(out: Path) -> None:
    """Drag the torus's branch of "csg" onto the smooth union in the object tree."""
    viewer = Viewer("csg", PANEL_SIZE)
    viewer.resolution_scale = 0.25
    seen = {}

    def drag(ctx):
        seen["objects before"] = _kinds(viewer.history.scene.objects)
        ctx.set_ref("//Scene/scene tabs/Objects")
        ctx.item_drag_and_drop("translate##(3,)", "translate##(2,)/smooth_union##(2, 0)")
        ctx.yield_(2)
        seen["objects after"] = _kinds(viewer.history.scene.objects)
        seen["selection"] = list(viewer.selection or ())
        # A primitive holds no children: dropping onto the floor plane moves nothing.
        ctx.item_drag_and_drop("translate##(3,)", "plane (floor)##(0,)")
        ctx.yield_(2)
        seen["objects after a refused drop"] = _kinds(viewer.history.scene.objects)
        seen["selection after a refused drop"] = list(viewer.selection or ())
        seen["status"] = viewer.status

    run(Window(viewer), PANEL_SIZE, test=drag)
    viewer.save(out / "edited.toml")
    _state(out, **seen)


def physics(out: Path) -> None:
    """Step, play, pause and reset "bounce" with the Physics panel's buttons, set restitution
    and gravity with its sliders and Kick: the playback after each."""
    viewer = Viewer("bounce", PANEL_SIZE)
    viewer.resolution_scale = 0.25
    seen = {}

    def state(key):
        playback = viewer.playback
        seen[key] = {"time": playback.time, "steps": playback.steps,
                     "playing": playback.playing,
                     "positions": playback.positions().tolist(),
                     "velocities": playback.world.velocity.tolist()}

    def buttons(ctx):
        # The panel reaches below a 560-pixel window: the test engine moves it up to reach
        # the sliders, as a person would drag it.
        ctx.set_ref("//Physics")
        state("at the start")
        ctx.item_click("Step")
        state("after Step")
        ctx.yield_(5)
        state("5 frames after Step")
        ctx.item_click("Play")
        _yield_until(ctx, lambda: viewer.playback.steps > 5)
        state("while playing")
        ctx.item_click("Pause")
        state("after Pause")
        ctx.yield_(5)
        state("5 frames after Pause")
        ctx.item_click("Reset")
        state("after Reset")
        ctx.item_input_value("restitution", 0.25)
        world = viewer.playback.world
        seen["restitution"] = {"settings": viewer.playback.settings.restitution,
                               "bodies": world.restitution.tolist(),
                               "planes": world.plane_restitution.tolist()}
        ctx.item_input_value("gravity (m s^-2)/$$1", -4.0)     # its y component
        seen["gravity"] = {"settings": list(viewer.playback.settings.gravity),
                           "world": world.gravity.tolist()}
        ctx.item_click("Kick")
        state("after Kick")

    run(Window(viewer), PANEL_SIZE, test=buttons)
    _state(out, **seen)


def reference_check(out: Path) -> None:
    """Press "Check against the reference" on a small view and wait for its verdict."""
    viewer = Viewer("classroom", CHECK_SIZE)
    seen = {}

    def press(ctx):
        ctx.set_ref("//Render")
        ctx.item_click("Check against the reference")
        _yield_until(ctx, lambda: viewer.check is not None)   # the reference renders in a thread
        ctx.yield_(2)                                          # and the panel shows its verdict
        seen["size"] = list(viewer.size)

    run(Window(viewer), CHECK_SIZE, test=press)
    if viewer.check is None:
        raise SystemExit(f"no verdict within {WAIT_SECONDS} s")
    result = viewer.check
    np.savez(out / "result.npz", reference=result.reference, gpu=result.gpu,
             difference=result.difference)
    _state(out, failures=result.failures, opencl_failures=result.opencl_failures, **seen)


def _yield_until(ctx, done) -> None:
    """Let frames pass until ``done()``, for at most WAIT_SECONDS."""
    deadline = time.monotonic() + WAIT_SECONDS
    while not done() and time.monotonic() < deadline:
        ctx.yield_()


def _kinds(nodes) -> list:
    """The kinds in a tree of nodes, nested as the tree is: [kind, [children...]]."""
    from scene_model.shapes import children
    return [[node.kind, _kinds(children(node))] for node in nodes]


def _state(out: Path, **values) -> None:
    (out / "result.json").write_text(json.dumps(values))


if __name__ == "__main__":
    check, folder, *rest = sys.argv[1:]
    globals()[check](Path(folder), *rest)
