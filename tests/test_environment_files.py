"""Environment images from files: read as linear colour, checked, and refused in one line.

8-bit images are decoded from sRGB (IEC 61966-2-1); a cube map of faces that are not square or
not of one size, an image with NaN or of no pixels, and a missing file each stop a render with
one line naming the file and exit code 2. Paths in a scene file are read relative to it.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from cli_helpers import assert_one_line_error, run_cli
from marchlab import load_scene, render, save_scene
from scene_model.environment import cube_faces, read_image, srgb_to_linear
from scene_model.errors import MarchlabError
from scene_model.scene import CUBE_FACES, CubeMapBackground, EquirectBackground

NAMES = ("px", "nx", "py", "ny", "pz", "nz")


def test_srgb_decoding_matches_the_standards_values():
    """IEC 61966-2-1: 0 and 1 are fixed, the two pieces meet at 0.04045 (to 3e-9: the
    standard's constants are rounded), and 0.5 encodes 0.2140 of linear light."""
    c = srgb_to_linear(np.array([0.0, 0.04045, 0.5, 1.0]))
    np.testing.assert_allclose(c, [0.0, 0.04045 / 12.92, 0.21404, 1.0], atol=5e-6)
    below, above = srgb_to_linear(np.array([0.04045, np.nextafter(0.04045, 1)]))
    assert abs(above - below) < 1e-8


def test_an_8_bit_png_is_read_as_linear_rgb_and_a_grey_one_as_three_equal_channels(tmp_path):
    pixels = np.array([[[0, 128, 255], [10, 200, 60]]], np.uint8)
    Image.fromarray(pixels).save(tmp_path / "colour.png")
    Image.fromarray(pixels[:, :, 1]).save(tmp_path / "grey.png")
    colour, grey = read_image(str(tmp_path / "colour.png")), read_image(str(tmp_path / "grey.png"))
    assert colour.dtype == np.float32 and colour.shape == (1, 2, 3)
    np.testing.assert_allclose(colour, srgb_to_linear(pixels / 255.0), rtol=1e-6)
    np.testing.assert_array_equal(grey, np.repeat(colour[:, :, 1:2], 3, axis=2))


def test_a_float_array_is_taken_as_linear_as_it_is(tmp_path):
    pixels = np.random.default_rng(1).uniform(0, 4, (3, 5, 3)).astype(np.float32)
    np.save(tmp_path / "hdr.npy", pixels)
    np.testing.assert_array_equal(read_image(str(tmp_path / "hdr.npy")), pixels)


def write_faces(folder, sizes=(4,) * 6, colour=(0.25, 0.5, 0.75)):
    """Six .npy faces of one colour, of the given sizes; their paths."""
    paths = []
    for name, size in zip(NAMES, sizes):
        side = size if isinstance(size, tuple) else (size, size)
        np.save(folder / f"{name}.npy", np.full(side + (3,), colour, np.float32))
        paths.append(str(folder / f"{name}.npy"))
    return paths


@pytest.mark.parametrize("sizes, problem", [
    ((4, 4, 4, 8, 4, 4), "cube map face -y is 8 x 8 pixels, but face +x"),
    ((4, 4, (4, 6), 4, 4, 4), "cube map face +y is 6 x 4 pixels; each face must be square"),
])
def test_faces_not_square_or_not_of_one_size_are_refused_naming_the_face(tmp_path, sizes,
                                                                          problem):
    paths = write_faces(tmp_path, sizes)
    with pytest.raises(MarchlabError) as caught:
        cube_faces(paths)
    bad = CUBE_FACES.index(problem.split()[3])
    assert str(caught.value).startswith(f"{paths[bad]}: {problem}")


@pytest.mark.parametrize("pixels, problem", [
    (np.zeros((0, 0, 3), np.float32), "is empty (0 x 0 pixels)"),
    (np.zeros((4, 0, 3), np.float32), "is empty (0 x 4 pixels)"),
    (np.where(np.arange(12).reshape(2, 2, 3) == 7, np.nan, 0.5), "has NaN or infinite values "
     "(the first at row 1, column 0)"),
    (np.full((2, 2, 3), np.inf), "has NaN or infinite values"),
    (np.full((2, 2, 3), -0.5), "has negative values"),
    (np.zeros((2, 2, 2)), "is not an image of grey, RGB or RGBA pixels"),
])
def test_a_texture_with_nan_or_of_no_pixels_is_refused_in_one_line(tmp_path, pixels, problem):
    np.save(tmp_path / "bad.npy", pixels)
    with pytest.raises(MarchlabError) as caught:
        read_image(str(tmp_path / "bad.npy"))
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'bad.npy'}: {problem}") and "\n" not in message


def test_a_file_that_is_not_an_image_is_refused_in_one_line(tmp_path):
    (tmp_path / "notes.png").write_text("not a picture\n")
    with pytest.raises(MarchlabError) as caught:
        read_image(str(tmp_path / "notes.png"))
    assert "not an image marchlab can read" in str(caught.value)
    assert "\n" not in str(caught.value)


# --- Scene files and the command line --------------------------------------------------------

def scene_file(folder, background: str) -> str:
    path = folder / "scene.toml"
    path.write_text(f'[render]\nbackground = {background}\n\n[[objects]]\ntype = "sphere"\n')
    return str(path)


def test_faces_named_in_a_scene_file_are_read_relative_to_it(tmp_path, monkeypatch):
    (tmp_path / "sky").mkdir()
    write_faces(tmp_path / "sky", colour=(0.2, 0.4, 0.6))
    faces = ", ".join(f'"sky/{name}.npy"' for name in NAMES)
    path = scene_file(tmp_path, f'{{ type = "cubemap", faces = [{faces}] }}')
    monkeypatch.chdir(tmp_path / "sky")          # not where the scene file is
    scene = load_scene(path)
    assert scene.render.background.faces[0] == str(tmp_path / "sky" / "px.npy")
    frame = render(scene, 8, 6)
    np.testing.assert_array_equal(frame.color[~frame.hit],
                                  np.broadcast_to(np.float32([0.2, 0.4, 0.6]),
                                                  frame.color[~frame.hit].shape))
    save_scene(scene, tmp_path / "again.toml")
    assert load_scene(tmp_path / "again.toml") == scene


def test_a_relative_path_in_python_stays_as_written():
    background = CubeMapBackground(faces=tuple(f"{n}.png" for n in NAMES))
    assert background.faces[0] == "px.png"
    assert EquirectBackground("/abs/pano.png").relative_to("/elsewhere").image == "/abs/pano.png"


@pytest.mark.parametrize("case", ["mismatched faces", "NaN", "no pixels", "missing file"])
def test_render_with_a_bad_environment_exits_2_with_one_line_naming_the_file(tmp_path, capsys,
                                                                             case):
    faces = write_faces(tmp_path, (4, 4, 4, 4, 2, 4) if case == "mismatched faces" else (4,) * 6)
    if case == "NaN":
        np.save(faces[3], np.full((4, 4, 3), np.nan, np.float32))
    elif case == "no pixels":
        np.save(faces[5], np.zeros((0, 0, 3), np.float32))
    elif case == "missing file":
        faces[1] = str(tmp_path / "nowhere.png")
    listed = ", ".join(f'"{p}"' for p in faces)
    path = scene_file(tmp_path, f'{{ type = "cubemap", faces = [{listed}] }}')
    code, _, err = run_cli(capsys, "render", path, "-o", tmp_path / "out.png", "--size", "8x6")
    assert_one_line_error(code, err)
    named = {"mismatched faces": faces[4], "NaN": faces[3], "no pixels": faces[5],
             "missing file": faces[1]}[case]
    assert named in err
    assert {"mismatched faces": "must be the same size", "NaN": "NaN",
            "no pixels": "is empty", "missing file": "cannot read"}[case] in err
    assert not (tmp_path / "out.png").exists()
