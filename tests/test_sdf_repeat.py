"""Domain repetition (``op_repeat``, ``op_repeat_limited`` and the ``Repeat`` node).

The fold must give the offset from the nearest cell centre, so the field is periodic; the
limited fold must equal the infinite one inside the kept cells and, beyond them, give the
distance to the nearest kept copy (found by trying every copy).
"""

from __future__ import annotations

import numpy as np
from sdf_reference import EXACT, box_distance

from reference_cpu import sdf as S
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.shapes import Box, Repeat


PERIOD = np.array([2.0, 0.0, 3.0])      # repeat along x and z, leave y alone


def points_in_cells(rng, cells, n=1000, margin=0.01):
    """Offsets u from the cell centre (kept ``margin`` inside the cell) and the points
    u + period * cell for integer cells drawn from -cells..cells; u_y is any value."""
    u = rng.uniform(-0.5, 0.5, (n, 3)) * (PERIOD - 2 * margin)
    u[:, 1] = rng.uniform(-5, 5, n)
    cell = rng.integers(-cells, cells + 1, (n, 3)) * (PERIOD > 0)
    return u, u + PERIOD * cell, cell


def test_repeat_folds_point_to_offset_from_cell_centre_within_1e_10():
    """Along x and z the folded point is the offset from the nearest cell centre, so the field
    is periodic with the period; along y (period 0) the coordinate is returned unchanged.
    Points lie up to 150 from the origin, where one ulp is 3e-14: hence 1e-10, not 1e-12."""
    u, p, _ = points_in_cells(np.random.default_rng(13), cells=50)
    folded = S.op_repeat(p, PERIOD)
    np.testing.assert_allclose(folded, u, rtol=0, atol=1e-10)
    np.testing.assert_array_equal(folded[:, 1], p[:, 1])


def test_repeated_box_field_is_periodic_within_1e_10():
    """An off-centre box repeated every period: moving by whole periods (up to 60 away, hence
    1e-10) leaves the distance unchanged; it is the distance to the box in the point's own cell
    (within 1e-12)."""
    node = Repeat(Box((0.3, 0.4, 0.5)).at(0.2, 0.0, -0.4), tuple(PERIOD))
    sdf = build_scene_sdf([node])
    u, p, _ = points_in_cells(np.random.default_rng(14), cells=20)
    np.testing.assert_allclose(sdf(p)[0], sdf(u)[0], rtol=0, atol=1e-10)
    np.testing.assert_allclose(sdf(u)[0], box_distance(u - (0.2, 0.0, -0.4), np.array([0.3, 0.4, 0.5])),
                               rtol=0, atol=EXACT)


def test_limited_repeat_equals_repeat_inside_kept_cells():
    """Within cells -count..count the limited fold is the infinite fold, bit for bit."""
    count = np.array([2.0, 0.0, 1.0])
    _, p, cell = points_in_cells(np.random.default_rng(15), cells=3)
    kept = np.all(np.abs(cell) <= count, axis=1)
    assert kept.sum() > 100 and (~kept).sum() > 100
    np.testing.assert_array_equal(S.op_repeat_limited(p[kept], PERIOD, count),
                                  S.op_repeat(p[kept], PERIOD))


def test_limited_repeat_of_sphere_is_distance_to_nearest_kept_copy_within_1e_12():
    """The limited field equals the distance to the nearest of the (2 count + 1) copies, found by
    trying all of them; so beyond the last copy it keeps growing instead of repeating."""
    count, radius = np.array([2, 0, 1]), 0.6
    p = np.random.default_rng(16).uniform(-12, 12, (3000, 3))
    centres = np.array([(i * PERIOD[0], 0.0, k * PERIOD[2])
                        for i in range(-count[0], count[0] + 1)
                        for k in range(-count[2], count[2] + 1)])
    expected = np.linalg.norm(p[:, None, :] - centres[None], axis=-1).min(axis=1) - radius
    got = S.sdf_sphere(S.op_repeat_limited(p, PERIOD, count.astype(float)), radius)
    np.testing.assert_allclose(got, expected, rtol=0, atol=EXACT)
    beyond = p[:, 0] > PERIOD[0] * (count[0] + 1)      # past the last copy along +x
    assert np.all(got[beyond] > S.sdf_sphere(S.op_repeat(p[beyond], PERIOD), radius))
