"""The speed-against-error report (`marchlab.accuracy`, ``marchlab bench accuracy``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cli_helpers import run_cli
from marchlab import accuracy as A


def row(setting, ms, surface, off_band=0, normal=0.1, backend="numpy", precision="float64",
        scene="s"):
    zeros = {f.name: 0.0 for f in dataclasses.fields(A.Row)
             if f.type in ("float", float)}
    zeros.update(misclassified=0, off_band=off_band, notes=[])
    zeros.update(scene=scene, backend=backend, precision=precision, setting=setting, ms=ms,
                 surface_p99=surface, normal_p99_deg=normal)
    return A.Row(**zeros)


def test_pareto_keeps_exactly_the_rows_nothing_beats_on_both_time_and_error():
    rows = [row("a", 10, 1e-3), row("b", 20, 1e-4), row("c", 30, 1e-3), row("d", 5, 1e-2),
            row("e", 20, 1e-3)]
    assert [r.setting for r in A.pareto(rows)] == ["d", "a", "b"]


def test_recommend_picks_the_fastest_setting_within_tolerance_on_every_scene():
    rows = [row("fast but wrong", 1, 5e-3, scene="x"), row("fast but wrong", 1, 1e-4, scene="y"),
            row("good", 4, 9e-4, scene="x"), row("good", 4, 9e-4, scene="y"),
            row("slow", 9, 1e-5, scene="x"), row("slow", 9, 1e-5, scene="y")]
    assert A.recommend(rows)[("numpy", "float64")] == "good"
    # a misclassified pixel off the silhouette band disqualifies a setting too
    rows[2] = row("good", 4, 9e-4, off_band=1, scene="x")
    assert A.recommend(rows)[("numpy", "float64")] == "slow"


def test_measured_errors_of_the_reference_stay_within_its_contract():
    """NumPy float64 at epsilon 1e-3 against the exact truth: every hit point is within
    epsilon of the surface (the march stops where |sdf| < epsilon, and these SDFs are exact),
    and relaxed marching keeps that while taking at least 25% fewer steps."""
    scenes = A.analytic_scenes()
    grid = {k: v for k, v in A.settings_grid().items()
            if k in ("plain, eps 0.001", "auto, eps 0.001")}
    rows = A.sweep(scenes, size=(48, 36), repeat=1, grid=grid, pairs=[("numpy", "float64")])
    assert len(rows) == 4
    for r in rows:
        assert r.surface_max < 1e-3, r
        assert r.color_max <= 1 and not r.notes
    saved = A.steps_saved(rows, "auto, eps 0.001", "plain, eps 0.001")
    assert min(saved.values()) >= 0.25, saved


def test_the_markdown_table_escapes_the_pipes_of_its_titles():
    text = A.table([row("plain", 1.5, 1e-3)])
    header, rule, line = text.splitlines()
    assert header.count(" | ") == rule.count(" | ") == line.count(" | ")


def test_bench_accuracy_quick_writes_the_report_and_its_plot(tmp_path, capsys):
    report = tmp_path / "out" / "report.md"
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", "--size", "32x24",
                           "--repeat", "1", "-o", report)
    assert code == 0, err
    text = report.read_text()
    assert "## Recommended settings" in text and "classroom" in text
    plot = tmp_path / "out" / "images" / "speed-vs-error-classroom.png"
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("args, message", [
    (["-o", "report.txt"], "report.txt: the report is Markdown"),
    (["--repeat", "0"], "expected a positive integer"),
])
def test_bench_accuracy_refuses_bad_options_in_one_line(tmp_path, monkeypatch, capsys, args,
                                                        message):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", *args)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())
