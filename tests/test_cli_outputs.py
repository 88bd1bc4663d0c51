"""Every output of a command is checked before the work starts and all are written together.

A folder where a file should go, a file where a folder should go, a parent that is a file:
each is refused in one line naming the user's path (never a temporary file's), before any
rendering, stepping or benchmarking (`marchlab.outputs`). A command's files appear together
or not at all (`scene_model.files.write_together`). `marchlab bench accuracy` writes into
out/ unless told otherwise, never over the documentation's copy.
"""

from __future__ import annotations

import pytest
from cli_helpers import assert_one_line_error, leftovers, run_cli

import marchlab.cli
from marchlab.outputs import check_outputs
from scene_model.errors import MarchlabError

QUICK = ("--seconds", "0.3", "--fps", "10", "--size", "32x24")      # 3 frames


def refuse_work(monkeypatch):
    """Make rendering, stepping and benchmarking fail loudly: a refused command must not
    have started its work."""
    def started(*args, **kwargs):
        raise AssertionError("the work started before the outputs were checked")
    monkeypatch.setattr("reference_cpu.render.Tracer.trace", started)
    monkeypatch.setattr("physics.World.step", started)
    monkeypatch.setattr("marchlab.accuracy_report.run", started)
    monkeypatch.setattr("marchlab.accuracy_report.plan_run", started)


def test_simulate_checks_every_output_before_stepping(tmp_path, capsys, monkeypatch):
    refuse_work(monkeypatch)
    folder = tmp_path / "DIR"
    folder.mkdir()
    code, _, err = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", tmp_path / "ok.gif",
                           "--csv", folder)
    assert_one_line_error(code, err)
    assert err == f"marchlab: error: {folder}: is a folder (give a file name)\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["DIR"]


@pytest.mark.parametrize("argv", [
    ("render", "classroom", "--size", "4x3", "-o", "{file}/x.png"),
    ("simulate", "bounce", *QUICK, "-o", "{file}/x.gif"),
    ("simulate", "bounce", *QUICK, "-o", "ok.gif", "--csv", "{file}/deeper/t.csv"),
    ("truth", "classroom", "--size", "4x3", "-o", "{file}/t.npz"),
    ("bench", "accuracy", "--quick", "-o", "{file}/r.md"),
    ("bench", "accuracy", "--quick", "-o", "r.md", "--images", "{file}/plots"),
], ids=["render", "simulate", "simulate_csv", "truth", "bench_report", "bench_images"])
def test_an_output_under_a_regular_file_is_refused_naming_it_before_any_work(
        tmp_path, capsys, monkeypatch, argv):
    refuse_work(monkeypatch)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "FILE").write_text("a file, not a folder")
    argv = [arg.replace("{file}", "FILE") for arg in argv]
    code, _, err = run_cli(capsys, *argv)
    assert_one_line_error(code, err)
    assert "FILE is not a folder" in err
    named = next(arg for arg in argv if arg.startswith("FILE/"))
    assert err.startswith(f"marchlab: error: {named}: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["FILE"]


def test_compare_save_to_a_regular_file_is_one_line_before_rendering(tmp_path, capsys,
                                                                    monkeypatch):
    refuse_work(monkeypatch)
    target = tmp_path / "PATH"
    target.write_text("not a folder")
    code, stdout, err = run_cli(capsys, "compare", "classroom", "--a", "numpy", "--b", "numpy",
                                "--size", "8x6", "--save", target)
    assert_one_line_error(code, err)
    assert err == f"marchlab: error: {target}: is a file, not a folder\n"
    assert stdout == "" and target.read_text() == "not a folder"


def test_the_same_path_named_for_two_outputs_is_refused(tmp_path, capsys, monkeypatch):
    refuse_work(monkeypatch)
    out = tmp_path / "same.gif"
    code, _, err = run_cli(capsys, "simulate", "bounce", *QUICK, "-o", out, "--csv", out)
    assert_one_line_error(code, err)
    assert "named twice" in err and not out.exists()


def test_check_outputs_accepts_files_whose_folders_can_still_be_made(tmp_path):
    check_outputs(files=[tmp_path / "a" / "b" / "c.png", None], folders=[tmp_path / "new"])
    assert list(tmp_path.iterdir()) == []                   # checking makes nothing
    with pytest.raises(MarchlabError, match="is a folder"):
        check_outputs(files=[tmp_path])


def test_simulate_writes_its_gif_and_csv_together_or_neither(tmp_path, capsys, monkeypatch):
    """A full disk while the CSV's temporary is written: the GIF is not left alone either."""
    import scene_model.files as files
    real = files._write_temporary

    def disk_full_for_csv(path, payload):
        if path.suffix == ".csv":
            raise OSError(28, "No space left on device", "/tmp/.t.csv.abc123.tmp")
        return real(path, payload)

    monkeypatch.setattr(files, "_write_temporary", disk_full_for_csv)
    gif, table = tmp_path / "ok.gif", tmp_path / "t.csv"
    code, _, err = run_cli(capsys, "simulate", "bounce", *QUICK, "--backend", "numpy",
                           "-o", gif, "--csv", table)
    assert_one_line_error(code, err)
    assert err == f"marchlab: error: {table}: cannot write: No space left on device\n"
    assert list(tmp_path.iterdir()) == []


def test_a_write_error_names_the_users_path_never_the_temporary(tmp_path, capsys, monkeypatch):
    def refused(*args, **kwargs):
        raise PermissionError(13, "Permission denied", str(tmp_path / ".x.png.k2j4.tmp"))
    monkeypatch.setattr("scene_model.files.tempfile.mkstemp", refused)
    out = tmp_path / "x.png"
    code, _, err = run_cli(capsys, "render", "classroom", "--size", "4x3", "-o", out)
    assert_one_line_error(code, err)
    assert err == f"marchlab: error: {out}: cannot write: Permission denied\n"
    assert ".tmp" not in err


def test_bench_accuracy_writes_into_out_by_default_never_under_docs(tmp_path, capsys,
                                                                    monkeypatch):
    import marchlab.accuracy_report as report
    seen = {}

    def fake_run(markdown, images, *args, **kwargs):
        seen.update(markdown=markdown, images=images)
        return []

    monkeypatch.setattr(report, "run", fake_run)
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", "--size", "8x6")
    assert code == 0, err
    assert (str(seen["markdown"]), str(seen["images"])) == ("out/speed-vs-error.md",
                                                            "out/images")
    bench = marchlab.cli.build_parser().parse_args(["bench", "accuracy"])
    assert not bench.output.startswith("docs")


def test_make_speed_vs_error_is_what_regenerates_the_docs_copy():
    from pathlib import Path
    makefile = (Path(__file__).parents[1] / "Makefile").read_text()
    assert ("speed-vs-error: $(VENV)/.installed\n\t$(BIN)/marchlab bench accuracy "
            "-o docs/speed-vs-error.md --images docs/images\n") in makefile
    assert "make speed-vs-error" in makefile.split("\n\n")[0]          # the header names it


def test_truth_refuses_an_image_over_the_pixel_budget_before_tracing(tmp_path, capsys,
                                                                    monkeypatch):
    monkeypatch.setattr("reference_cpu.truth.ground_truth",
                        lambda *a, **k: pytest.fail("the truth started"))
    code, _, err = run_cli(capsys, "truth", "classroom", "--size", "10000x10000",
                           "-o", tmp_path / "t.npz")
    assert_one_line_error(code, err)
    assert "100,000,000 pixels" in err and "smaller --size" in err
    assert leftovers(tmp_path) == [] and list(tmp_path.iterdir()) == []
