"""The live view's state without a window (marchlab/view.py `Viewer`): what the mouse, the
keys, the sliders and the menus of ``marchlab view`` do to the camera, the scene, its undo
history, its file and its physics. No GUI, no OpenGL, no GPU: each test calls the function a
button would call and checks the plain data it changed."""

from __future__ import annotations

import os

import numpy as np
import pytest

from marchlab import camera_control
from marchlab.view import (MOVING_SCALE, MOVING_SCALES, SETTLE_SECONDS, TARGET_FPS, Viewer,
                          adapt_moving_scale)
from scene_model import editing
from scene_model.camera import camera_basis, pixel_ray, project
from scene_model.errors import MarchlabError
from scene_model.scene import rendered_scene, scene_at
from scene_model.scenefile import load_scene, scene_to_toml
from scene_model.shapes import Translate

SIZE = (640, 480)
BODIES_SCENE = "bounce"      # a bundled scene with [[bodies]]
PLAIN_SCENE = "classroom"    # a bundled scene without


@pytest.fixture
def clock():
    """A fake clock: ``now[0]`` seconds, moved by the test."""
    return [100.0]


@pytest.fixture
def viewer(clock):
    return Viewer(PLAIN_SCENE, SIZE, clock=lambda: clock[0])


@pytest.fixture
def scene_file(tmp_path):
    """The classroom copied into tmp_path, so the test may save and change it."""
    path = tmp_path / "classroom.toml"
    path.write_text(scene_to_toml(load_scene(PLAIN_SCENE)), encoding="utf-8")
    return path


def _rewrite(path, text):
    """Write ``text`` to ``path`` and move its mtime a second on, so that a file system with
    coarse timestamps still sees a change."""
    before = os.stat(path).st_mtime_ns
    path.write_text(text, encoding="utf-8")
    os.utime(path, ns=(before + 1_000_000_000, before + 1_000_000_000))


def assert_cameras_equal(a, b, tol=1e-12):
    np.testing.assert_allclose(a.position, b.position, rtol=0, atol=tol)
    np.testing.assert_allclose(a.look_at, b.look_at, rtol=0, atol=tol)
    np.testing.assert_allclose(a.up, b.up, rtol=0, atol=tol)
    assert a.fov == pytest.approx(b.fov, abs=tol)


# --- the resolution the view renders at ----------------------------------------------------

def test_render_size_is_the_full_window_at_rest(viewer):
    assert viewer.render_size() == SIZE


def test_render_size_is_moving_scale_of_each_side_while_the_camera_moves(viewer, clock):
    viewer.drag("left", 12, 0)
    expected = tuple(round(side * MOVING_SCALE) for side in SIZE)
    assert viewer.render_size() == expected
    clock[0] += 0.9 * SETTLE_SECONDS
    assert viewer.render_size() == expected


def test_render_size_returns_to_full_size_settle_seconds_after_the_last_drag(viewer, clock):
    viewer.drag("left", 12, 0)
    clock[0] += 0.9 * SETTLE_SECONDS
    viewer.drag("right", 0, 5)              # a second drag restarts the wait
    clock[0] += 0.9 * SETTLE_SECONDS
    assert viewer.render_size() != SIZE
    clock[0] += 0.2 * SETTLE_SECONDS        # 1.1 x SETTLE_SECONDS after the last drag
    assert viewer.render_size() == SIZE


def test_render_size_stays_full_while_moving_when_refine_is_off(viewer):
    viewer.refine = False
    viewer.scroll(1)
    assert viewer.moving
    assert viewer.render_size() == SIZE


def test_render_size_is_resolution_scale_of_each_side(viewer):
    viewer.resolution_scale = 0.5
    assert viewer.render_size() == (320, 240)
    viewer.drag("left", 3, 4)
    assert viewer.render_size() == (round(320 * MOVING_SCALE), round(240 * MOVING_SCALE))


def _settle(frame_seconds, fixed=0.0, frames=40, scale=MOVING_SCALE):
    """The moving scales ``frames`` frames in a row take, each frame costing
    ``frame_seconds(scale)``, with ``fixed`` known as the frame's fixed part."""
    scales = []
    for _ in range(frames):
        scale = adapt_moving_scale(scale, frame_seconds(scale), fixed)
        scales.append(scale)
    return scales


FIXED = 0.015     # a frame's fixed part (panels, display, swap) in these models


def _frame_model(full_frame_ms):
    """A frame: the fixed part plus a render that grows with the picture's area, taking
    ``full_frame_ms`` in all at scale 1."""
    return lambda scale: FIXED + (full_frame_ms / 1e3 - FIXED) * scale ** 2


@pytest.mark.parametrize("full_frame_ms", [60.0, 200.0, 400.0])
@pytest.mark.parametrize("start", [MOVING_SCALES[0], MOVING_SCALE, MOVING_SCALES[-1]])
def test_adapt_moving_scale_knowing_the_fixed_part_settles_on_the_finest_step_within_30_fps(
        full_frame_ms, start):
    cost = _frame_model(full_frame_ms)
    scales = _settle(cost, fixed=FIXED, scale=start)
    fitting = [s for s in MOVING_SCALES if cost(s) <= 1 / TARGET_FPS]
    assert set(scales[-10:]) == {fitting[-1]}


@pytest.mark.parametrize("full_frame_ms", [60.0, 200.0, 400.0])
@pytest.mark.parametrize("start", [MOVING_SCALES[0], MOVING_SCALE, MOVING_SCALES[-1]])
def test_adapt_moving_scale_not_knowing_the_fixed_part_settles_within_30_fps(full_frame_ms,
                                                                             start):
    cost = _frame_model(full_frame_ms)
    scales = _settle(cost, fixed=0.0, scale=start)
    assert len(set(scales[-10:])) == 1                     # steady, no flicker
    assert cost(scales[-1]) <= 1 / TARGET_FPS


def test_adapt_moving_scale_stays_at_the_coarsest_step_when_nothing_keeps_the_rate():
    assert _settle(lambda scale: 0.1)[-1] == MOVING_SCALES[0]


def test_adapt_moving_scale_steps_up_only_when_the_area_model_says_the_next_step_fits():
    # At 0.3, 25 ms: 0.35 would take 25 * (0.35 / 0.3)**2 = 34 ms > 33.3 ms: stay.
    assert adapt_moving_scale(0.3, 0.025) == 0.3
    assert adapt_moving_scale(0.3, 0.024) == 0.35             # 32.7 ms: step up
    assert adapt_moving_scale(0.3, 0.034) == 0.25             # missed 30 fps: step down


def test_frames_drawn_moving_adapt_the_viewers_moving_scale_and_others_do_not(viewer):
    viewer.record_frame_time(0.2, drew=True, drew_moving=False)
    assert viewer.moving_scale == MOVING_SCALE
    viewer.record_frame_time(0.2, drew_moving=True)
    assert viewer.moving_scale < MOVING_SCALE
    viewer.adapt = False
    viewer.record_frame_time(0.2, drew_moving=True)
    assert viewer.moving_scale == MOVING_SCALES[MOVING_SCALES.index(MOVING_SCALE) - 1]


def test_frames_that_render_nothing_tell_the_adaptation_the_frames_fixed_part(viewer):
    # At 0.35, 30 ms a frame: with nothing known of the fixed part, 0.4 would be predicted
    # at 30 * (0.4 / 0.35)**2 = 39 ms (stay); with 20 ms of it fixed, at 33.1 ms (step up).
    viewer.record_frame_time(0.030, drew_moving=True)
    assert viewer.moving_scale == 0.35
    for seconds in (0.025, 0.020, 0.022):
        viewer.record_frame_time(seconds, drew=False)
    viewer.record_frame_time(0.030, drew_moving=True)
    assert viewer.moving_scale == 0.4


# --- the camera --------------------------------------------------------------------------

@pytest.mark.parametrize("button, dx, dy", [("left", 40, -25), ("right", -13, 7),
                                            ("middle", 5, 60)])
def test_drag_moves_the_camera_as_camera_control_drag(viewer, button, dx, dy):
    expected = camera_control.drag(viewer.camera, button, dx, dy, SIZE[1])
    viewer.drag(button, dx, dy)
    assert_cameras_equal(viewer.camera, expected, tol=0)


def test_scroll_moves_the_camera_as_camera_control_scroll(viewer):
    expected = camera_control.scroll(viewer.camera, 2.5)
    viewer.scroll(2.5)
    assert_cameras_equal(viewer.camera, expected, tol=0)


def test_fly_moves_the_camera_as_camera_control_fly_keys(viewer):
    expected = camera_control.fly_keys(viewer.camera, {"D", "E"}, 0.3, True)
    viewer.fly({"D", "E"}, 0.3, fast=True)
    assert_cameras_equal(viewer.camera, expected, tol=0)


def test_advance_with_w_held_flies_forward_for_those_seconds(viewer):
    expected = camera_control.fly_keys(viewer.camera, {"W"}, 0.2)
    viewer.hold_keys({"w"})
    viewer.advance(0.2)
    assert_cameras_equal(viewer.camera, expected, tol=1e-12)
    viewer.hold_keys(set())
    viewer.advance(0.2)                     # nothing held: the camera stays
    assert_cameras_equal(viewer.camera, expected, tol=0)


def test_reset_camera_returns_to_the_files_camera(viewer):
    viewer.drag("left", 100, 30)
    viewer.scroll(3)
    viewer.reset_camera()
    assert_cameras_equal(viewer.camera, load_scene(PLAIN_SCENE).camera, tol=0)


# --- editing fields ----------------------------------------------------------------------

def test_set_field_changes_the_scene_as_one_undo_step(viewer):
    before = viewer.scene
    assert viewer.set_field("render.epsilon", 0.002) is True
    assert viewer.scene.render.epsilon == 0.002
    assert viewer.history.undo_labels == ("set render.epsilon",)
    viewer.undo()
    assert viewer.scene == before


def test_a_slider_drag_of_set_field_calls_on_one_path_is_one_undo_step(viewer):
    before = viewer.scene
    for value in (0.0015, 0.002, 0.0025, 0.003):
        assert viewer.set_field("render.epsilon", value)
    assert viewer.scene.render.epsilon == 0.003
    assert len(viewer.history.undo_labels) == 1
    viewer.undo()
    assert viewer.scene == before
    assert not viewer.history.can_undo


def test_set_field_refuses_a_bad_value_leaving_the_scene_and_saying_why(viewer):
    before = viewer.scene
    assert viewer.set_field("render.epsilon", -1) is False
    assert viewer.scene == before
    assert not viewer.history.can_undo
    assert "epsilon" in viewer.status and "\n" not in viewer.status


def test_set_field_camera_fov_moves_the_view_camera_without_an_undo_step(viewer):
    assert viewer.set_field("camera.fov", 35.0) is True
    assert viewer.camera.fov == 35.0
    assert viewer.scene.camera.fov == 35.0
    assert not viewer.history.can_undo


# --- objects, undo and redo --------------------------------------------------------------

def test_add_duplicate_delete_undo_all_returns_the_original_scene(viewer):
    original = viewer.scene
    count = len(original.objects)
    viewer.add_object("sphere")
    assert len(viewer.scene.objects) == count + 1
    viewer.duplicate_selected()
    assert len(viewer.scene.objects) == count + 2
    # the copy is the original moved by DUPLICATE_OFFSET (a translate of its own)
    assert viewer.scene.objects[-1] == Translate(viewer.scene.objects[-2],
                                                 editing.DUPLICATE_OFFSET)
    assert viewer.selection == (count + 1, 0)
    viewer.select((0,))
    viewer.delete_selected()
    assert len(viewer.scene.objects) == count + 1
    assert viewer.selection is None
    for _ in range(3):
        viewer.undo()
    assert viewer.scene == original
    assert not viewer.history.can_undo
    for _ in range(3):
        viewer.redo()
    assert len(viewer.scene.objects) == count + 1
    assert viewer.scene.objects[0] == original.objects[1]


def test_modified_is_false_after_open_true_after_an_edit_false_after_save(viewer, tmp_path):
    assert viewer.modified is False
    viewer.add_object("box")
    assert viewer.modified is True
    viewer.save(tmp_path / "edited.toml")
    assert viewer.modified is False


# --- saving ------------------------------------------------------------------------------

def test_save_without_a_path_refuses_a_bundled_scene_asking_for_save_as(viewer):
    with pytest.raises(MarchlabError, match="Save as"):
        viewer.save()


def test_save_writes_a_file_that_loads_back_equal_to_the_view(viewer, tmp_path):
    viewer.set_field("render.epsilon", 0.004)
    viewer.drag("left", 30, 10)             # the saved camera is the view's
    path = viewer.save(tmp_path / "x.toml")
    assert path == tmp_path / "x.toml"
    assert load_scene(path) == viewer.scene


def test_save_refuses_a_path_not_ending_in_toml(viewer, tmp_path):
    with pytest.raises(MarchlabError, match=r"\.toml"):
        viewer.save(tmp_path / "x.txt")
    assert not (tmp_path / "x.txt").exists()


def test_save_without_a_path_writes_back_to_an_opened_file(scene_file):
    viewer = Viewer(scene_file, SIZE)
    viewer.set_field("render.epsilon", 0.004)
    viewer.save()
    assert load_scene(scene_file).render.epsilon == 0.004
    assert viewer.modified is False


# --- reloading a file changed on disk ----------------------------------------------------

def test_reload_if_changed_reads_a_changed_file_as_an_undoable_step(scene_file):
    viewer = Viewer(scene_file, SIZE)
    changed = editing.set_field(load_scene(scene_file), "render.epsilon", 0.005)
    _rewrite(scene_file, scene_to_toml(changed))
    assert viewer.reload_if_changed() is True
    assert viewer.scene.render.epsilon == 0.005
    assert viewer.modified is False
    viewer.undo()
    assert viewer.scene.render.epsilon == 0.001


def test_reload_if_changed_keeps_the_scene_when_the_file_no_longer_reads(scene_file):
    viewer = Viewer(scene_file, SIZE)
    before = viewer.scene
    text = scene_file.read_text(encoding="utf-8")
    assert "epsilon = 0.001\n" in text
    _rewrite(scene_file, text.replace("epsilon = 0.001\n", "epsilon = -1.0\n"))
    assert viewer.reload_if_changed() is False
    assert viewer.scene == before
    assert viewer.status.startswith("not reloaded") and "\n" not in viewer.status


def test_reload_if_changed_is_false_for_an_unchanged_file(scene_file):
    viewer = Viewer(scene_file, SIZE)
    before = viewer.scene
    assert viewer.reload_if_changed() is False
    assert viewer.scene == before
    assert not viewer.history.can_undo


# --- picking ------------------------------------------------------------------------------

def _primitive_count(scene):
    """How many object ids the scene's objects take (one per primitive)."""
    return sum(len(editing.primitive_ids(scene, (i,))) for i in range(len(scene.objects)))


def test_pick_selects_the_top_level_object_of_the_primitive_clicked(viewer):
    scene = viewer.history.scene
    count = _primitive_count(scene)
    for object_id in range(count):
        viewer.pick(object_id)
        assert viewer.selection == editing.object_path(scene, object_id)
        assert object_id in viewer.selected_ids()
        assert viewer.selected_ids() == editing.primitive_ids(scene, viewer.selection)


def test_pick_of_minus_one_clears_the_selection(viewer):
    viewer.pick(0)
    assert viewer.selection is not None
    viewer.pick(-1)
    assert viewer.selection is None
    assert viewer.selected_ids() == ()


def test_pick_selects_a_nested_objects_top_level_path(viewer):
    viewer.add_object("union")              # a top-level operator of two primitives
    scene = viewer.history.scene
    top = len(scene.objects) - 1
    last = _primitive_count(scene) - 1
    viewer.pick(last)
    assert viewer.selection == (top,)
    assert viewer.selected_ids() == (last - 1, last)


# --- physics -----------------------------------------------------------------------------

@pytest.fixture
def bodies_viewer(clock):
    return Viewer(BODIES_SCENE, SIZE, clock=lambda: clock[0])


def test_a_scene_without_bodies_has_no_playback(viewer):
    assert viewer.playback is None


def test_a_bodies_scene_starts_paused_and_advance_moves_nothing(bodies_viewer):
    playback = bodies_viewer.playback
    assert playback is not None and playback.playing is False
    start = playback.positions().copy()
    bodies_viewer.advance(0.1)
    np.testing.assert_array_equal(playback.positions(), start)


def test_advance_while_playing_moves_the_bodies_and_drawn_scene_shows_them(bodies_viewer):
    playback = bodies_viewer.playback
    start = playback.positions().copy()
    playback.play()
    bodies_viewer.advance(0.1)
    now = playback.positions()
    # balls dropped from rest fall ~g t^2 / 2 = 4.9 cm in 0.1 s: well over a millimetre
    assert np.max(np.linalg.norm(now - start, axis=1)) > 1e-3
    drawn = bodies_viewer.drawn_scene()
    assert drawn.bodies == ()
    assert drawn == rendered_scene(scene_at(bodies_viewer.scene, now))


def _grab_centre(viewer, body=0):
    centre = viewer.playback.positions()[body]
    x, y, _ = project(viewer.camera, [centre], *viewer.size)[0]
    return centre, x, y


def test_editing_the_physics_settings_restarts_the_playback_with_them(bodies_viewer):
    bodies_viewer.playback.play()
    bodies_viewer.advance(0.1)
    assert bodies_viewer.set_field("physics.restitution", 0.9)
    assert bodies_viewer.playback.settings.restitution == 0.9
    assert bodies_viewer.playback.time == 0.0
    bodies_viewer.undo()
    assert bodies_viewer.playback.settings.restitution != 0.9


def test_grab_ball_on_a_bodys_centre_takes_hold_of_it(bodies_viewer):
    _, x, y = _grab_centre(bodies_viewer, 0)
    assert bodies_viewer.grab_ball(x, y) is True
    assert bodies_viewer.playback._held == 0


def test_drag_ball_puts_the_body_on_the_ray_through_the_new_pixel_within_1e_6(bodies_viewer):
    centre, x, y = _grab_centre(bodies_viewer, 0)
    assert bodies_viewer.grab_ball(x, y)
    bodies_viewer.drag_ball(x + 40, y - 30)
    moved = bodies_viewer.playback.positions()[0]
    assert np.linalg.norm(moved - centre) > 0.1
    origin, direction = pixel_ray(bodies_viewer.camera, x + 40, y - 30, *bodies_viewer.size)
    offset = moved - origin
    distance_to_ray = np.linalg.norm(offset - (offset @ direction) * direction)
    assert distance_to_ray < 1e-6
    bodies_viewer.release_ball()
    assert bodies_viewer.playback._held is None


def test_grab_ball_on_empty_sky_returns_false(bodies_viewer):
    assert bodies_viewer.grab_ball(SIZE[0] / 2, 1.0) is False   # top row: sky above the balls
    assert bodies_viewer.playback._held is None


def test_a_press_on_a_bodys_centre_takes_hold_of_the_ball(bodies_viewer):
    x, y, _ = project(bodies_viewer.camera, [bodies_viewer.playback.positions()[0]], *SIZE)[0]
    assert bodies_viewer.press(x, y) == "ball" and bodies_viewer.holding == "ball"
    bodies_viewer.let_go()
    assert bodies_viewer.holding is None


# --- dragging lights and objects in the view ---------------------------------------------

def _marker(viewer, index=0):
    return next((x, y) for i, x, y in viewer.light_markers() if i == index)


def _forward_depth(viewer, point):
    forward = camera_basis(viewer.camera)[0]
    return float((np.asarray(point) - np.asarray(viewer.camera.position)) @ forward)


def test_light_markers_are_where_the_lights_project(viewer):
    for i, x, y in viewer.light_markers():
        expected = project(viewer.camera, [viewer.scene.lights[i].position], *SIZE)[0]
        assert (x, y) == pytest.approx(tuple(expected[:2]), abs=1e-9)


def test_a_drag_from_a_lights_marker_keeps_the_light_under_the_cursor_within_1e_6_px(viewer):
    x, y = _marker(viewer)
    before = viewer.scene.lights[0].position
    assert viewer.press(x + 3, y - 2) == "light"            # within the marker's radius
    viewer.move_to(x + 43, y + 23)
    after = viewer.scene.lights[0].position
    moved = project(viewer.camera, [after], *SIZE)[0]
    assert tuple(moved[:2]) == pytest.approx((x + 40, y + 25), abs=1e-6)
    # It moved in the plane facing the camera: its depth along the view is unchanged.
    assert _forward_depth(viewer, after) == pytest.approx(_forward_depth(viewer, before),
                                                          abs=1e-9)


def test_a_whole_drag_is_one_undo_step_and_the_next_drag_another(viewer):
    x, y = _marker(viewer)
    start = viewer.scene.lights[0].position
    viewer.press(x, y)
    for k in range(1, 6):
        viewer.move_to(x + 10 * k, y)
    viewer.let_go()
    first = viewer.scene.lights[0].position
    x, y = _marker(viewer)
    viewer.press(x, y)
    viewer.move_to(x, y + 30)
    viewer.let_go()
    viewer.undo()
    assert viewer.scene.lights[0].position == pytest.approx(first, abs=1e-12)
    viewer.undo()
    assert viewer.scene.lights[0].position == pytest.approx(start, abs=1e-12)


def test_shift_drag_moves_the_selected_object_so_its_centre_follows_the_cursor(viewer):
    viewer.select((1,))                          # a sphere inside a translate
    centre = editing.get_field(viewer.scene, "objects[1].position")
    x, y, _ = project(viewer.camera, [centre], *SIZE)[0]
    assert viewer.press(x, y, shift=True) == "object"
    viewer.move_to(x - 30, y + 12)
    viewer.let_go()
    moved = editing.get_field(viewer.scene, "objects[1].position")
    assert tuple(project(viewer.camera, [moved], *SIZE)[0][:2]) == \
        pytest.approx((x - 30, y + 12), abs=1e-6)
    viewer.undo()
    assert editing.get_field(viewer.scene, "objects[1].position") == pytest.approx(centre)


def test_shift_drag_of_an_object_without_a_position_gives_it_one(viewer):
    viewer.select((0,))                          # the floor plane: no translate
    assert editing.get_field(viewer.scene, "objects[0].position") is None
    assert viewer.press(320, 400, shift=True) == "object"
    viewer.move_to(320, 380)
    assert editing.get_field(viewer.scene, "objects[0].position") is not None


def test_a_press_on_nothing_holds_nothing_so_the_drag_orbits(viewer):
    assert viewer.press(SIZE[0] / 2, 1.0) is None              # sky, no marker, no shift
    assert viewer.press(SIZE[0] / 2, 1.0, shift=True) is None  # shift, but nothing selected
    viewer.move_to(10, 10)                                     # carries nothing
    assert not viewer.modified


# --- checking against the reference ------------------------------------------------------

@pytest.fixture
def checked(viewer):
    """The view checked against a frame the NumPy reference itself rendered (32 x 24)."""
    from marchlab.render import render
    frame = render(viewer.scene, 32, 24, backend="numpy", path_labels=True)
    assert viewer.check_against_reference(frame, background=False) is None
    return viewer


def test_check_against_the_references_own_frame_gives_identical_images(checked):
    check = checked.check
    for image in (check.reference, check.gpu, check.difference):
        assert image.shape == (24, 32, 3)
    np.testing.assert_array_equal(check.reference, check.gpu)
    assert not check.difference.any()
    assert checked.check_progress is None


def test_check_against_the_references_own_frame_passes_every_gate(checked):
    assert checked.check.failures == []


def test_the_check_holds_opencl_against_the_reference_too_where_it_runs(checked):
    from required_backends import need_backend
    need_backend("opencl")
    check = checked.check
    assert check.opencl.shape == (24, 32, 3)
    assert check.opencl_failures == []


def test_a_scene_made_in_python_opens_has_no_file_and_saves_only_under_a_name(tmp_path):
    scene = load_scene("csg")
    viewer = Viewer(scene, SIZE)
    assert viewer.scene == scene and viewer.path is None
    assert viewer.reload_if_changed() is False
    with pytest.raises(MarchlabError, match="has no file yet"):
        viewer.save()
    saved = viewer.save(tmp_path / "mine.toml")
    assert load_scene(saved) == viewer.scene and viewer.path == saved
