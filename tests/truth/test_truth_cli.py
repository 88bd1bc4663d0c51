"""``marchlab truth``: what it writes, and the one-line errors that leave nothing behind."""

import sys

import numpy as np
import pytest
from cli_helpers import assert_one_line_error, leftovers, run_cli

from marchlab import cli
from reference_cpu.truth import METHODS, ground_truth
from scene_model.builder import Scene, plane, sphere, torus
from scene_model.scenefile import save_scene

KEYS = {"depth", "normal", "hit", "object_id", "method", "error_bound", "error_rounding",
        "measured_error", "measured_error_p99"}


def test_cli_methods_are_the_truth_modules_methods():
    assert cli.TRUTH_METHODS == METHODS


def test_analytic_truth_writes_the_arrays_the_python_api_returns(capsys, tmp_path):
    output = tmp_path / "out" / "truth.npz"
    code, out, err = run_cli(capsys, "truth", "classroom", "--size", "16x12", "-o", output)
    assert code == 0 and err == ""
    assert out.startswith(f"wrote {output} (16x12, analytic: ") and out.count("\n") == 1
    with np.load(output) as data:
        assert set(data.files) == KEYS
        assert data["depth"].shape == data["hit"].shape == data["object_id"].shape == (12, 16)
        assert data["normal"].shape == (12, 16, 3)
        assert str(data["method"]) == "analytic"
        from marchlab import load_scene
        expected = ground_truth(load_scene("classroom"), 16, 12)
        np.testing.assert_array_equal(data["depth"], expected.depth)
        np.testing.assert_array_equal(data["normal"], expected.normal)
        np.testing.assert_array_equal(data["object_id"], expected.object_id)
        assert data["hit"].sum() > 0 and np.isinf(data["depth"][~data["hit"]]).all()
    assert leftovers(output.parent) == []


def test_embree_truth_writes_its_error_terms(capsys, tmp_path, embree):
    output = tmp_path / "csg.npz"
    code, out, _ = run_cli(capsys, "truth", "csg", "--method", "embree", "--size", "16x12",
                           "--resolution", "16", "-o", output)
    assert code == 0 and "embree: " in out and "error bound" in out
    with np.load(output) as data:
        assert set(data.files) == KEYS | {"error_mesh", "error_tessellation"}
        assert float(data["error_mesh"]) == pytest.approx(
            float(data["error_bound"]) - float(data["error_tessellation"])
            - float(data["error_rounding"]))
        assert float(data["measured_error"]) <= float(data["error_bound"])


def test_unsupported_node_is_one_line_naming_file_and_path_and_writes_nothing(capsys,
                                                                           tmp_path):
    scene_file = tmp_path / "donut.toml"
    save_scene(Scene(objects=(plane(), sphere(), torus().at(0, 1, 0))), scene_file)
    output = tmp_path / "truth.npz"
    code, _, err = run_cli(capsys, "truth", scene_file, "-o", output)
    assert_one_line_error(code, err)
    assert err == (f"marchlab: error: {scene_file}: objects[2]: 'torus' has no analytic "
                   "intersection (the analytic method takes unions of spheres, boxes and "
                   "planes); use --method embree\n")
    assert not output.exists() and leftovers(tmp_path) == []


@pytest.mark.parametrize("name", ("truth.png", "truth", "truth.npz.tmp"))
def test_output_must_end_in_npz(capsys, tmp_path, name):
    code, _, err = run_cli(capsys, "truth", "classroom", "--size", "4x3", "-o", tmp_path / name)
    assert_one_line_error(code, err)
    assert "(use .npz)" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("value", ("1", "-5", "many", "100000"))
def test_bad_resolution_is_one_line(capsys, value):
    code, _, err = run_cli(capsys, "truth", "classroom", "--resolution", value)
    assert_one_line_error(code, err)
    assert "--resolution" in err


def test_missing_embreex_is_one_line_saying_what_to_install(capsys, tmp_path, monkeypatch):
    # None in sys.modules makes `import embreex` fail, as on a machine without it.
    for name in ("embreex", "embreex.rtcore_scene", "embreex.mesh_construction"):
        monkeypatch.setitem(sys.modules, name, None)
    output = tmp_path / "truth.npz"
    code, _, err = run_cli(capsys, "truth", "csg", "--method", "embree", "--size", "4x3",
                           "-o", output)
    assert_one_line_error(code, err)
    assert "pip install 'marchlab[embree]'" in err
    assert not output.exists()


def test_an_unwritable_output_is_one_line_and_leaves_no_temporary_file(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code, _, err = run_cli(capsys, "truth", "classroom", "--size", "4x3",
                           "-o", blocker / "truth.npz")
    assert_one_line_error(code, err)
    assert leftovers(tmp_path) == [] and blocker.read_text() == "not a folder"
