"""A candidate that samples each pixel a little off its centre (a hardware rasteriser's
sub-pixel snapping, `Frame.subpixel`) is measured from the reference drawn around the
centres (`marchlab.compare.reference_around`): the four turned cameras enclose the square it
may sample at every pixel, a picture sampled inside that square passes, and one a whole
pixel off still fails."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gpu_shader.context import subpixel_shift
from marchlab import load_scene, render
from marchlab.compare import (compare_frames, failures, gates_against, outside_range,
                              reference_around, straddling)
from scene_model.camera import project, turned
from scene_model.frame import Frame
from scene_model.scene import Camera

S = 2.0 ** -9           # an NVIDIA H100's: 8 sub-pixel bits
WIDTH, HEIGHT = 64, 48


def displacement(camera, dx, dy, width, height):
    """(H, W, 2): where each pixel of the turned camera looks, in the original's pixels,
    from the pixel's centre."""
    from scene_model.camera import camera_rays
    origin, directions = camera_rays(turned(camera, dx, dy, width, height), width, height)
    seen = project(camera, origin + directions.reshape(-1, 3), width, height)[:, :2]
    x, y = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    return seen.reshape(height, width, 2) - np.stack([x, y], axis=-1)


@pytest.mark.parametrize("fov", [30.0, 60.0, 90.0])
def test_a_turned_camera_moves_the_picture_centre_by_the_turn(fov):
    camera = Camera(position=(0.3, 1.6, 4.2), look_at=(0.0, 0.2, 0.0), fov=fov)
    for turn in [(2 * S, 0.0), (0.0, -2 * S), (0.25, 0.5)]:
        moved = displacement(camera, *turn, 2 * WIDTH, 2 * HEIGHT)[HEIGHT, WIDTH]
        # That pixel's centre lies half a pixel from the image's centre: the move there
        # equals the turn to first order (within 1% of the turn's size).
        np.testing.assert_allclose(moved, turn, rtol=0, atol=1e-2 * max(map(abs, turn)))


@pytest.mark.parametrize("fov", [30.0, 60.0, 90.0])
def test_four_turned_cameras_enclose_the_sampling_square_at_every_pixel(fov):
    """The four samples (+-2 s, +-2 s) form a convex quadrilateral about each pixel's
    centre that holds the square of side 2 s, whatever the pixel's place in the image."""
    camera = Camera(position=(0.3, 1.6, 4.2), look_at=(0.0, 0.2, 0.0), fov=fov)
    corners = [displacement(camera, dx * 2 * S, dy * 2 * S, WIDTH, HEIGHT)
               for dx, dy in [(-1, -1), (1, -1), (1, 1), (-1, 1)]]        # in turning order
    for qx, qy in [(-S, -S), (S, -S), (S, S), (-S, S)]:
        for k in range(4):
            p, q = corners[k], corners[(k + 1) % 4]
            cross = ((q[..., 0] - p[..., 0]) * (qy - p[..., 1])
                     - (q[..., 1] - p[..., 1]) * (qx - p[..., 0]))
            assert np.all(cross > 0), f"a corner of the square falls outside at fov {fov}"


def test_outside_range_is_the_distance_to_the_references_span():
    references = [np.array([0.0, 1.0, 2.0, np.inf]), np.array([1.0, 1.0, 3.0, np.inf])]
    values = np.array([0.5, 1.5, 1.0, np.inf])
    np.testing.assert_array_equal(outside_range(values, references), [0.0, 0.5, 1.0, 0.0])
    np.testing.assert_array_equal(outside_range(values, references[:1]), [0.5, 0.5, 1.0, 0.0])


def ramp_frame(shift: float, subpixel: float = 0.0) -> Frame:
    """A picture whose colour climbs from 0.2 to 0.8 within 0.002 px, starting s / 4 right of
    pixel 10's centre (a toon band's edge seen at a slant: steep, with no label to mark it),
    sampled ``shift`` pixels right of every centre."""
    x = np.arange(24) + 0.5 + shift
    value = 0.2 + 0.6 * np.clip((x - 10.5 - S / 4) / 0.002, 0.0, 1.0)
    color = np.repeat(np.tile(value, (8, 1))[..., None], 3, axis=-1).astype(np.float32)
    shape = color.shape[:2]
    return Frame(color=color, depth=np.ones(shape), normal=np.tile([0.0, 0.0, 1.0], shape + (1,)),
                 steps=np.zeros(shape, np.int32), object_id=np.zeros(shape, np.int32),
                 hit=np.ones(shape, bool), backend="ramp", precision="float64",
                 path=np.zeros(shape, np.uint32), subpixel=subpixel)


def test_a_steep_ramp_sampled_off_centre_passes_against_the_reference_around_it():
    reference, candidate = ramp_frame(0.0), ramp_frame(S / 2, subpixel=S)
    gates = gates_against("float64")
    alone = compare_frames(reference, candidate, epsilon=1e-3)
    assert failures(alone, gates) == ["interior colour: 0.1465 > 0.007843 (37.35/255)",
                                      "display: 8-bit images differ by 35 levels > 1"]
    around = tuple(ramp_frame(dx) for dx in (-2 * S, 2 * S) for _ in (0, 1))
    assert failures(compare_frames(reference, candidate, epsilon=1e-3, around=around),
                    gates) == []
    wrong = ramp_frame(1.001, subpixel=S)                               # a pixel off
    assert failures(compare_frames(reference, wrong, epsilon=1e-3, around=around), gates)


def test_pixels_a_label_jump_crosses_within_the_square_are_straddling():
    reference = ramp_frame(0.0)
    moved = dataclasses.replace(ramp_frame(2 * S), path=reference.path.copy())
    moved.path[:, 10] = 1                                   # the jump passed pixel 10's centre
    mask = straddling(reference, (reference, moved))
    assert mask[:, 10].all() and mask.sum() == 8
    assert not straddling(reference, ()).any()


def test_a_mesh_picture_sampled_off_centre_passes_and_one_a_pixel_off_fails():
    scene = load_scene("meshes")
    gates = gates_against("float64", meshes=True)
    reference = render(scene, WIDTH, HEIGHT, backend="numpy-raster")
    around = reference_around(scene, WIDTH, HEIGHT, "numpy-raster", S)
    assert len(around) == 4 and reference_around(scene, WIDTH, HEIGHT, "numpy-raster", 0) == ()

    def drawn_off_centre(dx, dy):
        moved = dataclasses.replace(scene, camera=turned(scene.camera, dx, dy, WIDTH, HEIGHT))
        return dataclasses.replace(render(moved, WIDTH, HEIGHT, backend="numpy-raster"),
                                   subpixel=S)

    inside = drawn_off_centre(S, -S)
    assert failures(compare_frames(reference, inside, epsilon=scene.render.epsilon,
                                   around=around), gates) == []
    a_pixel_off = drawn_off_centre(1.0, 0.0)
    assert failures(compare_frames(reference, a_pixel_off, epsilon=scene.render.epsilon,
                                   around=around), gates)


def test_a_frame_keeps_its_subpixel_precision_through_an_npz(tmp_path):
    frame = dataclasses.replace(ramp_frame(0.0), subpixel=S)
    frame.save(tmp_path / "f.npz")
    assert Frame.load(tmp_path / "f.npz").subpixel == S


class FakeContext:
    def __init__(self, renderer, bits):
        self.info = {"GL_RENDERER": renderer, "GL_SUBPIXEL_BITS": bits}


@pytest.mark.parametrize("renderer, bits, expected", [
    ("NVIDIA H100 80GB HBM3/PCIe/SSE2", 8, 2.0 ** -9),
    ("AMD Radeon RX 7900", 4, 2.0 ** -5),
    ("llvmpipe (LLVM 15.0.6, 256 bits)", 8, 0.0)])
def test_a_hardware_rasteriser_samples_within_half_a_subpixel_step(renderer, bits, expected):
    assert subpixel_shift(FakeContext(renderer, bits)) == expected
