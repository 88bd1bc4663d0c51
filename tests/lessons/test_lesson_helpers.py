"""marchlab.lessons, the plumbing the lesson notebooks import instead of copying.

Each helper is checked for what a lesson relies on: the source shown is the real source, a
slice holds the field's values, a drawing puts the surface where the field is 0, a variation
of a scene changes only what it names, a timing keeps the fastest run, and a sweep finds no
artefact at the converged setting and some where rays run out of steps.
"""

from __future__ import annotations

import inspect
import textwrap
import types

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib", reason="the lessons extra is not installed")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import marchlab  # noqa: E402
from marchlab import lessons  # noqa: E402
from reference_cpu import sdf as S  # noqa: E402
from reference_cpu.render import Tracer  # noqa: E402
from scene_model.builder import sphere  # noqa: E402
from scene_model.frame import Frame  # noqa: E402

WIDTH, HEIGHT = 32, 24


@pytest.fixture(scope="module")
def classroom():
    """The classroom scene with shadows and mirrors off: only the primary march is measured."""
    return lessons.with_settings(marchlab.load_scene("classroom"), shadows="none",
                                 reflection_depth=0)


def test_show_source_displays_the_exact_source_of_each_function(monkeypatch):
    display = pytest.importorskip("IPython.display")
    shown = []
    monkeypatch.setattr(display, "display", shown.append)
    lessons.show_source(S.sdf_sphere, Tracer.lit_color)
    assert shown[0].data == inspect.getsource(S.sdf_sphere)
    method = inspect.getsource(Tracer.lit_color)          # indented in its class
    assert shown[1].data == textwrap.dedent(method) != method
    assert shown[1].data.startswith("def lit_color(self")


def test_distance_field_is_the_union_of_its_nodes_within_1e_12():
    f = lessons.distance_field(sphere(1.0).at(-2, 0, 0), sphere(0.5).at(2, 0, 0))
    p = np.random.default_rng(0).uniform(-4, 4, (500, 3))
    exact = np.minimum(np.linalg.norm(p - [-2, 0, 0], axis=1) - 1.0,
                       np.linalg.norm(p - [2, 0, 0], axis=1) - 0.5)
    np.testing.assert_allclose(f(p), exact, rtol=0, atol=1e-12)


def test_slice_z0_holds_the_field_at_the_grid_points_of_the_plane_z0():
    x, y, d = lessons.slice_z0(lessons.distance_field(sphere(1.0)), xlim=(-3, 3),
                               ylim=(-2, 1), n=61)
    assert x.shape == y.shape == d.shape == (61, 61)
    assert x[0, 0] == -3 and x[0, -1] == 3 and y[0, 0] == -2 and y[-1, 0] == 1
    np.testing.assert_allclose(d, np.hypot(x, y) - 1.0, rtol=0, atol=1e-12)


def test_draw_field_draws_the_surface_at_zero_and_level_lines_at_multiples_of_spacing():
    x, y, d = lessons.slice_z0(lessons.distance_field(sphere(1.0)), n=201)
    fig, ax = plt.subplots()
    try:
        filled = lessons.draw_field(ax, x, y, d, spacing=0.25, title="unit sphere")
        _, lines, surface = ax.collections
        assert filled is ax.collections[0] and ax.get_title() == "unit sphere"
        # d runs from -1 (the centre) to 1.5 (the corners of the default slice).
        np.testing.assert_allclose(lines.levels, [-1.0, -0.75, -0.5, -0.25, 0.25, 0.5, 0.75,
                                                  1.0, 1.25, 1.5])
        assert list(surface.levels) == [0]
        # The grid step is 0.02: the zero line runs within that of the unit circle.
        vertices = np.concatenate(surface.allsegs[0])
        assert np.abs(np.hypot(vertices[:, 0], vertices[:, 1]) - 1).max() < 0.02
    finally:
        plt.close(fig)


def test_with_settings_and_with_materials_change_only_what_they_name(classroom):
    changed = lessons.with_settings(classroom, epsilon=0.01, max_steps=64)
    assert (changed.render.epsilon, changed.render.max_steps) == (0.01, 64)
    assert changed.render.shading == classroom.render.shading
    assert changed.objects == classroom.objects and classroom.render.epsilon != 0.01

    matte = lessons.with_materials(classroom, ks=0.0, kr=0.0)
    for name, material in matte.materials.items():
        assert (material.ks, material.kr) == (0.0, 0.0)
        assert material.color == classroom.materials[name].color
    sharper = lessons.with_materials(classroom, shininess=lambda m: 4 * m.shininess)
    for name, material in sharper.materials.items():
        assert material.shininess == 4 * classroom.materials[name].shininess
    with pytest.raises(TypeError):
        lessons.with_settings(classroom, no_such_setting=1)


def test_best_time_returns_the_last_result_and_the_fastest_of_its_repeats(monkeypatch):
    clock = iter([0.0, 5.0, 10.0, 12.0, 20.0, 29.0])     # runs of 5, 2 and 9 seconds
    monkeypatch.setattr(lessons, "time", types.SimpleNamespace(perf_counter=lambda: next(clock)))
    calls = []
    result, seconds = lessons.best_time(lambda: calls.append(1) or len(calls), repeats=3)
    assert (result, seconds, len(calls)) == (3, 2.0, 3)


def test_timed_render_times_numpy_renders_of_the_scene(monkeypatch, classroom):
    clock = iter([0.0, 5.0, 10.0, 12.0, 20.0, 29.0])
    monkeypatch.setattr(lessons, "time", types.SimpleNamespace(perf_counter=lambda: next(clock)))
    calls = []

    def fake_render(scene, width, height, backend):
        calls.append((scene, width, height, backend))
        return len(calls)

    monkeypatch.setattr(lessons, "render", fake_render)
    frame, seconds = lessons.timed_render(classroom, WIDTH, HEIGHT, repeats=3)
    assert seconds == 2.0 and frame == 3
    assert calls == [(classroom, WIDTH, HEIGHT, "numpy")] * 3


def test_wrong_pixels_marks_exactly_the_pixels_more_than_8_levels_off():
    def frame(color):
        h, w = color.shape[:2]
        return Frame(color=color.astype(np.float32), depth=np.zeros((h, w)),
                     normal=np.zeros((h, w, 3)), steps=np.zeros((h, w), np.int32),
                     object_id=np.zeros((h, w), np.int32), hit=np.ones((h, w), bool),
                     gamma=1.0)

    base = np.full((2, 3, 3), 100 / 255)
    changed = base.copy()
    changed[0, 0, 1] += 9 / 255          # 9 levels off: visible
    changed[1, 2, 0] -= 8 / 255          # 8 levels off: not
    changed[1, 1] += 20 / 255
    np.testing.assert_array_equal(lessons.wrong_pixels(frame(changed), frame(base)),
                                  [[True, False, False], [False, True, False]])


def test_sweep_finds_no_artefact_at_the_converged_value_and_many_when_steps_run_out(
        classroom):
    starved, converged = lessons.sweep(classroom, "max_steps", [4, 4096], 4096, WIDTH,
                                       HEIGHT, repeats=1)
    assert converged["value"] == 4096 and not converged["wrong"].any()
    assert starved["steps"] <= 4 and starved["wrong"].mean() > 0.2
    assert converged["steps"] == converged["frame"].steps.mean() > 4
    assert starved["ms"] > 0 and starved["wrong"].shape == (HEIGHT, WIDTH)


def test_show_renders_shows_and_returns_the_frames_of_its_scenes(monkeypatch, classroom):
    shown = []
    monkeypatch.setattr(plt, "show", lambda: shown.append(plt.gcf()))
    scenes = {"lit": classroom, "steps": lessons.with_settings(classroom, shading="steps")}
    frames = lessons.show_renders(scenes, WIDTH, HEIGHT, backend="numpy")
    try:
        (figure,) = shown
        assert [ax.get_title() for ax in figure.axes] == ["lit", "steps"]
        for ax, (title, scene) in zip(figure.axes, scenes.items()):
            expected = marchlab.render(scene, WIDTH, HEIGHT, backend="numpy").image()
            np.testing.assert_array_equal(frames[title].image(), expected)
            np.testing.assert_array_equal(ax.images[0].get_array(), expected)
    finally:
        plt.close("all")
