"""The window's small pure helpers: panels kept inside the view, and float32 widget values
stored as the decimals a person typed."""

from __future__ import annotations

import numpy as np
import pytest

from marchlab.view_window import MENU_BAR, float32_value, panel_inside


def test_a_panel_inside_the_view_is_left_where_it_is():
    assert panel_inside((10, 30, 300, 200), (800, 600)) == (10, 30, 300, 200)


@pytest.mark.parametrize("rectangle, view, expected", [
    ((470, 460, 310, 260), (780, 560), (470, 300, 310, 260)),    # off the bottom: moved up
    ((700, 30, 310, 420), (800, 600), (490, 30, 310, 420)),      # off the right: moved left
    ((-50, 5, 200, 100), (800, 600), (0, MENU_BAR, 200, 100)),   # under the menu bar
    ((0, 30, 330, 900), (320, 240), (0, MENU_BAR, 320, 240 - MENU_BAR)),   # shrunk to fit
])
def test_a_panel_past_the_views_edge_is_moved_and_if_need_be_shrunk_inside(rectangle, view,
                                                                          expected):
    x, y, w, h = panel_inside(rectangle, view)
    assert (x, y, w, h) == expected
    assert 0 <= x and x + w <= view[0] and MENU_BAR <= y and y + h <= view[1]


@pytest.mark.parametrize("typed", [0.004, 0.1, -9.81, 1e-5, 123.456, 0.0])
def test_a_typed_decimal_read_back_as_float32_is_stored_as_that_decimal(typed):
    assert float32_value(np.float32(typed)) == typed


def test_float32_value_is_the_same_float32_as_the_widgets():
    for value in np.random.default_rng(3).uniform(-100, 100, 200).astype(np.float32):
        assert np.float32(float32_value(value)) == value
