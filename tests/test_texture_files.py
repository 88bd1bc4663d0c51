"""Texture images from files: read relative to the scene file, and refused in one line.

A texture's image is read as an environment's is (`scene_model.environment.read_image`,
tested in tests/test_environment_files.py); here, what a scene file adds: the path is the
scene file's, a saved scene reloads equal, and a texture with NaN, of no pixels or missing
stops a render with one line naming the file and exit code 2, on every backend.
"""

from __future__ import annotations

import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run_cli
from marchlab import load_scene, render, save_scene
from required_backends import need_backend


def scene_file(folder, image: str, mapping: str = "triplanar") -> str:
    """A floor and a sphere of a material textured with ``image``, no lights, ambient 1."""
    path = folder / "scene.toml"
    path.write_text(f'lights = []\n\n[render]\nambient = [1.0, 1.0, 1.0]\n\n'
                    f'[materials.default]\nka = 1.0\nkd = 0.0\nks = 0.0\n'
                    f'texture = {{ image = "{image}", mapping = "{mapping}" }}\n\n'
                    '[[objects]]\ntype = "plane"\n\n'
                    '[[objects]]\ntype = "sphere"\nposition = [0.0, 1.0, 0.0]\n')
    return str(path)


def test_a_texture_named_in_a_scene_file_is_read_relative_to_it(tmp_path, monkeypatch):
    (tmp_path / "images").mkdir()
    np.save(tmp_path / "images" / "flat.npy", np.full((2, 3, 3), (0.2, 0.4, 0.6), np.float32))
    path = scene_file(tmp_path, "images/flat.npy")
    monkeypatch.chdir(tmp_path / "images")          # not where the scene file is
    scene = load_scene(path)
    assert scene.materials["default"].texture.image == str(tmp_path / "images" / "flat.npy")
    frame = render(scene, 8, 6)
    np.testing.assert_allclose(frame.color[frame.hit], np.broadcast_to(
        np.float32([0.2, 0.4, 0.6]), frame.color[frame.hit].shape), rtol=1e-6)
    save_scene(scene, tmp_path / "again.toml")
    assert load_scene(tmp_path / "again.toml") == scene


def test_a_built_in_image_stays_a_name_and_needs_no_file(tmp_path):
    scene = load_scene(scene_file(tmp_path, "uv_grid", "uv"))
    assert scene.materials["default"].texture.image == "uv_grid"
    assert render(scene, 8, 6).hit.any()


@pytest.mark.parametrize("backend", ["numpy", "gpu", "opencl"])
@pytest.mark.parametrize("case", ["NaN", "no pixels", "missing file"])
def test_render_with_a_bad_texture_exits_2_with_one_line_naming_the_file(tmp_path, capsys,
                                                                         case, backend):
    if backend != "numpy":
        need_backend(backend)
    image = tmp_path / ("nowhere.png" if case == "missing file" else "bad.npy")
    if case == "NaN":
        np.save(image, np.where(np.arange(12).reshape(2, 2, 3) == 4, np.nan, 0.5))
    elif case == "no pixels":
        np.save(image, np.zeros((0, 4, 3), np.float32))
    path = scene_file(tmp_path, str(image))
    code, _, err = run_cli(capsys, "render", path, "-o", tmp_path / "out.png", "--size", "8x6",
                           "--backend", backend)
    assert_one_line_error(code, err)
    assert str(image) in err
    assert {"NaN": "has NaN or infinite values (the first at row 0, column 1)",
            "no pixels": "is empty (4 x 0 pixels)", "missing file": "cannot read"}[case] in err
    assert not (tmp_path / "out.png").exists()
