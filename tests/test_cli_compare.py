"""``marchlab compare`` says which of its figures are gates and which are trends.

A gate fails the comparison (exit 1) beyond the limit printed beside it; a trend is
measured to watch and never fails it. The marks come from `marchlab.compare.gate_notes`, and
the property that matters is that they tell the truth: every figure marked a gate can fail
`failures` on its own, and no figure marked a trend can.
"""

from __future__ import annotations

import dataclasses

import pytest
from cli_helpers import run_cli

from marchlab.compare import GATE_LEGEND, Comparison, Gates, failures, gate_notes

PIXELS = 10_000


def passing() -> Comparison:
    """A comparison of two identical frames of PIXELS pixels."""
    zeros = {f.name: 0 for f in dataclasses.fields(Comparison)}
    return Comparison(**{**zeros, "pixels": PIXELS, "interior": PIXELS, "psnr": float("inf"),
                         "ssim": 1.0})


NOTES = gate_notes(Gates(), PIXELS)
GATES = [name for name, note in NOTES.items() if note.startswith("gate")]
TRENDS = [name for name, note in NOTES.items() if note == "trend"]


def test_identical_frames_pass_every_gate():
    assert failures(passing(), Gates()) == []


@pytest.mark.parametrize("name", GATES)
def test_a_figure_marked_as_a_gate_fails_the_comparison_on_its_own(name):
    over = {"int": PIXELS, "float": 1e9}[type(getattr(passing(), name)).__name__]
    worse = dataclasses.replace(passing(), **{name: over})
    assert failures(worse, Gates()), f"{name} is marked a gate but cannot fail"


@pytest.mark.parametrize("name", TRENDS)
def test_a_figure_marked_as_a_trend_never_fails_the_comparison(name):
    worst = {"psnr": 0.0, "ssim": 0.0}.get(name, 1e9)
    assert failures(dataclasses.replace(passing(), **{name: worst}), Gates()) == []


def test_gates_and_trends_cover_every_figure_but_the_counts():
    assert set(GATES) | set(TRENDS) | {"pixels", "interior"} == set(NOTES)
    assert {"psnr", "ssim", "depth_max"} <= set(TRENDS)


def test_compare_prints_each_figure_with_its_role_and_the_legend(capsys):
    code, out, _ = run_cli(capsys, "compare", "classroom", "--a", "numpy", "--b", "numpy",
                           "--b-precision", "float32", "--size", "16x12")
    assert code == 0
    lines = out.splitlines()
    assert GATE_LEGEND in lines
    rows = {line.split()[0]: line for line in lines if line.startswith("  ")}
    for name in GATES:
        assert "gate: " in rows[name], rows[name]
    for name in TRENDS:
        assert rows[name].endswith("trend"), rows[name]
    assert rows["color_max"].endswith("gate: <= 0.003922 (1/255)")
