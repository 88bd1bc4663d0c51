"""``marchlab simulate``: bodies stepped with a fixed dt, rendered into an animated GIF.

Frames are tiny (32x24) and runs short (0.5 s of simulated time, 2 s at most) so the file runs
in seconds. A user error must end with one stderr line, exit code 2 and no file (not even a
half-written one) left behind.
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
    assert result.stderr == ("marchlab: error: classroom: has no [[bodies]] to simulate "
                             "(marchlab animate renders a scene without them)\n")
    assert list(tmp_path.iterdir()) == []


# --- --save-state and --load-state: a run stopped and resumed is the same run ---------------

STATE_RUN = ("--fps", "10", "--size", SIZE)       # frames every 0.1 s; 1 s is t = 0 to 0.9 s


def csv_lines(path) -> list[str]:
    return path.read_text().splitlines()


def test_a_run_saved_and_resumed_gives_the_csv_rows_of_one_run_to_the_last_digit(tmp_path,
                                                                                capsys):
    """1 s saved at its last frame (t = 0.9 s) then 1 s loaded (t = 0.9 to 1.8 s) against one
    2 s run: the resumed rows, times included, equal the long run's rows from t = 0.9 s on,
    character for character (tolerance 0)."""
    state = tmp_path / "s.npz"
    code, stdout, _ = run_cli(capsys, "simulate", "bounce", "--seconds", "1", *STATE_RUN,
                              "-o", tmp_path / "a.gif", "--save-state", state)
    assert code == 0 and f"wrote {state} (the state at t = 0.9 s, step 216;" in stdout
    code, stdout, _ = run_cli(capsys, "simulate", "bounce", "--seconds", "1", *STATE_RUN,
                              "-o", tmp_path / "b.gif", "--load-state", state,
                              "--csv", tmp_path / "b.csv")
    assert code == 0 and "from t = 0.9 to 1.8 s" in stdout
    assert run_cli(capsys, "simulate", "bounce", "--seconds", "2", *STATE_RUN,
                   "-o", tmp_path / "c.gif", "--csv", tmp_path / "c.csv")[0] == 0
    resumed, straight = csv_lines(tmp_path / "b.csv"), csv_lines(tmp_path / "c.csv")
    assert resumed[0] == straight[0]                                  # the header
    assert resumed[1:] == straight[1 + 9 * BODIES: 1 + 19 * BODIES]   # frames 9 to 18
    assert resumed[1].startswith("0.9,0,") and resumed[-1].startswith(f"1.8,{BODIES - 1},")
    assert leftovers(tmp_path) == []


@pytest.fixture
def saved_state(tmp_path, capsys):
    """The state of the bounce scene after 0.5 s (QUICK), saved to tmp_path/s.npz."""
    state = tmp_path / "s.npz"
    assert run_cli(capsys, "simulate", "bounce", *QUICK, "-o", tmp_path / "a.gif",
                   "--save-state", state)[0] == 0
    (tmp_path / "a.gif").unlink()
    return state


@pytest.mark.parametrize("argv, damage, message", [
    (("--set", "bodies[3].radius=0.3"), None,
     "--load-state {state}: radius of body 3 is 0.35 m in the file but 0.3 m in the world"),
    (("--set", "physics.dt=0.001"), None,
     "--load-state {state}: dt is 0.004166666666666667 s in the file but 0.001 s"),
    ((), lambda state: state.write_bytes(state.read_bytes()[:100]),
     "--load-state {state}: not a physics state file, or a damaged one"),
    ((), lambda state: state.unlink(), "--load-state {state}: no such state file"),
], ids=["other_radius", "other_dt", "truncated", "missing"])
def test_a_state_that_does_not_fit_is_one_line_exit_2_and_writes_nothing(
        tmp_path, capsys, saved_state, argv, damage, message):
    if damage:
        damage(saved_state)
    before = sorted(tmp_path.iterdir())
    code, _, stderr = run_cli(capsys, "simulate", "bounce", *QUICK, *argv,
                              "--load-state", saved_state, "-o", tmp_path / "b.gif",
                              "--csv", tmp_path / "b.csv", "--save-state", tmp_path / "t.npz")
    assert_one_line_error(code, stderr)
    assert message.format(state=saved_state) in stderr, stderr
    assert sorted(tmp_path.iterdir()) == before                 # no GIF, CSV or state file


def test_save_state_naming_a_folder_is_refused_before_the_run(tmp_path, capsys):
    (tmp_path / "s.npz").mkdir()
    code, _, stderr = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", tmp_path / "a.gif",
                              "--save-state", tmp_path / "s.npz")
    assert_one_line_error(code, stderr)
    assert "s.npz: is a folder" in stderr
    assert [p.name for p in tmp_path.iterdir()] == ["s.npz"]


def test_a_state_saved_from_the_command_line_loads_into_the_scenes_world(saved_state):
    """The file is the physics module's own: `physics.load_state` reads it into the world
    `build_world` makes of the same scene, at the last frame of the run (step 96, t = 0.4 s)."""
    import physics
    from marchlab.simulation import build_world
    from scene_model.scenefile import load_scene
    world = build_world(load_scene("bounce"))
    physics.load_state(world, saved_state)
    assert world.steps == 96 and world.time == 96 * world.dt
    reference = build_world(load_scene("bounce"))
    reference.step(96)
    np.testing.assert_array_equal(world.position, reference.position)
