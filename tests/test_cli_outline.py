"""``marchlab render --outline PATH``: a picture with an object outlined as the live view
outlines its selection (`gpu_shader.display.overlay_image`, `outline_mask`)."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

import marchlab
from cli_helpers import assert_one_line_error, run_cli
from gpu_shader.display import OUTLINE_COLOR, outline_mask
from scene_model.editing import primitive_ids

SIZE = (64, 48)


def test_the_outline_surrounds_the_objects_primitives_and_nothing_else(tmp_path, capsys):
    out = tmp_path / "outlined.png"
    code, _, err = run_cli(capsys, "render", "gallery", "-o", out, "--size", "64x48",
                           "--outline", "4", "--outline", "1")
    assert code == 0, err
    scene = marchlab.load_scene("gallery")
    frame = marchlab.render(scene, *SIZE)
    selected = primitive_ids(scene, (4,)) + primitive_ids(scene, (1,))
    mask = outline_mask(frame.object_id, selected)
    image = iio.imread(out)
    assert mask.sum() > 20
    expected = np.round(np.multiply(OUTLINE_COLOR, 255)).astype(np.uint8)
    assert (np.abs(image[mask].astype(int) - expected).max() <= 1)
    np.testing.assert_array_equal(image[~mask], frame.image()[~mask])


@pytest.mark.parametrize("argv, named", [
    (["--outline", "40"], "--outline 40: objects[40]: no such object"),
    (["--outline", "1.0.0"], "--outline 1.0.0: "),      # objects[1] is a translated sphere
    (["--outline", "4", "-o", "all.npz"], "--outline draws on a picture"),
])
def test_a_bad_outline_exits_2_with_one_line(argv, named, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(capsys, "render", "gallery", "--size", "16x12", *argv)
    assert_one_line_error(code, err)
    assert named in err
    assert list(tmp_path.iterdir()) == []
