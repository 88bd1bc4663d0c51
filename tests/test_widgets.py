"""``marchlab.widgets.View``, the notebook view, driven with synthetic jupyter-rfb events (no
browser): its mouse moves the camera as the window's does, its picture is the gpu backend's
frame, its controls set scene fields, and saved without a kernel it leaves a PNG."""

from __future__ import annotations

import base64
import io
import math

import numpy as np
import pytest

from marchlab import camera_control
from marchlab.render import render
from required_backends import need_backend
from scene_model.errors import MarchlabError, SceneError
from scene_model.scenefile import load_scene

pytest.importorskip("jupyter_rfb", reason="the notebook view needs the [lessons] extra")
SIZE = (96, 72)


@pytest.fixture
def view():
    need_backend("gpu")
    from marchlab.widgets import View
    return View("classroom", controls=["render.epsilon", "materials.red.shininess",
                                       "render.shadows", "materials.red.color"], size=SIZE,
                markers=False)


def _drag(view, button, start, end):
    canvas = view.canvas
    canvas.handle_event({"type": "pointer_down", "x": start[0], "y": start[1],
                         "button": button, "modifiers": ()})
    canvas.handle_event({"type": "pointer_move", "x": end[0], "y": end[1],
                         "buttons": (button,), "modifiers": ()})
    canvas.handle_event({"type": "pointer_up", "x": end[0], "y": end[1], "button": button,
                         "modifiers": ()})


def _azimuth(camera) -> float:
    offset = np.subtract(camera.position, camera.look_at)
    return math.degrees(math.atan2(offset[0], offset[2]))


def test_a_left_drag_of_n_pixels_orbits_by_orbit_degrees_times_n_over_the_height(view):
    before = view.viewer.camera
    _drag(view, 1, (30, 40), (48, 40))                      # 18 px of a 72 px view
    turned = _azimuth(view.viewer.camera) - _azimuth(before)
    assert turned == pytest.approx(-camera_control.ORBIT_DEGREES * 18 / SIZE[1], abs=1e-9)


def test_a_drag_whose_last_moves_arrive_only_as_the_release_still_turns_all_the_way(view):
    # jupyter-rfb throttles pointer moves: the browser may send a quick drag's end only as
    # the release's position (CI saw 27 of 30 px turned).
    before = view.viewer.camera
    canvas = view.canvas
    canvas.handle_event({"type": "pointer_down", "x": 30, "y": 40, "button": 1,
                         "modifiers": ()})
    canvas.handle_event({"type": "pointer_move", "x": 39, "y": 40, "buttons": (1,),
                         "modifiers": ()})
    canvas.handle_event({"type": "pointer_up", "x": 48, "y": 40, "button": 1,
                         "modifiers": ()})
    turned = _azimuth(view.viewer.camera) - _azimuth(before)
    assert turned == pytest.approx(-camera_control.ORBIT_DEGREES * 18 / SIZE[1], abs=1e-9)


def test_a_right_drag_pans_as_the_window_does(view):
    before = view.viewer.camera
    _drag(view, 2, (30, 40), (20, 52))
    expected = camera_control.drag(before, "right", -10, 12, SIZE[1])
    np.testing.assert_allclose(view.viewer.camera.position, expected.position, atol=1e-12)
    np.testing.assert_allclose(view.viewer.camera.look_at, expected.look_at, atol=1e-12)


def test_one_wheel_notch_toward_the_scene_zooms_by_zoom_per_click(view):
    camera = view.viewer.camera
    distance = lambda c: np.linalg.norm(np.subtract(c.position, c.look_at))
    before = distance(camera)
    view.canvas.handle_event({"type": "wheel", "x": 40, "y": 30, "dx": 0, "dy": -100,
                              "modifiers": ()})
    assert distance(view.viewer.camera) == pytest.approx(
        before * camera_control.ZOOM_PER_CLICK, rel=1e-12)


def test_a_w_key_flies_forward_one_key_press_worth(view):
    from marchlab.widgets import KEY_SECONDS
    before = view.viewer.camera
    view.canvas.handle_event({"type": "key_down", "key": "w", "modifiers": ()})
    expected = camera_control.fly_keys(before, {"W"}, KEY_SECONDS)
    np.testing.assert_allclose(view.viewer.camera.position, expected.position, atol=1e-12)


def test_the_frame_at_rest_equals_marchlab_render_within_one_level(view):
    _drag(view, 1, (30, 40), (40, 44))
    view.viewer._last_motion = -math.inf                      # the motion has settled
    expected = render(view.viewer.drawn_scene(), *SIZE, backend="gpu").image()
    assert np.abs(view.image().astype(int) - expected).max() <= 1


def test_while_moving_the_frame_is_drawn_at_the_moving_scale(view):
    view.canvas.handle_event({"type": "wheel", "x": 40, "y": 30, "dx": 0, "dy": -100,
                              "modifiers": ()})
    image = view.image()
    assert image.shape[:2] == tuple(reversed(view.viewer.render_size()))
    assert image.shape[0] < SIZE[1]


def test_a_control_sets_its_field_and_the_next_frame_shows_it(view):
    shininess = view.controls[1]
    shininess.value = 5.0
    assert view.viewer.scene.materials["red"].shininess == pytest.approx(5.0)
    expected = render(view.viewer.drawn_scene(), *SIZE, backend="gpu").image()
    assert np.abs(view.image().astype(int) - expected).max() <= 1
    unedited = render(load_scene("classroom"), *SIZE, backend="gpu").image()
    assert np.abs(view.image().astype(int) - unedited).max() > 1


def test_choice_and_colour_controls_set_their_fields(view):
    view.controls[2].value = "soft"
    view.controls[3].value = "#00ff00"
    assert view.viewer.scene.render.shadows == "soft"
    assert view.viewer.scene.materials["red"].color == (0.0, 1.0, 0.0)


def test_glass_controls_slide_the_material_and_the_tree_and_a_share_spans_0_to_1():
    """Lesson 08's sliders: a material's index and transparency, the tree's depth and the
    Fresnel model; a field between 0 and 1 (transparency, kr) slides over exactly that."""
    need_backend("gpu")
    from marchlab.widgets import View
    view = View("glass", controls=["materials.clear.ior", "materials.clear.transparency",
                                   "render.reflection_depth", "render.fresnel",
                                   "materials.mirror.kr"], size=SIZE, markers=False)
    ior, transparency, depth, fresnel, kr = view.controls[:5]    # then the shading mode
    assert [(c.min, c.max) for c in (ior, transparency, kr)] == [(1.0, 4.0), (0.0, 1.0),
                                                                 (0.0, 1.0)]
    ior.value, transparency.value, depth.value, fresnel.value = 1.0, 0.5, 2, "schlick"
    scene = view.viewer.scene
    assert (scene.materials["clear"].ior, scene.materials["clear"].transparency) == (1.0, 0.5)
    assert (scene.render.reflection_depth, scene.render.fresnel) == (2, "schlick")


def test_a_click_selects_the_object_under_the_cursor(view):
    frame = render(load_scene("classroom"), *SIZE, backend="gpu")
    view.image()
    rows, cols = np.nonzero(frame.object_id > 0)              # an object other than the floor
    y, x = rows[len(rows) // 2], cols[len(cols) // 2]
    view.canvas.handle_event({"type": "pointer_down", "x": x + 0.5, "y": y + 0.5,
                              "button": 1, "modifiers": ()})
    view.canvas.handle_event({"type": "pointer_up", "x": x + 0.5, "y": y + 0.5, "button": 1,
                              "modifiers": ()})
    from scene_model.editing import primitive_ids
    assert view.viewer.selection is not None
    assert frame.object_id[y, x] in primitive_ids(view.viewer.scene, view.viewer.selection)


def test_the_static_fallback_is_a_png_of_the_first_frame(view):
    from PIL import Image
    bundle = view._repr_mimebundle_()
    data = bundle[0] if isinstance(bundle, tuple) else bundle
    assert "application/vnd.jupyter.widget-view+json" in data
    png = np.asarray(Image.open(io.BytesIO(base64.b64decode(data["image/png"]))))
    expected = render(load_scene("classroom"), *SIZE, backend="gpu").image()
    assert np.abs(png.astype(int) - expected).max() <= 1


def test_check_against_the_reference_passes_every_gate_and_shows_the_pictures(view):
    result = view.check()
    assert result.failures == [] and result.reference.shape == (SIZE[1], SIZE[0], 3)
    assert view.verdict.value.startswith("gpu: every gate passes")
    names = [box.children[0].value for box in view.check_images.children]
    assert names[:3] == ["NumPy reference", "gpu", "difference x32"]


def test_lights_are_marked_and_a_drag_from_a_mark_moves_the_light():
    need_backend("gpu")
    from marchlab.light_marks import MARKER_COLOR
    from marchlab.widgets import View
    view = View("lights", size=(192, 144))
    index, x, y = next((i, x, y) for i, x, y in view.viewer.light_markers()
                       if 0 <= x < 192 and 0 <= y < 144)        # a light inside the view
    image = view.image()
    assert (image[int(y), int(x)] == MARKER_COLOR).all()
    _drag(view, 1, (x, y), (x - 20, y + 10))
    from scene_model.camera import project
    moved = project(view.viewer.camera, [view.viewer.scene.lights[index].position], 192, 144)
    assert tuple(moved[0][:2]) == pytest.approx((x - 20, y + 10), abs=1e-6)


@pytest.mark.parametrize("path", ["render.nosuch", "camera.position"])
def test_a_control_for_a_field_that_cannot_have_one_is_refused_naming_it(path):
    need_backend("gpu")
    from marchlab.widgets import View
    with pytest.raises((MarchlabError, SceneError)) as caught:
        View("classroom", controls=[path], size=SIZE)
    assert path.rsplit(".", 1)[-1] in str(caught.value)


def test_a_saved_notebook_holds_one_output_for_a_view_with_a_png_of_its_first_frame(tmp_path):
    need_backend("gpu")
    nbformat = pytest.importorskip("nbformat")
    from nbclient import NotebookClient
    from PIL import Image
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(
        'from marchlab.widgets import View\nView("csg", size=(96, 72), markers=False)')]
    NotebookClient(notebook, timeout=120, kernel_name="python3").execute()
    outputs = notebook.cells[0].outputs
    assert len(outputs) == 1, [o.get("data", {}).get("text/plain") for o in outputs]
    png = base64.b64decode(outputs[0]["data"]["image/png"])
    expected = render(load_scene("csg"), 96, 72, backend="gpu").image()
    assert np.abs(np.asarray(Image.open(io.BytesIO(png))).astype(int) - expected).max() <= 1


# --- the physics view ------------------------------------------------------------------------

@pytest.fixture
def physics_view():
    need_backend("gpu")
    from marchlab.widgets import PhysicsView
    return PhysicsView("bounce", size=SIZE, markers=False)


def test_a_paused_physics_view_takes_one_fixed_step_per_step_press(physics_view):
    playback = physics_view.viewer.playback
    physics_view.step_button.click()
    assert playback.steps == 1 and playback.time == pytest.approx(playback.settings.dt)
    physics_view.tick(0.5)                                   # paused: time does not pass
    assert playback.steps == 1


def test_playing_advances_whole_fixed_steps_of_the_wall_time_and_draws_the_bodies_there(
        physics_view):
    playback = physics_view.viewer.playback
    physics_view.play_button.click()
    assert playback.playing and physics_view.play_button.description == "Pause"
    physics_view.tick(0.1)
    dt = playback.settings.dt
    assert playback.steps == int(0.1 / dt + 1e-9) and playback.time == pytest.approx(
        playback.steps * dt)
    expected = render(physics_view.viewer.drawn_scene(), *SIZE, backend="gpu").image()
    physics_view.viewer._last_motion = -math.inf
    assert np.abs(physics_view.image().astype(int) - expected).max() <= 1
    physics_view.play_button.click()
    assert not playback.playing


def test_the_sliders_set_restitution_friction_and_gravity_and_reset_puts_them_back(
        physics_view):
    playback = physics_view.viewer.playback
    physics_view.restitution.value = 0.3
    physics_view.friction.value = 0.6
    physics_view.gravity.value = -4.0
    assert playback.settings.restitution == pytest.approx(0.3)
    assert playback.settings.friction == pytest.approx(0.6)
    assert playback.settings.gravity[1] == pytest.approx(-4.0)
    physics_view.reset_button.click()
    scene_settings = load_scene("bounce").physics
    assert physics_view.restitution.value == pytest.approx(scene_settings.restitution)
    assert playback.time == 0.0


def test_kick_changes_the_velocities_and_no_time_passes(physics_view):
    playback = physics_view.viewer.playback
    before = playback.world.velocity.copy()
    physics_view.kick_button.click()
    assert playback.time == 0.0
    assert not np.allclose(playback.world.velocity, before)


def test_the_energy_sparkline_spans_the_picture_from_lowest_to_highest():
    from marchlab.widgets import sparkline
    image = sparkline(np.array([0.0, 1.0, 0.5]), size=(30, 10))
    inked = np.nonzero((image != 255).any(axis=-1))
    assert inked[1].min() == 0 and inked[1].max() == 29      # across the whole width
    assert inked[0].min() == 0 and inked[0].max() == 9       # from the top to the bottom


def test_a_physics_view_of_a_scene_without_bodies_is_refused_in_one_line():
    need_backend("gpu")
    from marchlab.widgets import PhysicsView
    with pytest.raises(MarchlabError, match="needs a scene with"):
        PhysicsView("csg", size=SIZE)


def test_every_view_offers_the_shading_mode_and_the_backends_that_run_here(view):
    from marchlab.render import MESH_BACKENDS, BACKENDS, backend_problem
    assert view.controls[-1].description == "shading"
    view.controls[-1].value = "normals"
    assert view.viewer.scene.render.shading == "normals"
    assert list(view.backend.options) == [b for b in BACKENDS if backend_problem(b) is None
                                          and b not in MESH_BACKENDS]


def test_flipping_the_backend_draws_the_same_view_with_the_reference(view):
    view.backend.value = "numpy"
    view.viewer._last_motion = -math.inf
    expected = render(view.viewer.drawn_scene(), *SIZE, backend="numpy").image()
    np.testing.assert_array_equal(view.image(), expected)
    assert view.canvas.frame.backend == "numpy"


def test_a_mesh_scene_is_drawn_by_the_raster_pipeline_and_checked_against_the_rasteriser():
    need_backend("raster")
    from marchlab.render import MESH_BACKENDS
    from marchlab.widgets import View
    view = View("meshes", size=SIZE, markers=False)
    assert view.canvas.backend == "raster"
    assert set(view.backend.options) <= set(MESH_BACKENDS)
    view.viewer._last_motion = -math.inf
    expected = render(view.viewer.drawn_scene(), *SIZE, backend="raster").image()
    np.testing.assert_array_equal(view.image(), expected)
    result = view.check()
    assert result.reference_backend == "numpy-raster" and result.failures == []
