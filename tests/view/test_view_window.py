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
from scene_model.scenefile import load_scene

CHECKS = Path(__file__).with_name("window_checks.py")
SIZE = (160, 120)


def in_window(check: str, out: Path, *arguments: str):
    """Run ``check`` of window_checks.py; its arrays and its state."""
    result = subprocess.run([sys.executable, str(CHECKS), check, str(out), *arguments],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    arrays = dict(np.load(out / "result.npz")) if (out / "result.npz").exists() else {}
    state = json.loads((out / "result.json").read_text()) if (out / "result.json").exists() \
        else {}
    return arrays, state


@pytest.mark.parametrize("name", ["classroom", "csg"])
def test_the_window_shows_the_gpu_backends_frame_within_one_level(window, tmp_path, name):
    arrays, _ = in_window("screen", tmp_path, name)
    expected = render(load_scene(name), *SIZE, backend="gpu").image()
    assert np.abs(arrays["screen"].astype(int) - expected).max() <= 1


def test_a_screenshot_of_an_unedited_scene_equals_marchlab_render(window, tmp_path):
    shot = tmp_path / "view.png"
    result = subprocess.run([sys.executable, "-m", "marchlab.cli", "view", "classroom",
                             "--size", "96x72", "--frames", "3", "--screenshot", str(shot)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    from PIL import Image
    expected = render(load_scene("classroom"), 96, 72, backend="gpu").image()
    assert np.abs(np.asarray(Image.open(shot)).astype(int) - expected).max() <= 1


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
