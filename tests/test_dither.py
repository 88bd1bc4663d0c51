"""Ordered dithering of the 8-bit output (scene_model/frame.py, ``render.dither``).

Bayer's 8x8 matrix spreads the offsets added before rounding evenly over each tile, so a flat
colour keeps its mean level (to 1/64 of a level) and a smooth ramp shows a fine pattern instead
of bands; no pixel moves by more than one level; every backend dithers the same way, so the
equivalence gates hold with it on.
"""

import dataclasses

import numpy as np
import pytest

from marchlab.compare import compare_frames, failures, gates_against
from marchlab.render import render
from scene_model.frame import bayer_matrix, dither_offsets, to_uint8
from scene_model.scenefile import load_scene
from tests.required_backends import need_backend


def test_the_bayer_matrix_holds_each_index_once_and_follows_its_recursion():
    matrix = bayer_matrix(8)
    assert sorted(matrix.ravel().tolist()) == list(range(64))
    np.testing.assert_array_equal(bayer_matrix(2), [[0, 2], [3, 1]])
    m4 = bayer_matrix(4)
    np.testing.assert_array_equal(matrix[:4, :4], 4 * m4)          # the top-left quarter


def test_offsets_lie_strictly_inside_half_a_level_and_average_zero_per_tile():
    offsets = dither_offsets(13, 21)
    assert offsets.shape == (13, 21)
    assert np.abs(offsets).max() < 0.5
    assert abs(dither_offsets(8, 8).mean()) < 1e-15


@pytest.mark.parametrize("level", [0.0, 10.3, 100.49, 100.5, 127.015625, 200.9, 254.7, 255.0])
def test_a_flat_colour_keeps_its_mean_level_to_a_sixty_fourth(level):
    """A flat value x = level / 255 over an 8x8 tile: the mean dithered level is 255 x within
    1/128 (the offsets are k/64 - 63/128 for k = 0..63); rounding without dithering is off by
    up to 1/2."""
    x = np.full((8, 8, 3), level / 255)
    mean = to_uint8(x, dither_offsets(8, 8)).astype(float).mean()
    assert abs(mean - level) <= 1 / 128 + 1e-9


def test_no_pixel_moves_more_than_one_level_and_without_offsets_nothing_changes():
    rng = np.random.default_rng(3)
    x = rng.uniform(-0.1, 1.1, (30, 40, 3))
    plain, dithered = to_uint8(x).astype(int), to_uint8(x, dither_offsets(30, 40)).astype(int)
    assert np.abs(plain - dithered).max() <= 1
    np.testing.assert_array_equal(plain, np.floor(np.clip(x, 0, 1) * 255 + 0.5))


def test_a_ramp_keeps_its_level_tile_by_tile_once_dithered():
    """A ramp rising 2 levels over 256 pixels, 8 rows: rounded, it is 2-3 flat bands, and an
    8x8 tile's mean level is off the ramp's by up to 1/2; dithered, every tile's mean is
    within 0.1 of it (1/128 from the matrix, plus the ramp's rise across a tile, 1/16)."""
    x = np.linspace(100 / 255, 102 / 255, 256)[None, :, None].repeat(8, 0).repeat(3, 2)
    true = (255 * x[..., 0]).reshape(8, 32, 8).mean(axis=(0, 2))

    def tile_error(image):
        return np.abs(image[..., 0].astype(float).reshape(8, 32, 8).mean(axis=(0, 2)) - true)

    plain = to_uint8(x)
    assert len(np.unique(plain)) <= 3 and tile_error(plain).max() > 0.4
    assert tile_error(to_uint8(x, dither_offsets(8, 256))).max() < 0.1


def test_a_frame_dithers_its_colour_image_only_when_the_scene_asks():
    scene = load_scene("classroom")
    plain = render(scene, 32, 24)
    dithered = render(dataclasses.replace(scene, render=dataclasses.replace(
        scene.render, dither=True)), 32, 24)
    assert not plain.dither and dithered.dither
    assert np.array_equal(plain.color, dithered.color)
    difference = plain.image().astype(int) - dithered.image().astype(int)
    assert np.abs(difference).max() == 1 and (difference != 0).mean() > 0.1
    assert np.array_equal(plain.image("normal"), dithered.image("normal"))


@pytest.mark.parametrize("backend", ["gpu", "opencl"])
def test_every_backend_dithers_as_the_reference_and_passes_the_gates(backend):
    need_backend(backend)
    scene = load_scene("classroom")
    scene = dataclasses.replace(scene, render=dataclasses.replace(scene.render, dither=True))
    reference = render(scene, 64, 48, precision="float32")
    frame = render(scene, 64, 48, backend=backend, path_labels=True)
    assert frame.dither
    reference_labelled = render(scene, 64, 48, precision="float32", path_labels=True)
    assert failures(compare_frames(reference_labelled, frame, epsilon=scene.render.epsilon),
                    gates_against("float32")) == []
    assert (reference.image().astype(int) != frame.image().astype(int)).mean() < 0.01
