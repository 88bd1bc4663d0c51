"""The display pass (`gpu_shader.display`): the picture drawn on the GPU from a target's planes.

Each overlay is held against `Frame.image` of the frame read back from the same planes, the
object-id colours and the selection outline against their NumPy twins (`id_colors`,
`outline_mask`). Tests that draw take the ``gpu`` fixture, which skips them where the gpu
backend cannot run (fails them where ``MARCHLAB_REQUIRE_BACKENDS`` names gpu).
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.display import MAX_SELECTED, OVERLAYS, depth_range, id_colors, outline_mask
from required_backends import need_backend
from scene_model.errors import MarchlabError
from scene_model.scene import rendered_scene
from scene_model.scenefile import load_scene

WIDTH, HEIGHT = 64, 48
LEVEL = 1                        # 8-bit levels a GPU picture may differ from Frame.image by
MAGENTA = (1.0, 0.0, 1.0)        # an outline colour no grey (depth) pixel can have


@pytest.fixture(scope="module")
def gpu():
    """The renderer and a `Display` on the gpu backend's context; skips without one."""
    need_backend("gpu")
    from gpu_shader.display import Display
    from gpu_shader.render import _renderer
    renderer = _renderer()
    return renderer, Display(renderer.ctx)


def draw(gpu, name: str, width: int = WIDTH, height: int = HEIGHT):
    """Render a bundled scene; its Frame, and the target that now holds its planes."""
    renderer, _ = gpu
    frame = renderer.render(rendered_scene(load_scene(name)), width, height)
    return frame, renderer.target(width, height)


def settings(frame) -> dict:
    """The display settings that make `Display.image` the picture `frame.image` makes."""
    return {"gamma": frame.gamma, "max_steps": frame.max_steps,
            "depth_range": depth_range(frame.depth, frame.hit)}


def selection(frame) -> set[int]:
    """The object with the most pixels: a selection with an outline to draw."""
    ids, counts = np.unique(frame.object_id[frame.hit], return_counts=True)
    return {int(ids[np.argmax(counts)])}


# --- the overlays ---------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["classroom", "primitives"])
@pytest.mark.parametrize("aov", ["color", "depth", "normal", "steps"])
def test_display_equals_frame_image_within_one_level(gpu, name, aov):
    frame, target = draw(gpu, name)
    picture = gpu[1].image(target, aov, **settings(frame))
    assert picture.shape == (HEIGHT, WIDTH, 3) and picture.dtype == np.uint8
    difference = np.abs(picture.astype(int) - frame.image(aov))
    assert difference.max() <= LEVEL, f"{aov} of {name}: off by {difference.max()} levels"


def test_object_id_overlay_equals_id_colors_exactly(gpu):
    frame, target = draw(gpu, "classroom")
    assert len(np.unique(frame.object_id)) > 2          # several objects and the sky
    np.testing.assert_array_equal(gpu[1].image(target, "object_id"), id_colors(frame.object_id))


def test_id_colors_are_distinct_for_ids_0_to_255_and_black_for_a_miss():
    colors = id_colors(np.arange(-1, 256)[None, :])[0]
    assert colors.dtype == np.uint8
    assert (colors[0] == 0).all()
    assert len({tuple(c) for c in colors[1:]}) == 256
    assert colors[1:].min() >= 64                         # never as dark as a miss


def test_depth_range_is_nearest_and_farthest_hit_and_unit_without_hits():
    depth = np.array([[2.0, np.inf], [5.0, 3.5]])
    assert depth_range(depth) == (2.0, 5.0)
    assert depth_range(depth, hit=depth < 4) == (2.0, 3.5)
    assert depth_range(np.full((2, 2), np.inf)) == (0.0, 1.0)


def test_read_depth_range_equals_depth_range_of_the_frame(gpu):
    frame, target = draw(gpu, "classroom")
    assert gpu[1].read_depth_range(target) == depth_range(frame.depth, frame.hit)


# --- the selection outline ------------------------------------------------------------------

@pytest.mark.parametrize("name", ["classroom", "primitives"])
def test_outline_equals_outline_mask_exactly_over_an_unchanged_overlay(gpu, name):
    frame, target = draw(gpu, name)
    selected = selection(frame)
    plain = gpu[1].image(target, "depth", **settings(frame))
    outlined = gpu[1].image(target, "depth", selected=selected, outline=MAGENTA,
                            **settings(frame))
    drawn = (outlined == [255, 0, 255]).all(axis=-1)
    expected = outline_mask(frame.object_id, selected)
    assert expected.any()
    np.testing.assert_array_equal(drawn, expected)
    np.testing.assert_array_equal(outlined[~drawn], plain[~drawn])


def test_outline_surrounds_the_selection_from_outside(gpu):
    frame, target = draw(gpu, "classroom")
    selected = selection(frame)
    outlined = gpu[1].image(target, "depth", selected=selected, outline=MAGENTA,
                            **settings(frame))
    drawn = (outlined == [255, 0, 255]).all(axis=-1)
    inside = np.isin(frame.object_id, list(selected))
    padded = np.pad(inside, 1)
    touches = padded[:-2, 1:-1] | padded[2:, 1:-1] | padded[1:-1, :-2] | padded[1:-1, 2:]
    assert not (drawn & inside).any(), "an outline pixel is itself selected"
    assert touches[drawn].all(), "an outline pixel touches no selected pixel"
    assert drawn[touches & ~inside].all(), "a gap in the outline"


def test_empty_selection_draws_no_outline(gpu):
    frame, target = draw(gpu, "classroom")
    picture = gpu[1].image(target, "depth", selected=(), outline=MAGENTA, **settings(frame))
    assert not (picture == [255, 0, 255]).all(axis=-1).any()
    assert np.abs(picture.astype(int) - frame.image("depth")).max() <= LEVEL


def test_more_selected_objects_than_the_shader_holds_is_refused(gpu):
    _, target = draw(gpu, "classroom")
    with pytest.raises(MarchlabError, match=f"at most {MAX_SELECTED}"):
        gpu[1].image(target, selected=range(MAX_SELECTED + 1))


def test_unknown_overlay_is_refused_naming_the_known_ones(gpu):
    _, target = draw(gpu, "classroom")
    with pytest.raises(MarchlabError, match=", ".join(OVERLAYS)):
        gpu[1].image(target, "albedo")


# --- drawing into a larger viewport ---------------------------------------------------------

def draw_in_window(gpu, target, window_size, viewport, **kwargs) -> np.ndarray:
    """`Display.draw` into a fresh RGBA8 framebuffer cleared to black, read back top row
    first."""
    renderer, display = gpu
    ctx = renderer.ctx
    width, height = window_size
    with ctx:
        window = ctx.framebuffer(color_attachments=[ctx.renderbuffer(window_size, 4)])
        window.use()
        ctx.clear(0.0, 0.0, 0.0, 1.0)
    display.draw(target, viewport=viewport, **kwargs)
    with ctx:
        rows = np.frombuffer(window.read(components=3, alignment=1), np.uint8)
        window.release()
    return rows.reshape(height, width, 3)[::-1]       # framebuffer rows come bottom first


def test_half_size_target_in_a_viewport_is_its_nearest_neighbour_2x_enlargement(gpu):
    frame, target = draw(gpu, "classroom", WIDTH // 2, HEIGHT // 2)
    selected = selection(frame)
    small = gpu[1].image(target, "color", selected=selected, **settings(frame))
    x, y = 16, 8                                      # the viewport's corner in the window
    picture = draw_in_window(gpu, target, (96, 64), (x, y, WIDTH, HEIGHT), aov="color",
                             selected=selected, **settings(frame))
    top = 64 - y - HEIGHT                             # y counts from the bottom
    enlarged = np.repeat(np.repeat(small, 2, axis=0), 2, axis=1)
    np.testing.assert_array_equal(picture[top:top + HEIGHT, x:x + WIDTH], enlarged)
    outside = np.ones(picture.shape[:2], bool)
    outside[top:top + HEIGHT, x:x + WIDTH] = False
    assert (picture[outside] == 0).all(), "drew outside its viewport"


def test_each_pixel_shows_the_texel_under_its_centre_at_a_1_5x_enlargement(gpu):
    _, target = draw(gpu, "classroom", WIDTH // 2, HEIGHT // 2)
    small = gpu[1].image(target, "object_id")
    picture = draw_in_window(gpu, target, (48, 36), (0, 0, 48, 36), aov="object_id")
    rows = np.floor((np.arange(36) + 0.5) * 24 / 36).astype(int)
    columns = np.floor((np.arange(48) + 0.5) * 32 / 48).astype(int)
    np.testing.assert_array_equal(picture, small[rows][:, columns])


@pytest.mark.parametrize("window", [(641, 479), (1000, 750), (97, 71)])
def test_the_texel_under_each_pixels_centre_is_exact_at_awkward_ratios(gpu, window):
    # The shader divides in floats and corrects by one (floor_divide): it must agree with
    # the integer floor((2 column + 1) W / (2 w)) at any ratio, including those where the
    # quotient is a whole number and a driver's approximate division could land below it.
    _, target = draw(gpu, "classroom", 37, 23)
    small = gpu[1].image(target, "object_id")
    width, height = window
    picture = draw_in_window(gpu, target, window, (0, 0, width, height), aov="object_id")
    rows = (2 * np.arange(height) + 1) * 23 // (2 * height)
    columns = (2 * np.arange(width) + 1) * 37 // (2 * width)
    np.testing.assert_array_equal(picture, small[rows][:, columns])


def test_draw_leaves_the_viewport_and_image_the_bound_framebuffer_as_they_were(gpu):
    renderer, display = gpu
    frame, target = draw(gpu, "classroom")
    ctx = renderer.ctx
    with ctx:
        window = ctx.framebuffer(color_attachments=[ctx.renderbuffer((80, 60), 4)])
        window.use()
        ctx.viewport = (1, 2, 30, 40)
    display.draw(target, viewport=(0, 0, 80, 60))
    display.image(target, **settings(frame))
    with ctx:
        assert ctx.fbo is window and ctx.viewport == (1, 2, 30, 40)
        window.release()


def test_warm_makes_the_program_and_draws_only_the_corner_pixel(gpu):
    from gpu_shader.display import Display
    renderer, _ = gpu
    ctx = renderer.ctx
    display = Display(ctx)
    with ctx:
        window = ctx.framebuffer(color_attachments=[ctx.renderbuffer((8, 6), 4)])
        window.use()
        ctx.clear(0.2, 0.4, 0.6, 1.0)
    display.warm(window, "color", outline=True)
    assert list(display.programs) == [("color", True)]
    with ctx:
        rows = np.frombuffer(window.read(components=3, alignment=1), np.uint8).reshape(6, 8, 3)
        window.release()
    untouched = np.ones((6, 8), bool)
    untouched[0, 0] = False                    # framebuffer row 0 is the bottom row
    assert (rows[untouched] == np.round(np.array([0.2, 0.4, 0.6]) * 255)).all()
