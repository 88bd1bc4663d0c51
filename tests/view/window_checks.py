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
from pathlib import Path

import numpy as np

from marchlab.view import Viewer
from marchlab.view_window import Window, run

SIZE = (160, 120)        # a view for image checks
PANEL_SIZE = (780, 560)  # room for the panels and free space between them, inside the
                         # 800x600 screen Xvfb has by default


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


def _state(out: Path, **values) -> None:
    (out / "result.json").write_text(json.dumps(values))


if __name__ == "__main__":
    check, folder, *rest = sys.argv[1:]
    globals()[check](Path(folder), *rest)
