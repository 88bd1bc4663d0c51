"""Ctrl-C stops any command cleanly, and warnings reach the user as one line of marchlab's own.

Ctrl-C is simulated by raising KeyboardInterrupt from a patched function in the middle of
the work (or of the writing): the command must end with exit code 130 and the single line
``marchlab: interrupted``, no traceback, and no file, whole or partial, left behind.
A NumPy warning raised while a command runs is not printed as NumPy prints it (a file name,
a line number and the source line) but summed up in one line (`marchlab.cli.warning_lines`).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from cli_helpers import run_cli

from marchlab.cli import warning_lines

QUICK = ("--seconds", "0.3", "--fps", "10", "--size", "32x24", "--backend", "numpy")


def interrupt(*args, **kwargs):
    raise KeyboardInterrupt


def assert_interrupted(code: int, err: str) -> None:
    assert code == 130
    assert err == "marchlab: interrupted\n"


def test_ctrl_c_during_a_render_leaves_no_file_and_exits_130(tmp_path, capsys, monkeypatch):
    from reference_cpu.render import Tracer
    real_trace, calls = Tracer.trace, []

    def trace_then_interrupt(self, origin, directions, *rest):
        calls.append(len(directions))
        if len(calls) == 2:                       # the second block of rays
            raise KeyboardInterrupt
        return real_trace(self, origin, directions, *rest)

    monkeypatch.setattr(Tracer, "trace", trace_then_interrupt)
    monkeypatch.setattr("reference_cpu.render.BLOCK_RAYS", 8)
    code, out, err = run_cli(capsys, "render", "classroom", "--size", "8x6",
                             "-o", tmp_path / "x.png")
    assert_interrupted(code, err)
    assert out == "" and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("where", ["physics.World.step", "marchlab.commands.render",
                                   "marchlab.animation.gif_bytes"],
                         ids=["stepping", "rendering_frames", "encoding"])
def test_ctrl_c_during_a_simulation_leaves_no_file_and_exits_130(tmp_path, capsys, monkeypatch,
                                                                 where):
    monkeypatch.setattr(where, interrupt)
    code, _, err = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", tmp_path / "x.gif",
                           "--csv", tmp_path / "x.csv")
    assert_interrupted(code, err)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_while_the_outputs_are_renamed_into_place_leaves_no_temporary(tmp_path, capsys,
                                                                              monkeypatch):
    monkeypatch.setattr("scene_model.files.os.replace", interrupt)
    old = tmp_path / "x.gif"
    old.write_bytes(b"the previous animation")
    code, _, err = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", old,
                           "--csv", tmp_path / "x.csv")
    assert_interrupted(code, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.gif"]
    assert old.read_bytes() == b"the previous animation"


def test_ctrl_c_during_bench_accuracy_writes_no_report_and_no_plot(tmp_path, capsys,
                                                                    monkeypatch):
    monkeypatch.setattr("marchlab.accuracy_report.sweep", interrupt)
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", "--size", "8x6",
                           "--repeat", "1", "-o", tmp_path / "r.md")
    assert code == 130 and err.endswith("marchlab: interrupted\n")
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def overflowing_render(real_render):
    """A render that, like a float32 backend given 1e308, overflows in a cast on the way."""
    def render(*args, **kwargs):
        np.array([1e308, -1e308]).astype(np.float32)          # RuntimeWarning: overflow
        np.divide(np.ones(2), np.zeros(2))                     # RuntimeWarning: divide by zero
        np.array([1e308]).astype(np.float32)                   # the same one again
        return real_render(*args, **kwargs)
    return render


def test_a_numpy_warning_reaches_the_user_as_one_line_of_marchlabs_own(tmp_path, capsys,
                                                                       monkeypatch):
    import marchlab.commands
    monkeypatch.setattr(marchlab.commands, "render", overflowing_render(marchlab.commands.render))
    code, out, err = run_cli(capsys, "render", "classroom", "--size", "4x3",
                             "-o", tmp_path / "x.png")
    assert code == 0 and out.startswith("wrote ")
    assert err.count("\n") == 1 and err.startswith("marchlab: warning: ")
    assert "overflow encountered in cast" in err and "divide by zero encountered" in err
    assert err.count("overflow encountered in cast") == 1
    assert ".py:" not in err and "RuntimeWarning" not in err


def test_a_user_error_is_still_one_line_when_warnings_came_first(tmp_path, capsys, monkeypatch):
    import marchlab.commands

    def warn_then_fail(*args, **kwargs):
        np.array([1e308]).astype(np.float32)
        raise marchlab.commands.MarchlabError("something the user can fix")

    monkeypatch.setattr(marchlab.commands, "render", warn_then_fail)
    code, _, err = run_cli(capsys, "render", "classroom", "--size", "4x3",
                           "-o", tmp_path / "x.png")
    assert code == 2 and err == "marchlab: error: something the user can fix\n"


def test_warning_lines_sum_up_arithmetic_and_drop_developer_warnings():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        np.array([1e308]).astype(np.float32)
        np.sqrt(np.array([-1.0]))
        warnings.warn("old API", DeprecationWarning)
        warnings.warn("a library has\nsomething to say", UserWarning)
    lines = warning_lines(caught)
    assert len(lines) == 2 and all(line.startswith("marchlab: warning: ") for line in lines)
    assert "overflow encountered in cast; invalid value encountered in sqrt" in lines[0]
    assert lines[1] == "marchlab: warning: a library has something to say"


def test_running_out_of_memory_past_the_budget_is_one_line_and_no_file(tmp_path, capsys,
                                                                        monkeypatch):
    """With --allow-large a job can still ask for more memory than the machine has."""
    def allocate(*args, **kwargs):
        raise MemoryError("Unable to allocate 22.4 GiB for an array with shape (100000000, 3) "
                          "and data type float64")
    monkeypatch.setattr("reference_cpu.render.Tracer.trace", allocate)
    code, _, err = run_cli(capsys, "render", "classroom", "--size", "4x3", "--allow-large",
                           "-o", tmp_path / "x.png")
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("marchlab: error: out of memory (Unable to allocate 22.4 GiB")
    assert list(tmp_path.iterdir()) == []
