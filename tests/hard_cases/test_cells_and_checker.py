"""Repetition cells and the checker floor at integer coordinates: floor, not fmod or round.

Both patterns cut space into cells with floor:

- checker: parity of floor(x / s) + floor(z / s) (even: color_a); at x = -1 the cell is -1,
  at x = -0.5 it is -1, where a trunc- or fmod-based version would say 0 and draw a double
  cell around the axes;
- repeat: cell = floor(p / period + 0.5), halves rounding *up* on both sides of zero (0.5 ->
  1, -0.5 -> 0, 2.5 -> 3), unlike GLSL's round (halves to even, or left to the
  implementation) or C's round (away from zero); limited repetition clamps the cell to
  -count..count.

A camera straight above (x0, 0, z0), looking down with an odd image, has a centre ray of
direction exactly (0, -1, 0): every point of that ray has x = x0 and z = z0 exactly, in any
precision, and a head-on plane is reached in one exact step, so the checker is evaluated at
exactly (x0, 0, z0). That puts the pattern's rule itself to the test at integer and
half-integer coordinates on every backend, with the cell read from the path label (with no
lights it is 64 (id + 1) + parity) or from which copy of a repeated sphere the ray hits.

Away from exact coordinates, an oblique view of a checker floor spanning negative and
positive x and z must show the floor-based parity of the point where each ray stopped,
excusing only pixels within 1e-4 of a cell edge (float rounding of that point).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from scene_model.builder import (Camera, Checker, Material, RenderSettings, Scene, SolidBackground,
                                 plane, sphere)

from .conftest import pixel_rays

FLOOR = {"floor": Material(checker=Checker(color_a=(0.9, 0.9, 0.9), color_b=(0.1, 0.1, 0.1),
                                           scale=1.0)),
         "half": Material(checker=Checker(color_a=(0.9, 0.9, 0.9), color_b=(0.1, 0.1, 0.1),
                                          scale=0.5)),
         "default": Material()}
HEIGHT = 2.0


def above(x0, z0=0.0) -> Camera:
    """Straight down onto (x0, 0, z0); the centre pixel of a 3 x 3 image looks there."""
    return Camera(position=(x0, HEIGHT, z0), look_at=(x0, 0.0, z0), up=(0.0, 0.0, -1.0),
                  fov=20.0)


def floor_parity(x, z, scale):
    return (math.floor(x / scale) + math.floor(z / scale)) % 2


CHECKER_POINTS = [(0.0, 0.0), (-1.0, 0.0), (-1.0, -1.0), (1.0, -1.0), (-0.5, 0.25),
                  (-3.0, 2.0), (2.0, -0.5), (-0.25, -0.75)]


@pytest.mark.parametrize("material, scale", [("floor", 1.0), ("half", 0.5)])
def test_checker_at_exact_integer_and_half_coordinates_follows_floor(renderer, material,
                                                                     scale):
    for x0, z0 in CHECKER_POINTS:
        scene = Scene(camera=above(x0, z0), render=RenderSettings(), materials=FLOOR,
                      objects=(plane(material=material),), lights=())
        frame = renderer.draw(scene, 3, 3)
        assert frame.hit[1, 1] and frame.depth[1, 1] == HEIGHT
        parity = floor_parity(x0, z0, scale)
        assert frame.path[1, 1] == 64 * 1 + parity, (
            f"{renderer}: at ({x0}, {z0}), scale {scale}, floor-based parity is {parity}")


# (x0, count, cell the ray must use): the sphere copy of cell c sits at x = c - 0.4, so a
# ray at x0 hits it (0.1 from its centre) only if it is in cell round_half_up(x0).
REPEAT_CASES = [
    (0.5, None, 1),        # half: up (GLSL round-half-even would say 0)
    (-0.5, None, 0),       # half: up (C round, away from zero, would say -1)
    (2.5, None, 3),        # half-even would say 2
    (-1.5, None, -1),      # away from zero would say -2
    (-1.3, None, -1),      # trunc(-0.8) would say 0
    (3.5, 3, None),        # cell 4 is clamped to 3, whose copy is 0.9 away: the floor
    (-2.5, 3, -2),
]


@pytest.mark.parametrize("x0, count, cell", REPEAT_CASES,
                         ids=[f"x{x}-count{c}" for x, c, _ in REPEAT_CASES])
def test_repeat_cell_at_exact_half_coordinates_rounds_halves_up(renderer, x0, count, cell):
    copies = sphere(0.2).at(-0.4, 0.3, 0.0).repeat((1.0, 0.0, 0.0),
                                                   count=None if count is None else
                                                   (count, 0, 0))
    scene = Scene(camera=above(x0), render=RenderSettings(shading="depth"),
                  objects=(copies, plane()), lights=())
    frame = renderer.draw(scene, 3, 3)
    assert frame.hit[1, 1]
    if cell is None:                     # no copy there: the floor, in one exact step
        assert frame.object_id[1, 1] == 1 and frame.depth[1, 1] == HEIGHT
        return
    offset = x0 - (cell - 0.4)
    assert abs(offset) == pytest.approx(0.1, abs=1e-12)
    top = 0.3 + math.sqrt(0.2 ** 2 - offset ** 2)         # where the ray enters the copy
    cos_theta = math.sqrt(0.2 ** 2 - offset ** 2) / 0.2
    short = (HEIGHT - top) - float(frame.depth[1, 1])
    assert frame.object_id[1, 1] == 0, f"{renderer}: x0 = {x0} missed the copy of cell {cell}"
    assert -1e-6 < short < 1e-3 / cos_theta + 1e-6


def test_every_backend_checker_on_an_oblique_floor_has_floor_parity_across_the_axes(renderer):
    scene = Scene(camera=Camera(position=(0.3, 3.0, 4.0), look_at=(-0.2, 0.0, 0.1), fov=70.0),
                  render=RenderSettings(max_steps=512,
                                        background=SolidBackground(color=(0.2, 0.3, 0.5))),
                  materials=FLOOR, objects=(plane(material="half"),), lights=())
    frame = renderer.draw(scene, 48, 36)
    origin, directions = pixel_rays(scene, 48, 36)
    hit = frame.hit
    p = origin + frame.depth[hit, None].astype(np.float64) * directions[hit]
    cells = np.floor(p[:, [0, 2]] / 0.5)
    parity = cells.sum(axis=1) % 2
    edge = np.abs(p[:, [0, 2]] / 0.5 - np.round(p[:, [0, 2]] / 0.5)).min(axis=1) * 0.5
    clear = edge > 1e-4
    assert (cells[clear] < 0).any(axis=1).sum() >= 300            # negative cells in view
    assert clear.mean() > 0.97
    np.testing.assert_array_equal(frame.path[hit][clear], 64 + parity[clear])
