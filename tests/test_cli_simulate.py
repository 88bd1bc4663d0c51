"""``marchlab simulate``: bodies stepped with a fixed dt, rendered into an animated GIF.

Frames are tiny (32x24) and runs short (0.5 s of simulated time) so the file runs in seconds.
A user error must end with one stderr line, exit code 2 and no file (not even a half-written
one) left behind.
"""

from __future__ import annotations

import csv
import importlib.util

import numpy as np
import pytest
from PIL import Image, ImageSequence

from marchlab.animation import gif_durations

from cli_helpers import assert_one_line_error, leftovers, run_cli, run_marchlab
from required_backends import need_backend

SIZE = "32x24"
QUICK = ("--seconds", "0.5", "--fps", "10", "--size", SIZE)       # 5 frames, t = 0 to 0.4 s
BODIES = 6                                                       # in the bundled bounce scene


def gif_frames(path) -> list[np.ndarray]:
    with Image.open(path) as image:
        return [np.asarray(frame.convert("RGB")) for frame in ImageSequence.Iterator(image)]


def test_simulate_bounce_writes_a_gif_of_seconds_times_fps_frames(tmp_path, capsys):
    out = tmp_path / "x.gif"
    code, stdout, _ = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", out)
    assert code == 0
    assert stdout.count("\n") == 1 and str(out) in stdout and "5 frames" in stdout
    with Image.open(out) as image:
        assert (image.format, image.n_frames, image.size) == ("GIF", 5, (32, 24))
    frames = gif_frames(out)
    assert not np.array_equal(frames[0], frames[-1])          # the balls fell
    assert leftovers(tmp_path) == []


def test_numpy_backend_writes_the_same_frame_count(tmp_path, capsys):
    out = tmp_path / "numpy.gif"
    code, stdout, _ = run_cli(capsys, "simulate", "bounce", *QUICK, "--backend", "numpy",
                              "-o", out)
    assert code == 0 and "numpy" in stdout
    with Image.open(out) as image:
        assert image.n_frames == 5


def test_gpu_and_numpy_frames_agree_to_a_few_levels(tmp_path, capsys):
    need_backend("gpu")
    # GIF palettes are chosen per frame, so only a loose bound: most pixels within 8 levels.
    paths = {backend: tmp_path / f"{backend}.gif" for backend in ("gpu", "numpy")}
    for backend, path in paths.items():
        assert run_cli(capsys, "simulate", "bounce", *QUICK, "--backend", backend,
                       "-o", path)[0] == 0
    for a, b in zip(gif_frames(paths["gpu"]), gif_frames(paths["numpy"])):
        close = np.abs(a.astype(int) - b.astype(int)).max(axis=2) <= 8
        assert close.mean() >= 0.97


def test_csv_has_one_row_per_frame_and_body_at_the_frame_times(tmp_path, capsys):
    out, table = tmp_path / "x.gif", tmp_path / "sub" / "t.csv"
    code, stdout, _ = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", out, "--csv", table)
    assert code == 0 and str(table) in stdout
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 5 * BODIES
    times = sorted({float(row["time"]) for row in rows})
    np.testing.assert_allclose(times, [0.0, 0.1, 0.2, 0.3, 0.4], atol=1e-12)
    first = [row for row in rows if float(row["time"]) == 0.0]
    assert [float(row["y"]) for row in first[:4]] == [2.0] * 4       # dropped from 2 m


def test_a_frame_period_that_is_not_a_multiple_of_dt_is_announced(tmp_path, capsys):
    code, _, stderr = run_cli(capsys, "simulate", "bounce", "--seconds", "0.3", "--fps", "7",
                              "--size", SIZE, "-o", tmp_path / "x.gif")
    assert code == 0
    assert "not a multiple of dt" in stderr and "every 34 steps" in stderr


def test_gif_frame_times_add_up_to_the_frame_starts_to_10_ms():
    durations = gif_durations(30, 1 / 30)
    assert set(durations) == {30, 40} and sum(durations) == 1000
    assert all(abs(sum(durations[:k]) - 1000 * k / 30) <= 5 for k in range(31))


@pytest.mark.parametrize("argv, message", [
    (("classroom",), "classroom: has no [[bodies]] to simulate"),
    (("bounce", "-o", "x.png"), "unsupported output format '.png'"),
    (("bounce", "--fps", "0"), "--fps: expected a positive number"),
    (("bounce", "--fps", "-3"), "--fps: expected a positive number"),
    (("bounce", "--seconds", "nan"), "--seconds: expected a positive number"),
    (("bounce", "--seconds", "0.01", "--fps", "10"), "less than one frame"),
    (("bounce", "--size", "0x24"), "expected WIDTHxHEIGHT"),
    (("bounce", "--set", "bodies[0].radius=-1"), "bounce: bodies[0].radius: must be positive"),
    (("bounce", "--set", "bodies[2].radius=1e200"), "bounce: bodies[2].radius: must be <= 1e6"),
    (("no_such_scene",), "no such file or bundled scene"),
], ids=["no_bodies", "png_output", "zero_fps", "negative_fps", "nan_seconds", "no_frame",
        "bad_size", "bad_body", "overflowing_mass", "unknown_scene"])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, argv, message):
    out = tmp_path / "out.gif"
    extra = () if "-o" in argv else ("-o", out)
    code, _, stderr = run_cli(capsys, "simulate", *argv, *extra, "--csv", tmp_path / "t.csv",
                              *(() if "--size" in argv else ("--size", SIZE)))
    assert_one_line_error(code, stderr)
    assert message in stderr, stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(importlib.util.find_spec("imageio_ffmpeg") is not None,
                    reason="imageio-ffmpeg is installed, so .mp4 works")
def test_mp4_without_imageio_ffmpeg_says_to_use_gif_in_one_line(tmp_path, capsys):
    code, _, stderr = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", tmp_path / "x.mp4")
    assert_one_line_error(code, stderr)
    assert "imageio-ffmpeg" in stderr and ".gif" in stderr
    assert list(tmp_path.iterdir()) == []


def test_the_real_command_refuses_a_scene_without_bodies_in_one_line(tmp_path):
    result = run_marchlab("simulate", "classroom", "-o", "x.gif", cwd=tmp_path)
    assert_one_line_error(result.returncode, result.stderr)
    assert result.stderr == "marchlab: error: classroom: has no [[bodies]] to simulate\n"
    assert list(tmp_path.iterdir()) == []
