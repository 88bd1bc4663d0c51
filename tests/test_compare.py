"""marchlab.compare measures exactly the differences injected into a copy of a frame."""

import dataclasses
import math

import numpy as np
import pytest

import marchlab
from marchlab.compare import boundary, compare_frames, dilate
from scene_model.builder import Camera, RenderSettings, Scene, SolidBackground, sphere

SCENE = Scene(camera=Camera(position=(0.0, 0.0, 4.0), fov=40.0),
              render=RenderSettings(background=SolidBackground((0.2, 0.3, 0.4))),
              objects=(sphere(1.0),))


@pytest.fixture(scope="module")
def frame():
    return marchlab.render(SCENE, 48, 36)


def copy(frame):
    return dataclasses.replace(frame, **{k: getattr(frame, k).copy() for k in
                                         ("color", "depth", "normal", "steps", "object_id", "hit")})


CENTRE = (18, 24)        # a pixel well inside the sphere's disc


def test_a_frame_compared_with_itself_shows_no_difference(frame):
    c = compare_frames(frame, frame)
    assert (c.hit_differs, c.object_id_differs, c.display_max) == (0, 0, 0)
    assert (c.depth_max, c.normal_max_degrees, c.color_max) == (0.0, 0.0, 0.0)
    assert math.isinf(c.psnr) and 0 < c.interior < frame.hit.sum()


def test_interior_depth_colour_and_normal_errors_are_measured_exactly(frame):
    b = copy(frame)
    b.depth[CENTRE] += 0.25
    b.color[CENTRE] += np.float32(0.125)
    angle = math.radians(3.0)                     # turn the normal by 3 degrees about z
    n = b.normal[CENTRE].astype(np.float64)
    rot = np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0],
                    [0, 0, 1]])
    b.normal[CENTRE] = rot @ n
    c = compare_frames(frame, b)
    assert c.depth_max == pytest.approx(0.25, abs=1e-12)
    assert c.depth_max_relative == pytest.approx(0.25 / frame.depth[CENTRE], rel=1e-9)
    assert c.color_max == pytest.approx(0.125, abs=1e-7)
    n_xy = math.hypot(n[0], n[1])                 # a turn about z moves only the xy part
    expected = math.degrees(math.acos(n[2] ** 2 + n_xy ** 2 * math.cos(angle)))
    assert c.normal_max_degrees == pytest.approx(expected, abs=1e-4)
    assert c.psnr == pytest.approx(10 * math.log10(1 / (3 * 0.125 ** 2 / (3 * frame.hit.size))),
                                   abs=1e-3)


def test_a_hit_flag_flipped_on_the_silhouette_is_excused_and_one_far_away_is_not(frame):
    edge = np.argwhere(boundary(frame.hit) & frame.hit)[0]
    b = copy(frame)
    b.hit[tuple(edge)] = False
    c = compare_frames(frame, b)
    assert (c.hit_differs, c.hit_differs_far) == (1, 0)
    b.hit[0, 0] = True                            # a corner, far from the sphere
    c = compare_frames(frame, b)
    assert (c.hit_differs, c.hit_differs_far) == (2, 1)


def test_display_difference_counts_8_bit_levels_outside_excused_pixels(frame):
    b = copy(frame)
    b.color[0, 0] = np.clip(b.color[0, 0] + 0.05, 0, 1)
    expected = np.abs(frame.image()[0, 0].astype(int) - b.image()[0, 0].astype(int)).max()
    assert compare_frames(frame, b).display_max == expected > 0


def test_boundary_and_dilate_on_a_small_mask():
    mask = np.zeros((5, 5), dtype=bool)
    mask[2, 2] = True
    assert boundary(mask).sum() == 9             # the pixel and its 8 neighbours
    assert dilate(mask, 1).sum() == 9 and dilate(mask, 2).sum() == 25
    assert not boundary(np.ones((4, 4), dtype=bool)).any()


def test_frames_of_different_sizes_are_refused(frame):
    with pytest.raises(ValueError, match="differ in size"):
        compare_frames(frame, marchlab.render(SCENE, 8, 6))
