"""The real ``marchlab view`` window, under Xvfb on llvmpipe: what it shows is the gpu
backend's frame, and imgui-bundle's test engine drives its panels and the mouse as a person
would (`imgui_bundle.immapp.testing`). Each check opens one small window for a few seconds,
in a process of its own (tests/view/window_checks.py says why)."""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from marchlab.render import render
from scene_model import editing
from scene_model.scenefile import load_scene

CHECKS = Path(__file__).with_name("window_checks.py")
SIZE = (160, 120)


def in_window(check: str, out: Path, *arguments: str):
    """Run ``check`` of window_checks.py; its arrays and its state."""
    result = subprocess.run([sys.executable, str(CHECKS), check, str(out), *arguments],
                            check=False, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    arrays = dict(np.load(out / "result.npz")) if (out / "result.npz").exists() else {}
    state = json.loads((out / "result.json").read_text()) if (out / "result.json").exists() \
        else {}
    return arrays, state


@pytest.fixture(scope="session")
def shared_check(tmp_path_factory):
    """``in_window`` for a check that several tests read: it runs once, in the first test
    that asks (after the ``window`` fixture let it run), and the others read its results.
    Returns (folder, arrays, state)."""
    runs = {}

    def run_once(check: str):
        if check not in runs:
            out = tmp_path_factory.mktemp(check)
            runs[check] = (out, *in_window(check, out))
        return runs[check]
    return run_once


@pytest.mark.parametrize("name", ["classroom", "csg"])
def test_the_window_shows_the_gpu_backends_frame_within_one_level(window, tmp_path, name):
    arrays, _ = in_window("screen", tmp_path, name)
    expected = render(load_scene(name), *SIZE, backend="gpu").image()
    assert np.abs(arrays["screen"].astype(int) - expected).max() <= 1


def screenshot(shot: Path, size: str, frames: int) -> subprocess.CompletedProcess:
    """``marchlab view classroom --size SIZE --frames N --screenshot SHOT``, run to its end."""
    result = subprocess.run([sys.executable, "-m", "marchlab.cli", "view", "classroom",
                             "--size", size, "--frames", str(frames), "--screenshot", str(shot)],
                            check=False, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return result


def test_a_screenshot_of_an_unedited_scene_equals_marchlab_render(window, tmp_path):
    shot = tmp_path / "view.png"
    screenshot(shot, "96x72", 3)
    from PIL import Image
    expected = render(load_scene("classroom"), 96, 72, backend="gpu").image()
    assert np.abs(np.asarray(Image.open(shot)).astype(int) - expected).max() <= 1


def test_a_screenshot_larger_than_the_display_says_the_size_it_has(window, tmp_path):
    # Xvfb's screen here is 1280x1024 (pyproject.toml): the window the display gives is
    # smaller than --size, and the `wrote` line says what the picture's size is.
    shot = tmp_path / "view.png"
    result = screenshot(shot, "2000x1500", 1)
    from PIL import Image
    height, width = np.asarray(Image.open(shot)).shape[:2]
    assert (width, height) != (2000, 1500)
    assert result.stdout.strip() == (f"wrote {shot} ({width}x{height}: the window was that "
                                     "large, not --size 2000x1500)")


def test_an_edit_in_the_panel_renders_as_the_edited_scene_file(window, tmp_path):
    arrays, state = in_window("edit", tmp_path)
    assert state["max_steps"] == 24
    expected = render(load_scene("classroom", ["render.max_steps=24"]), *SIZE,
                      backend="gpu").image()
    assert np.abs(arrays["view"].astype(int) - expected).max() <= 1
    unedited = render(load_scene("classroom"), *SIZE, backend="gpu").image()
    assert np.abs(arrays["view"].astype(int) - unedited).max() > 1     # the edit shows


def _azimuth(camera) -> float:
    position, look_at = np.asarray(camera)
    offset = position - look_at
    return math.degrees(math.atan2(offset[0], offset[2]))


def test_the_test_engine_drives_sliders_combos_mouse_and_the_object_tree(window, tmp_path):
    _, seen = in_window("drive", tmp_path)
    assert seen["epsilon"] == pytest.approx(0.004)
    assert seen["overlay"] == "steps"
    assert seen["shadows"] == "soft"
    turned = _azimuth(seen["after drag"]) - _azimuth(seen["before drag"])
    # 56 px on a 560 px view is 18 degrees; ImGui holds back the first pixel of a drag (its
    # drag threshold), so up to one pixel's worth (0.32 degrees) may be missing.
    assert turned == pytest.approx(-18.0, abs=0.35)
    distance = [np.linalg.norm(np.subtract(*seen[key])) for key in ("after drag", "after wheel")]
    assert distance[1] / distance[0] == pytest.approx(0.9)
    assert seen["added"] == "torus"
    assert seen["objects after add"] == seen["objects"] + 1
    assert seen["objects after delete"] == seen["objects"]
    assert seen["objects at the end"] == seen["objects"] + 1
    edited = load_scene(tmp_path / "edited.toml")
    assert len(edited.objects) == seen["objects"] + 1
    assert edited.render.epsilon == pytest.approx(0.004) and edited.render.shadows == "soft"


def test_undo_and_redo_from_the_edit_menu_and_ctrl_z_step_epsilon_back_and_forth(
        window, shared_check):
    _, _, seen = shared_check("undo_redo")
    written = load_scene("classroom").render.epsilon
    edited = seen["after the edit"]
    assert edited == pytest.approx(0.004, rel=1e-7)       # typed, then held in a float32
    # Undo gives back the value exactly as it was, redo the edited one exactly.
    assert seen["at the start"] == written
    assert seen["after Edit > Undo"] == written
    assert seen["after Edit > Redo"] == edited
    assert seen["after Ctrl+Z"] == written
    assert seen["after Ctrl+Shift+Z"] == edited


def test_undo_after_add_removes_the_added_object_and_nothing_else(window, shared_check):
    out, _, seen = shared_check("undo_redo")
    assert seen["objects after add"] == seen["objects before add"] + [["torus", []]]
    assert seen["objects after undo"] == seen["objects before add"]
    edited = load_scene(out / "edited.toml")
    assert edited.objects == load_scene("classroom").objects
    assert edited.render.epsilon == pytest.approx(0.004, rel=1e-7)   # the redone edit stays


def test_dropping_a_top_level_object_on_an_operator_in_the_tree_moves_it_there(
        window, shared_check):
    out, _, seen = shared_check("reparent")
    # csg's top level: plane, translate(subtraction), translate(smooth_union of two spheres),
    # translate(torus), translate(rotate(box)); the torus's branch goes into the smooth union.
    before = seen["objects before"]
    sphere, torus = ["translate", [["sphere", []]]], ["translate", [["torus", []]]]
    assert before[2:4] == [["translate", [["smooth_union", [sphere, sphere]]]], torus]
    assert seen["objects after"] == [before[0], before[1],
                                     ["translate", [["smooth_union", [sphere, sphere, torus]]]],
                                     before[4]]
    assert seen["selection"] == [2, 0, 2]                 # the moved node, selected
    expected, _ = editing.reparent(load_scene("csg"), (3,), (2, 0))
    assert load_scene(out / "edited.toml").objects == expected.objects


def test_dropping_an_object_on_a_primitive_in_the_tree_moves_nothing_and_says_why(
        window, shared_check):
    _, _, seen = shared_check("reparent")
    assert seen["objects after a refused drop"] == seen["objects after"]
    # Pressing a node to drag it selects it (as a click does); the refused drop leaves it
    # selected where it is.
    assert seen["selection after a refused drop"] == [3]
    assert seen["status"] == ("not moved: objects[0]: a plane is a primitive and holds no "
                              "children")


def test_the_physics_buttons_step_one_dt_while_paused_and_reset_to_the_scene(
        window, shared_check):
    _, _, seen = shared_check("physics")
    scene = load_scene("bounce")
    dt = scene.physics.dt
    assert seen["at the start"]["steps"] == 0 and not seen["at the start"]["playing"]
    step = seen["after Step"]
    assert (step["steps"], step["time"], step["playing"]) == (1, dt, False)
    # One step of semi-implicit Euler from rest for the four balls dropped from 2 m:
    # v = g dt, then y = y0 + v dt.
    heights = np.asarray(step["positions"])[:4, 1]
    np.testing.assert_allclose(heights, 2.0 - 9.81 * dt * dt, rtol=0, atol=1e-12)
    assert seen["5 frames after Step"] == step            # paused: frames take no steps
    playing = seen["while playing"]
    assert playing["playing"] and playing["steps"] > 5
    assert playing["time"] == pytest.approx(playing["steps"] * dt, rel=1e-12)
    paused = seen["after Pause"]
    assert not paused["playing"] and paused["steps"] >= playing["steps"]
    assert seen["5 frames after Pause"] == paused
    reset = seen["after Reset"]
    assert (reset["steps"], reset["time"], reset["playing"]) == (0, 0.0, False)
    assert reset["positions"] == [list(body.position) for body in scene.bodies]
    assert reset["velocities"] == [list(body.velocity) for body in scene.bodies]


def test_the_physics_sliders_set_the_typed_values_and_kick_adds_the_sessions_impulse(
        window, shared_check):
    _, _, seen = shared_check("physics")
    scene = load_scene("bounce")
    assert seen["restitution"] == {"settings": 0.25, "bodies": [0.25] * len(scene.bodies),
                                   "planes": [0.25]}      # bounce's one plane, the floor
    assert seen["gravity"] == {"settings": [0.0, -4.0, 0.0], "world": [0.0, -4.0, 0.0]}
    # Kick after Reset gives each ball 1 N s in a direction uniform on the sphere, the
    # first draw of the session's generator, seeded by [physics] seed at the reset: its
    # velocity changes by that over its mass, 4/3 pi r^3 density. No time passes.
    kicked = seen["after Kick"]
    assert (kicked["steps"], kicked["time"]) == (0, 0.0)
    rng = np.random.default_rng(scene.physics.seed)
    directions = rng.standard_normal((len(scene.bodies), 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    mass = np.array([4 / 3 * np.pi * body.radius ** 3 * (body.density or scene.physics.density)
                     for body in scene.bodies])
    expected = np.array([body.velocity for body in scene.bodies]) + directions / mass[:, None]
    np.testing.assert_allclose(kicked["velocities"], expected, rtol=0, atol=1e-12)   # m/s


def test_check_against_the_reference_on_a_small_view_passes_every_gate(window, tmp_path):
    arrays, seen = in_window("reference_check", tmp_path)
    width, height = seen["size"]
    assert (width, height) == (340, 240)                 # the window's, CHECK_SIZE
    assert seen["failures"] == []
    from required_backends import why_unavailable
    if why_unavailable("opencl") is None:              # the third backend, where it runs
        assert seen["opencl_failures"] == []
    for name in ("reference", "gpu", "difference"):
        assert arrays[name].shape == (height, width, 3), name
    scene = load_scene("classroom")
    assert np.array_equal(arrays["reference"],
                          render(scene, width, height, backend="numpy").image())
    gpu = render(scene, width, height, backend="gpu").image()
    assert np.abs(arrays["gpu"].astype(int) - gpu).max() <= 1
