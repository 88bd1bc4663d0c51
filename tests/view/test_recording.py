"""Recordings of the view (`marchlab.recording`): the frames written are the frames given,
and a turntable is one seamless turn about the pivot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marchlab.camera_control import turntable
from marchlab.recording import Recorder, Turntable, scale_nearest
from scene_model.errors import MarchlabError
from scene_model.scenefile import load_scene


@pytest.fixture
def camera():
    return load_scene("classroom").camera


def _azimuth(camera) -> float:
    offset = np.subtract(camera.position, camera.look_at)
    return math.degrees(math.atan2(offset[0], offset[2]))


def test_turntable_frame_k_is_turned_360_k_over_n_degrees_at_the_same_distance_and_height(
        camera):
    n = 8
    cameras = turntable(camera, n)
    start = _azimuth(camera)
    for k, c in enumerate(cameras):
        turned = (_azimuth(c) - start) % 360.0
        assert turned == pytest.approx(360.0 * k / n, abs=1e-9)
        np.testing.assert_allclose(c.look_at, camera.look_at, atol=1e-12)
        offset, original = np.subtract(c.position, c.look_at), np.subtract(camera.position,
                                                                           camera.look_at)
        assert np.linalg.norm(offset) == pytest.approx(np.linalg.norm(original), rel=1e-12)
        assert offset[1] == pytest.approx(original[1], abs=1e-12)     # y is up here


def test_turntable_starts_at_the_camera_itself(camera):
    first = turntable(camera, 5)[0]
    np.testing.assert_allclose(first.position, camera.position, atol=1e-12)


def _frames(n=4, shape=(12, 16)):
    """Frames of flat primary colours, which a GIF's palette holds exactly."""
    colours = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (255, 255, 255)]
    return [np.broadcast_to(np.array(colours[k % 4], np.uint8), (*shape, 3)).copy()
            for k in range(n)]


def test_a_gif_recording_reads_back_frame_for_frame(tmp_path):
    import imageio.v3 as iio
    recorder = Recorder(tmp_path / "clip.gif", fps=10)
    for frame in _frames():
        recorder.add(frame)
    path = recorder.finish()
    back = iio.imread(path, index=None)[..., :3]
    assert back.shape == (4, 12, 16, 3)
    np.testing.assert_array_equal(back, np.stack(_frames()))


def test_an_mp4_recording_has_every_frame(tmp_path):
    import imageio.v3 as iio
    recorder = Recorder(tmp_path / "clip.mp4", fps=10)
    for frame in _frames(6, (48, 64)):
        recorder.add(frame)
    path = recorder.finish()
    back = iio.imread(path, index=None)
    assert back.shape[:3] == (6, 48, 64)
    # Lossy, but a flat red frame stays red: mean within 8 levels.
    assert np.abs(back[0].astype(int) - (255, 0, 0)).mean() < 8


def test_a_reduced_frame_is_scaled_to_the_first_frames_size_by_nearest_pixel():
    small = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)
    big = scale_nearest(small, (4, 6))
    assert big.shape == (4, 6, 3)
    np.testing.assert_array_equal(big[::2, ::2], small)
    np.testing.assert_array_equal(big[1::2, 1::2], small)
    odd = scale_nearest(small, (5, 7))          # not a whole multiple: no black border
    assert odd.shape == (5, 7, 3) and (odd[-1, -1] == small[-1, -1]).all()


def test_a_recording_that_is_not_mp4_or_gif_is_refused_before_recording(tmp_path):
    with pytest.raises(MarchlabError, match="a recording is an .mp4 or a .gif"):
        Recorder(tmp_path / "clip.avi")


def test_finishing_an_empty_recording_writes_nothing(tmp_path):
    with pytest.raises(MarchlabError, match="nothing was recorded"):
        Recorder(tmp_path / "clip.gif").finish()
    assert not (tmp_path / "clip.gif").exists()


def test_a_turntable_asks_for_each_camera_once_then_is_finished(tmp_path, camera):
    spin = Turntable(tmp_path / "spin.gif", camera, frames=3)
    expected = turntable(camera, 3)
    for k, frame in enumerate(_frames(3)):
        assert not spin.finished
        assert spin.next_camera() == expected[k]
        spin.add(frame)
    assert spin.finished and spin.finish().exists()


def test_a_turntable_of_one_frame_is_refused(tmp_path, camera):
    with pytest.raises(MarchlabError, match="at least 2 frames"):
        Turntable(tmp_path / "spin.gif", camera, frames=1)


def test_a_scripted_turntable_records_the_gpu_frame_of_each_turned_camera(window, tmp_path):
    import dataclasses
    import subprocess
    import sys
    import imageio.v3 as iio
    from marchlab.render import render
    (tmp_path / "spin.toml").write_text('[[action]]\nturntable = "spin.gif"\nframes = 4\n')
    result = subprocess.run([sys.executable, "-m", "marchlab.cli", "view", "csg",
                             "--size", "64x48", "--frames", "1", "--script", "spin.toml"],
                            capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    frames = iio.imread(tmp_path / "spin.gif", index=None)[..., :3].astype(int)
    assert frames.shape == (4, 48, 64, 3)
    scene = load_scene("csg")
    expected = [render(dataclasses.replace(scene, camera=c), 64, 48, backend="gpu").image()
                for c in turntable(scene.camera, 4)]
    for k in range(4):
        # A GIF's 256-colour palette moves a pixel by a few levels: compare the means.
        errors = [np.abs(frames[k] - e).mean() for e in expected]
        assert errors[k] < 2.0 and errors[k] == min(errors)
