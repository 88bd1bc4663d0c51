"""Lights marked on rendered pictures (`marchlab.light_marks`, ``--mark-lights``): a dot where
the camera sees a point or spot light, none for a light behind a solid or a directional one."""

from __future__ import annotations

import dataclasses

import imageio.v3 as iio
import numpy as np

import marchlab
from cli_helpers import assert_one_line_error, run_cli
from marchlab.light_marks import MARKER_COLOR, light_marks, mark_lights
from scene_model.builder import (Camera, DirectionalLight, PointLight, RenderSettings, Scene,
                                 box, plane)
from scene_model.camera import project

WIDTH, HEIGHT = 64, 48
SCENE = Scene(camera=Camera(position=(0.0, 1.0, 5.0), look_at=(0.0, 1.0, 0.0), fov=50.0),
              render=RenderSettings(max_distance=30.0),
              lights=(PointLight(position=(-1.0, 1.5, 0.0)),),
              objects=(plane(), box(0.4).at(1.5, 1.0, 1.0)))


def test_a_light_in_view_is_marked_where_it_projects():
    frame = marchlab.render(SCENE, WIDTH, HEIGHT)
    image = mark_lights(frame.image(), SCENE, frame)
    x, y, _ = project(SCENE.camera, [SCENE.lights[0].position], WIDTH, HEIGHT)[0]
    assert (image[int(y), int(x)] == MARKER_COLOR).all()
    changed = np.any(image != frame.image(), axis=-1)
    rows, cols = np.nonzero(changed)
    assert np.hypot(cols + 0.5 - x, rows + 0.5 - y).max() < 2.0 + 1.5 + 1   # dot and ring


def test_a_light_behind_a_solid_or_a_directional_light_is_not_marked():
    hidden = PointLight(position=(1.5, 1.0, 0.3))            # behind the box, from the eye
    scene = dataclasses.replace(SCENE, lights=(hidden, DirectionalLight()))
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    assert light_marks(scene, WIDTH, HEIGHT) != []           # it projects into the picture
    assert light_marks(scene, WIDTH, HEIGHT, frame.depth) == []
    np.testing.assert_array_equal(mark_lights(frame.image(), scene, frame), frame.image())


def test_render_mark_lights_writes_the_marked_picture(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    marchlab.save_scene(SCENE, path)
    out = tmp_path / "marked.png"
    code, _, err = run_cli(capsys, "render", path, "-o", out, "--size", f"{WIDTH}x{HEIGHT}",
                           "--mark-lights")
    assert code == 0, err
    x, y, _ = project(SCENE.camera, [SCENE.lights[0].position], WIDTH, HEIGHT)[0]
    assert (iio.imread(out)[int(y), int(x)] == MARKER_COLOR).all()


def test_mark_lights_on_an_npz_exits_2_with_one_line(tmp_path, capsys):
    code, _, err = run_cli(capsys, "render", "classroom", "-o", tmp_path / "all.npz",
                           "--size", "16x12", "--mark-lights")
    assert_one_line_error(code, err)
    assert "--mark-lights" in err and not (tmp_path / "all.npz").exists()


def test_animate_mark_lights_marks_every_frame(tmp_path, capsys):
    path, out = tmp_path / "scene.toml", tmp_path / "marked.gif"
    marchlab.save_scene(SCENE, path)
    code, _, err = run_cli(capsys, "animate", path, "-o", out, "--seconds", "0.1", "--fps",
                           "20", "--size", f"{WIDTH}x{HEIGHT}", "--backend", "numpy",
                           "--mark-lights")
    assert code == 0, err
    frames = iio.imread(out, index=None)[..., :3].astype(int)
    x, y, _ = project(SCENE.camera, [SCENE.lights[0].position], WIDTH, HEIGHT)[0]
    # a GIF's palette may move a colour by a few levels
    assert len(frames) >= 1           # a still scene: the GIF may keep one frame
    assert all(np.abs(f[int(y), int(x)] - MARKER_COLOR).max() <= 8 for f in frames)
