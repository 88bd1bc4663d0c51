"""Camera path presets (`scene_model.camera_paths`, ``marchlab animate --camera-path``): each
move checked at its key times against where it must put the eye, to 1e-12."""

from __future__ import annotations

import dataclasses

import imageio.v3 as iio
import numpy as np
import pytest

import marchlab
from cli_helpers import assert_one_line_error, run_cli
from scene_model.camera import camera_basis
from scene_model.camera_paths import PRESETS, camera_path
from scene_model.errors import SceneError
from scene_model.keyframes import Orbit
from scene_model.timeline import scene_at_time

SECONDS = 4.0
SCENE = marchlab.load_scene("classroom")
EYE = np.array(SCENE.camera.position)
TARGET = np.array(SCENE.camera.look_at)
DISTANCE = np.linalg.norm(TARGET - EYE)
_, RIGHT, UP = camera_basis(SCENE.camera)


def eye_at(name, t):
    return np.array(scene_at_time(camera_path(SCENE, name, SECONDS), t).camera.position)


@pytest.mark.parametrize("name", PRESETS)
def test_every_path_starts_where_the_scene_puts_the_camera_and_keeps_its_look_at(name):
    start = eye_at(name, 0.0) if name != "flyby" else eye_at(name, SECONDS / 2)
    np.testing.assert_allclose(start, EYE, atol=1e-12)
    for t in np.linspace(0, SECONDS, 9):
        moved = scene_at_time(camera_path(SCENE, name, SECONDS), t).camera
        np.testing.assert_allclose(moved.look_at, TARGET, atol=1e-12)


def test_dolly_reaches_half_way_to_look_at_and_comes_back():
    np.testing.assert_allclose(eye_at("dolly", SECONDS / 2), EYE + 0.5 * (TARGET - EYE),
                               atol=1e-12)
    np.testing.assert_allclose(eye_at("dolly", SECONDS), EYE, atol=1e-12)


def test_crane_rises_by_half_the_distance_along_up():
    np.testing.assert_allclose(eye_at("crane", SECONDS / 2), EYE + 0.5 * DISTANCE * UP,
                               atol=1e-12)


def test_flyby_crosses_from_left_to_right_at_constant_speed():
    np.testing.assert_allclose(eye_at("flyby", 0.0), EYE - 0.5 * DISTANCE * RIGHT, atol=1e-12)
    np.testing.assert_allclose(eye_at("flyby", SECONDS / 4), EYE - 0.25 * DISTANCE * RIGHT,
                               atol=1e-12)


def test_turntable_turns_once_round_the_vertical_through_look_at():
    quarter = eye_at("turntable", SECONDS / 4) - TARGET
    start = EYE - TARGET
    assert np.linalg.norm(quarter) == pytest.approx(np.linalg.norm(start), abs=1e-12)
    up = np.array(SCENE.camera.up) / np.linalg.norm(SCENE.camera.up)
    flat = lambda v: v - (v @ up) * up
    cosine = flat(quarter) @ flat(start) / (np.linalg.norm(flat(start)) ** 2)
    assert cosine == pytest.approx(0.0, abs=1e-12)        # a quarter turn
    np.testing.assert_allclose(eye_at("turntable", SECONDS), EYE, atol=1e-9)


def test_a_scene_whose_camera_already_moves_is_refused():
    with pytest.raises(SceneError, match="already moves its camera"):
        camera_path(dataclasses.replace(SCENE, orbit=Orbit()), "dolly", SECONDS)
    keyed = camera_path(SCENE, "crane", SECONDS)
    with pytest.raises(SceneError, match="keyframes of camera.position"):
        camera_path(keyed, "flyby", SECONDS)


def test_animate_camera_path_moves_the_picture(tmp_path, capsys):
    out = tmp_path / "dolly.gif"
    code, _, err = run_cli(capsys, "animate", "classroom", "-o", out, "--seconds", "1",
                           "--fps", "4", "--size", "32x24", "--backend", "numpy",
                           "--camera-path", "dolly")
    assert code == 0, err
    frames = iio.imread(out, index=None)
    assert len(frames) >= 3
    assert np.abs(frames[2].astype(int) - frames[0].astype(int)).max() > 50


def test_a_camera_path_on_a_scene_that_orbits_exits_2_with_one_line(tmp_path, capsys):
    path = tmp_path / "orbiting.toml"
    marchlab.save_scene(dataclasses.replace(SCENE, orbit=Orbit(period=3.0)), path)
    code, _, err = run_cli(capsys, "animate", path, "-o", tmp_path / "x.gif", "--seconds",
                           "1", "--size", "16x12", "--camera-path", "turntable")
    assert_one_line_error(code, err)
    assert "--camera-path turntable" in err and not (tmp_path / "x.gif").exists()
