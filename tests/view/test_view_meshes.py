"""``marchlab view`` on scenes of triangle meshes ("meshes", "museum"): the raster backend
draws them and the display pass shows them, so what the window shows is ``marchlab render
--backend raster``; the mouse orbits and selects by object id, the keyframes play, and the
check against the reference (numpy-raster) passes its gates.

The window halves run in a process of their own (``python tests/view/test_view_meshes.py
CHECK OUTDIR ...``), as tests/view/window_checks.py explains: a window's GLX context and the
raster backend's headless EGL context do not mix in one process. The Viewer tests at the end
need no window and no GPU.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from marchlab.view import Viewer, mesh_holding, mesh_ids
from scene_model.errors import MarchlabError
from scene_model.mesh_world import scene_meshes
from scene_model.scenefile import load_scene
from scene_model.timeline import scene_at_time

SIZE = (160, 120)
CHECK_SIZE = (340, 240)     # room for the Render panel's button (as window_checks.py's)
PANEL_SIZE = (780, 560)     # room for the panels (as window_checks.py's)
WAIT_SECONDS = 30


# --- The window's side (run as a script) -------------------------------------------------------

def _window_classes():
    from marchlab.view_window import Window

    class ScreenWindow(Window):
        """A window that also reads back what it put on the screen each frame."""

        def background(self):
            super().background()
            if self.drawer is None or self.drawer.target is None:
                return
            width, height = self.viewer.size
            with self.drawer.ctx:
                raw = self.drawer.ctx.detect_framebuffer(0).read(
                    viewport=(0, 0, width, height), components=3)
            self.screen = np.frombuffer(raw, np.uint8).reshape(height, width, 3)[::-1]
    return Window, ScreenWindow


def screen(out: Path, name: str) -> None:
    """Scene ``name`` opened without panels: what the window shows, and its screenshot."""
    from marchlab.view_window import run
    _, ScreenWindow = _window_classes()
    window = ScreenWindow(Viewer(name, SIZE), frames=4, panels=False,
                          screenshot=out / "shot.png")
    run(window, SIZE)
    from PIL import Image
    np.savez(out / "result.npz", screen=window.screen,
             shot=np.asarray(Image.open(out / "shot.png")))
    _state(out, drawer=type(window.drawer).__name__)


def mouse(out: Path, x: str, y: str) -> None:
    """On "meshes": a click at view pixel (x, y), then a left drag from there (an orbit)."""
    from marchlab.view_window import run
    Window, _ = _window_classes()
    viewer = Viewer("meshes", SIZE)
    window = Window(viewer, panels=False)
    seen, shots = {}, {}

    def actions(ctx):
        ctx.yield_(3)
        seen["renders before"] = window.drawer.renders
        ctx.mouse_move_to_pos((float(x) + 0.5, float(y) + 0.5))
        ctx.mouse_click(0)
        ctx.yield_(2)
        seen["selection"] = list(viewer.selection or ())
        seen["selected ids"] = list(viewer.selected_ids())
        window.on_gl_thread(lambda: shots.update(before=window.drawer.image(viewer)))
        ctx.yield_(2)
        seen["camera before"] = [list(viewer.camera.position), list(viewer.camera.look_at)]
        ctx.mouse_drag_with_delta((40.0, 0.0), 0)
        ctx.yield_(3)
        seen["camera after"] = [list(viewer.camera.position), list(viewer.camera.look_at)]
        seen["renders after"] = window.drawer.renders
        viewer.select(None)              # the picture compared below has no outline
        window.on_gl_thread(lambda: shots.update(after=window.drawer.image(viewer)))
        ctx.yield_(2)

    run(window, SIZE, test=actions)
    np.savez(out / "result.npz", **shots)
    _state(out, **seen)


def animation(out: Path) -> None:
    """"museum" playing its keyframes for a while, then paused: the time and the picture."""
    from marchlab.view_window import run
    Window, _ = _window_classes()
    viewer = Viewer("museum", SIZE)
    window = Window(viewer, panels=True)
    seen, shots = {}, {}

    def take():
        shots["image"] = window.drawer.image(viewer)
        seen["time"] = viewer.animation_time

    def play(ctx):
        ctx.set_ref("//Animation")
        ctx.item_click("Play##animation")
        _yield_until(ctx, lambda: (viewer.animation_time or 0.0) > 1.0)
        ctx.item_click("Pause##animation")
        ctx.yield_(2)
        window.on_gl_thread(take)
        ctx.yield_(2)

    run(window, SIZE, test=play)
    np.savez(out / "result.npz", **shots)
    _state(out, **seen)


def reference_check(out: Path) -> None:
    """Press "Check against the reference" on "meshes" and wait for its verdict."""
    from marchlab.view_window import run
    Window, _ = _window_classes()
    viewer = Viewer("meshes", CHECK_SIZE)

    def press(ctx):
        ctx.set_ref("//Render")
        ctx.item_click("Check against the reference")
        _yield_until(ctx, lambda: viewer.check is not None)
        ctx.yield_(2)                                   # the panel shows the verdict

    run(Window(viewer), CHECK_SIZE, test=press)
    if viewer.check is None:
        raise SystemExit(f"no verdict within {WAIT_SECONDS} s ({viewer.status})")
    _state(out, failures=viewer.check.failures, reference=viewer.check.reference_backend)


def tools(out: Path) -> None:
    """The object tools on "meshes": pick "torus" in the "new" list, Add, then Delete what
    the Add selected, then Add again; the scene's mesh kinds after each, and the picture."""
    from marchlab.view_window import run
    Window, _ = _window_classes()
    viewer = Viewer("meshes", PANEL_SIZE)
    window = Window(viewer)
    seen, shots = {}, {}

    def take():
        shots["image"] = window.drawer.image(viewer)

    def kinds():
        return [node.kind for node in viewer.history.scene.meshes]

    def drive(ctx):
        ctx.set_ref("//Scene")
        seen["before"] = kinds()
        ctx.combo_click("new/torus")
        ctx.item_click("Add")
        seen["after add"], seen["selection"] = kinds(), list(viewer.selection)
        ctx.item_click("Delete")
        seen["after delete"] = kinds()
        ctx.item_click("Add")
        ctx.yield_(3)
        window.on_gl_thread(take)
        ctx.yield_(2)
        seen["at the end"] = kinds()

    run(window, PANEL_SIZE, test=drive)
    viewer.save(out / "edited.toml")
    np.savez(out / "result.npz", **shots)
    _state(out, **seen)


def _yield_until(ctx, done) -> None:
    deadline = time.monotonic() + WAIT_SECONDS
    while not done() and time.monotonic() < deadline:
        ctx.yield_()


def _state(out: Path, **values) -> None:
    (out / "result.json").write_text(json.dumps(values))


# --- The tests ---------------------------------------------------------------------------------

def in_window(check: str, out: Path, *arguments: str):
    """Run ``check`` of this file in a process of its own; its arrays and its state."""
    result = subprocess.run([sys.executable, __file__, check, str(out), *arguments],
                            check=False, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    arrays = dict(np.load(out / "result.npz")) if (out / "result.npz").exists() else {}
    return arrays, json.loads((out / "result.json").read_text())


def raster_image(scene, size=SIZE) -> np.ndarray:
    from marchlab.render import render
    return render(scene, *size, backend="raster").image()


def _moved(scene, camera):
    import dataclasses
    position, look_at = camera
    return dataclasses.replace(scene, camera=dataclasses.replace(
        scene.camera, position=tuple(position), look_at=tuple(look_at)))


@pytest.mark.parametrize("name", ["meshes", "museum"])
def test_the_window_shows_marchlab_render_raster_within_one_level(window, tmp_path, name):
    arrays, state = in_window("screen", tmp_path, name)
    expected = raster_image(load_scene(name))
    assert state["drawer"] == "MeshDrawer"
    assert np.abs(arrays["shot"].astype(int) - expected).max() <= 1
    assert np.abs(arrays["screen"].astype(int) - expected).max() <= 1


def test_a_click_selects_the_mesh_under_the_cursor_and_a_drag_orbits(window, tmp_path):
    from marchlab.render import render
    scene = load_scene("meshes")
    ids = render(scene, *SIZE, backend="raster").object_id
    markers = Viewer("meshes", SIZE).light_markers()
    # The hit pixel nearest the centre that is not the most common object (the floor) and
    # is clear of the lights' markers (a press there would take hold of the light).
    rows, columns = np.nonzero(ids >= 0)
    floor = np.bincount(ids[rows, columns]).argmax()
    candidates = [(abs(c - SIZE[0] / 2) + abs(r - SIZE[1] / 2), c, r)
                  for r, c in zip(rows, columns) if ids[r, c] != floor
                  and all(np.hypot(mx - c, my - r) > 12 for _, mx, my in markers)]
    _, x, y = min(candidates)
    arrays, state = in_window("mouse", tmp_path, str(x), str(y))
    picked = mesh_holding(scene, int(ids[y, x]))
    assert state["selection"] == ["mesh", picked]
    assert int(ids[y, x]) in state["selected ids"]
    assert state["camera after"][0] != state["camera before"][0]       # the eye turned
    assert state["renders after"] > state["renders before"]
    expected = raster_image(_moved(scene, state["camera after"]))
    assert np.abs(arrays["after"].astype(int) - expected).max() <= 1
    assert np.abs(arrays["after"].astype(int) - arrays["before"]).max() > 1


def test_the_object_tools_add_and_delete_meshes_in_the_window(window, tmp_path):
    arrays, state = in_window("tools", tmp_path)
    before = state["before"]
    assert state["after add"] == before + ["torus"] and state["selection"] == ["mesh", 4]
    assert state["after delete"] == before and state["at the end"] == before + ["torus"]
    edited = load_scene(tmp_path / "edited.toml")
    assert [node.kind for node in edited.meshes] == before + ["torus"]
    # The window shows the scene with its torus, as `marchlab render --backend raster` does.
    expected = raster_image(edited, PANEL_SIZE)
    assert np.abs(arrays["image"].astype(int) - expected).max() <= 1
    assert np.abs(expected.astype(int) - raster_image(load_scene("meshes"),
                                                      PANEL_SIZE)).max() > 1


def test_the_museums_mobile_turns_in_the_window_as_the_scene_at_that_time(window, tmp_path):
    arrays, state = in_window("animation", tmp_path)
    assert state["time"] > 1.0
    viewer = Viewer("museum", SIZE)
    viewer.set_animation_time(state["time"])
    expected = raster_image(viewer.drawn_scene())
    assert np.abs(arrays["image"].astype(int) - expected).max() <= 1
    as_written = raster_image(load_scene("museum"))
    assert np.abs(arrays["image"].astype(int) - as_written).max() > 1


def test_the_check_against_numpy_raster_passes_every_gate_on_meshes(window, tmp_path):
    _, state = in_window("reference_check", tmp_path)
    assert state["reference"] == "numpy-raster"
    assert state["failures"] == []


def test_the_display_planes_pass_equals_its_numpy_twin_on_the_museum():
    from required_backends import need_backend
    need_backend("raster")
    from gpu_shader.raster_display import RasterDisplayPlanes, display_planes_numpy
    from gpu_shader.raster_render import MeshRenderer
    scene = load_scene("museum")
    renderer = MeshRenderer(scene)
    planes = RasterDisplayPlanes(renderer.ctx)
    try:
        fbo = renderer.draw(scene, *SIZE)
        raw = [np.empty((SIZE[1], SIZE[0], 4), dtype) for dtype in (np.float32, np.int32,
                                                                    np.float32)]
        with renderer.ctx:
            for plane, k in zip(raw, (0, 2, 3)):
                fbo.read_into(plane, components=4, attachment=k, dtype=plane.dtype.str[1:])
        shown = planes.read(planes.convert(fbo, *SIZE))
    finally:
        planes.release()
        renderer.release()
    expected = display_planes_numpy(*raw)
    assert (expected[0][..., 3] > 0).any() and np.isinf(expected[1][..., 3]).any()
    for got, want in zip(shown, expected):
        np.testing.assert_array_equal(got, want)     # copies and clamps only: exact


# --- The Viewer on a mesh scene, without a window ----------------------------------------------

def test_keyframes_apply_only_once_the_clock_starts_then_follow_it():
    viewer = Viewer("museum", SIZE)
    written = viewer.history.scene
    assert viewer.drawn_scene().meshes == written.meshes          # as `marchlab render`
    viewer.play_animation()
    viewer.advance(3.0)
    viewer.advance(0.0)
    still = viewer.drawn_scene()
    assert viewer.animation_time == pytest.approx(3.0)
    assert still.meshes == scene_at_time(written, 3.0).meshes
    assert still.meshes[7].rotation == pytest.approx((0.0, 90.0, 0.0))   # 360 degrees in 12 s
    assert still.camera == viewer.camera                                 # the person's
    viewer.toggle_play()                                                 # space: pause
    viewer.advance(1.0)
    assert viewer.animation_time == pytest.approx(3.0)
    viewer.rewind_animation()
    assert viewer.drawn_scene().meshes == written.meshes


@pytest.mark.parametrize("name", ["meshes", "museum"])
def test_mesh_ids_number_the_nodes_parts_as_scene_meshes_does(name):
    scene = load_scene(name)
    ids = [mesh_ids(scene, i) for i in range(len(scene.meshes))]
    assert [k for part in ids for k in part] == list(range(len(scene_meshes(scene)[0])))
    for i, part in enumerate(ids):
        assert all(mesh_holding(scene, k) == i for k in part)
    assert mesh_holding(scene, -1) is None


def test_a_pick_selects_the_top_level_mesh_and_outlines_all_its_parts():
    viewer = Viewer("museum", SIZE)
    viewer.pick(14)                      # a part of the mobile (node 7, ids 12 to 16)
    assert viewer.selection == ("mesh", 7)
    assert viewer.selected_ids() == (12, 13, 14, 15, 16)
    viewer.pick(-1)
    assert viewer.selection is None


def test_a_shift_drag_moves_the_selected_mesh_in_one_undo_step():
    viewer = Viewer("meshes", SIZE)
    viewer.select(("mesh", 1))
    before = viewer.history.scene.meshes[1].position
    assert viewer.press(80, 60, shift=True) == "object"
    viewer.move_to(90, 60)
    viewer.move_to(100, 60)
    viewer.let_go()
    assert viewer.history.scene.meshes[1].position != before
    viewer.undo()
    assert viewer.history.scene.meshes[1].position == before


def test_sdf_tools_refuse_a_mesh_scene_in_one_line():
    viewer = Viewer("meshes", SIZE)
    with pytest.raises(MarchlabError, match="SDF objects"):
        viewer.probe_pixel(10, 10)
    with pytest.raises(MarchlabError, match="triangle meshes.*uv_sphere"):
        viewer.add_object("sphere")
    assert len(viewer.history.scene.meshes) == 4


def test_the_object_tools_add_duplicate_and_delete_meshes_each_one_undo_step():
    viewer = Viewer("meshes", SIZE)
    original = viewer.history.scene.meshes
    viewer.add_object("torus")
    assert viewer.selection == ("mesh", 4) and viewer.history.scene.meshes[4].kind == "torus"
    # The new mesh is drawn: its object id is the scene's last.
    assert mesh_ids(viewer.history.scene, 4) == (len(scene_meshes(viewer.history.scene)[0]) - 1,)
    viewer.select(("mesh", 1))
    viewer.duplicate_selected()
    meshes = viewer.history.scene.meshes
    assert viewer.selection == ("mesh", 2) and len(meshes) == 6
    assert meshes[2].position == tuple(a + b for a, b in zip(meshes[1].position,
                                                              (0.5, 0.0, 0.0)))
    viewer.delete_selected()
    assert viewer.selection is None and viewer.history.scene.meshes[:4] == original
    for _ in range(3):
        viewer.undo()
    assert viewer.history.scene.meshes == original


def test_a_mesh_scene_keeps_its_last_mesh():
    viewer = Viewer("meshes", SIZE)
    for _ in range(3):
        viewer.select(("mesh", 0))
        viewer.delete_selected()
    assert len(viewer.history.scene.meshes) == 1
    viewer.select(("mesh", 0))
    viewer.delete_selected()
    assert len(viewer.history.scene.meshes) == 1 and "at least one mesh" in viewer.status


if __name__ == "__main__":
    check, folder, *rest = sys.argv[1:]
    globals()[check](Path(folder), *rest)
