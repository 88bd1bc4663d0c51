"""``marchlab view --script`` in the real window (under Xvfb): a script's drag from a light's
marker moves the light as a person's drag would, and the saved scene holds it."""

from __future__ import annotations

import subprocess
import sys

import pytest

from marchlab.view import Viewer
from scene_model.camera import project
from scene_model.scenefile import load_scene

SIZE = (320, 240)


def test_a_scripted_drag_from_a_lights_marker_saves_the_light_where_it_was_dropped(
        window, tmp_path):
    viewer = Viewer("classroom", SIZE)
    index, x, y = viewer.light_markers()[0]
    drop = (x - 50.0, y + 30.0)
    (tmp_path / "move.toml").write_text(
        f'[[action]]\ndrag = "left"\nfrom = [{x}, {y}]\nto = [{drop[0]}, {drop[1]}]\n'
        'frames = 5\n[[action]]\nsave = "moved.toml"\n')
    result = subprocess.run([sys.executable, "-m", "marchlab.cli", "view", "classroom",
                             "--size", f"{SIZE[0]}x{SIZE[1]}", "--frames", "1",
                             "--script", "move.toml"],
                            capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    moved = load_scene(tmp_path / "moved.toml")
    assert moved.camera == viewer.scene.camera                     # it did not orbit
    landed = project(moved.camera, [moved.lights[index].position], *SIZE)[0]
    # The saved file keeps what TOML writes of a float: well within 1e-6 of a pixel.
    assert tuple(landed[:2]) == pytest.approx(drop, abs=1e-6)
