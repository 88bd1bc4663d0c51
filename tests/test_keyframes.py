"""Animated scenes: keyframed fields, the camera orbit, and `marchlab animate`.

scene_model/keyframes.py and timeline.py: a field's value between keys is interpolated
linearly or by smoothstep, the orbit turns the camera about the vertical through what it looks
at, and `scene_at_time` is the still a renderer draws at t. Closed forms: values at the keys,
half-way values, the orbit's distance, height and angle; the animation's frames are exactly the
renders of those stills.
"""

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from marchlab.commands import render_frames
from marchlab.render import render
from scene_model.errors import SceneError
from scene_model.keyframes import Keyframes, Orbit, keyframe_value, orbit_position
from scene_model.scenefile import load_scene, scene_from_dict, scene_to_toml
from scene_model.timeline import check_keyframes, scene_at_time
from tests.cli_helpers import run_cli


def keys(**fields):
    return Keyframes(**dict(dict(field="camera.fov", times=(1.0, 3.0, 4.0),
                                 values=(40.0, 60.0, 50.0)), **fields))


@pytest.mark.parametrize("interpolation", ["linear", "smoothstep"])
def test_the_value_at_each_key_time_is_that_key_and_outside_the_keys_it_holds(interpolation):
    frames = keys(interpolation=interpolation)
    for time, value in zip(frames.times, frames.values):
        assert keyframe_value(frames, time) == value
    assert keyframe_value(frames, 0.0) == 40.0 and keyframe_value(frames, 99.0) == 50.0


def test_half_way_the_value_is_the_mean_for_both_and_a_quarter_way_differs():
    """At u = 1/2 both give the mean (w = 1/2); at u = 1/4 linear gives w = 1/4 and
    smoothstep 3/16 - 2/64 = 5/32 (1e-12)."""
    linear, smooth = keys(), keys(interpolation="smoothstep")
    assert keyframe_value(linear, 2.0) == pytest.approx(50.0, abs=1e-12)
    assert keyframe_value(smooth, 2.0) == pytest.approx(50.0, abs=1e-12)
    assert keyframe_value(linear, 1.5) == pytest.approx(40 + 20 / 4, abs=1e-12)
    assert keyframe_value(smooth, 1.5) == pytest.approx(40 + 20 * 5 / 32, abs=1e-12)


def test_smoothstep_is_at_rest_at_the_keys():
    smooth = keys(interpolation="smoothstep")
    for time in (1.0, 3.0):
        slope = (keyframe_value(smooth, time + 1e-6) - keyframe_value(smooth, time - 1e-6))
        assert abs(slope) / 2e-6 < 1e-3


def test_vector_keys_interpolate_each_component_and_loops_repeat():
    frames = Keyframes(field="camera.position", times=(0.0, 2.0),
                       vectors=((0.0, 1.0, 5.0), (4.0, 3.0, 1.0)), loop=True)
    assert keyframe_value(frames, 0.5) == pytest.approx((1.0, 1.5, 4.0), abs=1e-12)
    assert keyframe_value(frames, 4.5) == pytest.approx((1.0, 1.5, 4.0), abs=1e-12)


def test_the_orbit_keeps_the_distance_and_height_and_turns_by_two_pi_t_over_period():
    """Camera at (3, 2, 4) looking at (1, 0.5, 0), up +y, period 8 s: at t = 2 it has turned
    90 degrees (counter-clockwise seen from above, about +y) and at t = 8 it is back (1e-12)."""
    look, up, start = np.array([1.0, 0.5, 0.0]), (0.0, 1.0, 0.0), np.array([3.0, 2.0, 4.0])
    orbit = Orbit(period=8.0)
    quarter = np.array(orbit_position(start, look, up, orbit, 2.0))
    arm, turned = start - look, quarter - look
    assert turned[1] == pytest.approx(arm[1], abs=1e-12)
    assert np.hypot(turned[0], turned[2]) == pytest.approx(np.hypot(arm[0], arm[2]), abs=1e-12)
    np.testing.assert_allclose(turned[[0, 2]], (arm[2], -arm[0]), atol=1e-12)
    np.testing.assert_allclose(orbit_position(start, look, up, orbit, 8.0), start, atol=1e-12)


def test_the_still_at_a_time_sets_every_keyed_field_and_drops_the_animation():
    scene = dataclasses.replace(
        load_scene("classroom"), orbit=Orbit(period=4.0),
        keyframes=(keys(), Keyframes(field="objects[1].radius", times=(0.0, 1.0),
                                     values=(0.5, 1.5)),
                   Keyframes(field="render.max_steps", times=(0.0, 1.0),
                             values=(10.0, 21.0))))
    still = scene_at_time(scene, 0.5)
    assert still.camera.fov == 40.0
    assert still.objects[1].child.radius == pytest.approx(1.0, abs=1e-12)
    assert still.render.max_steps == 16            # 15.5 to the nearest integer (even: 16)
    assert still.keyframes == () and still.orbit is None
    assert still.camera.position != scene.camera.position


@pytest.mark.parametrize("fields, blamed, words", [
    (dict(field="objects[9].radius"), "field", "names no field"),
    (dict(field="camera.position"), "field", "is not a number"),
    (dict(field="objects[1].radius", values=(0.5, -1.0, 1.0)), "values", "must be positive"),
])
def test_bad_keyframes_are_refused_in_one_line_naming_the_entry(fields, blamed, words):
    scene = dataclasses.replace(load_scene("classroom"), keyframes=(keys(**fields),))
    with pytest.raises(SceneError) as error:
        check_keyframes(scene)
    assert f"keyframes[0].{blamed}" in str(error.value) and words in str(error.value)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("fields, words", [
    (dict(times=[1.0, 1.0], values=[1.0, 2.0]), "must increase"),
    (dict(times=[0.0, 1.0], values=[1.0]), "one value per key time"),
    (dict(times=[0.0, 1.0]), "give the key values"),
    (dict(times=[0.0], values=[1.0], loop=True), "at least two"),
])
def test_bad_keys_in_a_file_are_refused_by_the_format(fields, words):
    with pytest.raises(SceneError, match=words):
        scene_from_dict({"keyframes": [dict(field="camera.fov", **fields)]})


def test_keyframes_and_orbit_round_trip_through_toml():
    scene = dataclasses.replace(load_scene("classroom"), orbit=Orbit(period=-3.0, start=1.0),
                                keyframes=(keys(interpolation="smoothstep", loop=True),))
    assert scene_from_dict(tomllib.loads(scene_to_toml(scene))) == scene


def test_each_frame_of_an_animation_is_the_render_of_the_still_at_its_time():
    """`render_frames` (what animate and simulate use) gives, frame by frame, exactly the
    numpy render of `scene_at_time` (bit for bit)."""
    scene = dataclasses.replace(load_scene("classroom"), orbit=Orbit(period=2.0),
                                keyframes=(keys(times=(0.0, 1.0), values=(35.0, 70.0),
                                                interpolation="smoothstep"),))
    times = np.array([0.0, 0.4, 0.9])
    frames = render_frames(scene, np.zeros((3, 0, 3)), 40, 30, "numpy", times=times)
    for frame, time in zip(frames, times):
        expected = render(scene_at_time(scene, time), 40, 30, backend="numpy").image("color")
        assert np.array_equal(frame, expected)
    assert not np.array_equal(frames[0], frames[-1])


def test_animate_writes_one_frame_per_step_of_the_frame_rate(tmp_path, capsys):
    path = tmp_path / "turn.toml"
    path.write_text(scene_to_toml(dataclasses.replace(load_scene("classroom"),
                                                      orbit=Orbit(period=2.0))))
    out = tmp_path / "turn.gif"
    code, _, err = run_cli(capsys, "animate", path, "-o", out, "--seconds", "0.5", "--fps", "6",
                           "--size", "32x24", "--backend", "numpy")
    assert code == 0, err
    import imageio.v3 as iio
    frames = iio.imread(out, index=None)
    assert frames.shape[:3] == (3, 24, 32)
    assert not np.array_equal(frames[0], frames[-1])


def test_animate_refuses_a_keyframe_of_no_field_in_one_line_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(scene_to_toml(dataclasses.replace(
        load_scene("classroom"), keyframes=(keys(field="objects[7].radius"),))))
    out = tmp_path / "bad.gif"
    code, _, err = run_cli(capsys, "animate", path, "-o", out, "--seconds", "0.2", "--size",
                           "16x12", "--backend", "numpy")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "keyframes[0].field" in lines[0]
    assert not out.exists()


def test_a_physics_scene_animates_its_bodies_and_keyframes_through_the_same_path(tmp_path,
                                                                               capsys):
    """bounce with its camera's fov keyframed: animate steps the bodies as simulate does and
    renders each frame with the keyframed still."""
    scene = load_scene("bounce")
    path = tmp_path / "zoom.toml"
    path.write_text(scene_to_toml(dataclasses.replace(scene, keyframes=(
        Keyframes(field="camera.fov", times=(0.0, 0.3), values=(scene.camera.fov, 20.0)),))))
    out, table = tmp_path / "zoom.gif", tmp_path / "zoom.csv"
    code, _, err = run_cli(capsys, "animate", path, "-o", out, "--csv", table, "--seconds",
                           "0.3", "--fps", "10", "--size", "32x24", "--backend", "numpy")
    assert code == 0, err
    rows = table.read_text().splitlines()
    assert len(rows) == 1 + 3 * len(scene.bodies)
    assert math.isclose(float(rows[-1].split(",")[0]), 0.2, rel_tol=1e-9)


# --- A morph's t, keyframed (scene_model/scenes/morph.toml) ---------------------------------

def test_the_morph_scene_sweeps_the_middle_morphs_t_from_sphere_to_box_and_back():
    """Its keys: t = 0, 1, 0 at 0, 2, 4 s, smoothstep, looping. The shorthand position puts
    the morph under a translate, which the path objects[2].t looks through."""
    scene = check_keyframes(load_scene("morph"))
    for time, t in [(0.0, 0.0), (1.0, 0.5), (2.0, 1.0), (3.0, 0.5), (4.5, 5 / 32)]:
        morph = scene_at_time(scene, time).objects[2].child
        assert morph.kind == "morph" and morph.t == pytest.approx(t, abs=1e-12)


def test_a_keyframed_morph_renders_as_the_scene_with_that_t_set():
    """At 2 s the middle morph is the box: the frame equals the render of the file with
    objects[2].t = 1 (bit for bit), and the middle object shows the box's id, not the
    sphere's."""
    scene = load_scene("morph")
    frame = render_frames(scene, np.zeros((1, 0, 3)), 40, 30, "numpy", times=np.array([2.0]))[0]
    still = render(load_scene("morph", ["objects[2].t=1.0"]), 40, 30, backend="numpy")
    assert np.array_equal(frame, still.image("color"))
    written = render(scene, 40, 30, backend="numpy")            # t = 0.5: the sphere's id
    middle = written.object_id[:, 15:25]
    assert 3 in middle and 4 not in middle
    assert 4 in still.object_id[:, 15:25] and 3 not in still.object_id[:, 15:25]


def test_a_morph_key_outside_0_to_1_is_refused_in_one_line():
    scene = dataclasses.replace(load_scene("morph"), keyframes=(
        Keyframes(field="objects[2].t", times=(0.0, 1.0), values=(0.0, 1.5)),))
    with pytest.raises(SceneError) as error:
        check_keyframes(scene)
    message = str(error.value)
    assert message.startswith("keyframes[0].values: key 1: ") and "\n" not in message
    assert "between 0 and 1 (got 1.5)" in message
