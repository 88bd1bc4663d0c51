"""marchlab loads a backend only when it is used; the CLI shows progress only on a terminal."""

import io
import subprocess
import sys
import time

from marchlab.commands import progress_bar

BACKEND_MODULES = ("reference_cpu", "gpu_shader", "moderngl", "pyopencl", "embreex")


def loaded_after(code: str) -> list[str]:
    """Which backend modules are imported after running ``code`` in a fresh interpreter."""
    probe = f"{code}\nimport sys\nprint([m for m in {BACKEND_MODULES!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True)
    return eval(out.stdout.strip().splitlines()[-1])


def test_importing_marchlab_and_its_cli_loads_no_backend():
    code = ("import marchlab, marchlab.cli, marchlab.commands, marchlab.compare, "
            "scene_model.builder")
    assert loaded_after(code) == []


def test_rendering_with_numpy_loads_only_the_numpy_backend():
    code = "import marchlab\nmarchlab.render(marchlab.load_scene('classroom'), 4, 3)"
    assert loaded_after(code) == ["reference_cpu"]


class FakeTerminal(io.StringIO):
    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self):
        return self.tty


def run_progress(monkeypatch, tty: bool, seconds: float) -> str:
    """Drive progress_bar like a render of 4 blocks lasting ``seconds``; return stderr."""
    stderr = FakeTerminal(tty)
    monkeypatch.setattr(sys, "stderr", stderr)
    with progress_bar(4000) as progress:
        for done in (1000, 2000, 3000, 4000):
            time.sleep(seconds / 4)
            if progress is not None:
                progress(done, 4000)
    return stderr.getvalue()


def test_progress_bar_is_drawn_on_a_terminal_once_a_render_takes_over_a_second(monkeypatch):
    shown = run_progress(monkeypatch, tty=True, seconds=1.3)
    assert "px" in shown and "%" in shown


def test_no_progress_bar_for_a_quick_render_or_when_stderr_is_not_a_terminal(monkeypatch):
    assert run_progress(monkeypatch, tty=True, seconds=0.2) == ""
    assert run_progress(monkeypatch, tty=False, seconds=1.3) == ""


class RecordingBars:
    """Stands in for `marchlab.commands.progress_bar`: records each bar's unit and total and
    every report, so a test sees which phases of a command show progress (without timing)."""

    def __init__(self):
        self.bars = []

    def __call__(self, total, unit="px"):
        from contextlib import contextmanager

        @contextmanager
        def bar():
            reports = []
            self.bars.append((unit, total, reports))
            yield lambda done, _total: reports.append(done)
        return bar()


def test_simulate_shows_progress_while_stepping_and_while_rendering_frames(tmp_path, capsys,
                                                                          monkeypatch):
    from cli_helpers import run_cli
    bars = RecordingBars()
    monkeypatch.setattr("marchlab.commands.progress_bar", bars)
    code, _, err = run_cli(capsys, "simulate", "bounce", "--seconds", "0.5", "--fps", "10",
                           "--size", "16x12", "--backend", "numpy", "-o", tmp_path / "x.gif")
    assert code == 0, err
    units = [(unit, total) for unit, total, _ in bars.bars]
    assert units == [("step", 96), ("frame", 5)]               # 4 frame periods of 24 steps
    steps, frames = (reports for _, _, reports in bars.bars)
    assert steps == sorted(steps) and steps[-1] == 96
    assert frames == [1, 2, 3, 4, 5]


def test_bench_accuracy_shows_progress_per_configuration(tmp_path, capsys, monkeypatch):
    from cli_helpers import run_cli
    bars = RecordingBars()
    monkeypatch.setattr("marchlab.commands.progress_bar", bars)
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", "--size", "8x6",
                           "--repeat", "1", "-o", tmp_path / "r.md")
    assert code == 0, err
    ((unit, total, reports),) = bars.bars
    assert unit == "config" and reports == list(range(1, total + 1))
    assert "[1/" not in err                    # no line per configuration: the bar shows them


def test_compare_shows_one_bar_over_both_frames(capsys, monkeypatch):
    from cli_helpers import run_cli
    bars = RecordingBars()
    monkeypatch.setattr("marchlab.commands.progress_bar", bars)
    code, _, _ = run_cli(capsys, "compare", "classroom", "--a", "numpy", "--b", "numpy",
                         "--size", "8x6")
    assert code == 0
    ((unit, total, reports),) = bars.bars
    assert (unit, total) == ("px", 96) and reports[-1] == 96 and reports == sorted(reports)
