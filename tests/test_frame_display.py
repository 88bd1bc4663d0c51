"""A `Frame` in a notebook: its picture (IPython's ``_repr_png_``) and a one-line repr,
never its buffers printed out."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image

import marchlab


def test_a_frame_shows_itself_as_the_png_that_save_writes(tmp_path):
    frame = marchlab.render(marchlab.load_scene("classroom"), 16, 12)
    shown = Image.open(io.BytesIO(frame._repr_png_()))
    assert shown.size == (16, 12)
    np.testing.assert_array_equal(np.asarray(shown), frame.image())
    frame.save(tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes() == frame._repr_png_()


def test_a_frames_repr_is_one_line_with_its_size_backend_and_hits():
    frame = marchlab.render(marchlab.load_scene("classroom"), 16, 12)
    text = repr(frame)
    assert "\n" not in text and len(text) < 100
    assert text == f"Frame(16x12, numpy float64, {int(frame.hit.sum())} of 192 pixels hit)"


def test_a_scene_shows_itself_in_a_notebook_as_a_short_summary_naming_its_parts():
    from scene_model.scenefile import load_scene
    scene = load_scene("csg")
    html = scene._repr_html_()
    assert html.count("<br>") < 40                       # a summary, not every field
    for part in ("smooth_union", "subtraction", "torus", "clay", "steel", "point"):
        assert part in html
