"""A structural edit compiles in the background while the view keeps drawing its old program
(`gpu_shader.background_compile`, `marchlab.view_window.ViewDrawer`), on the gpu backend's
headless context: no window needed."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from marchlab.render import render
from marchlab.view import Viewer
from required_backends import need_backend
from scene_model.scene import rendered_scene

SIZE = (96, 72)


@pytest.fixture
def ctx():
    need_backend("gpu")
    from gpu_shader.context import gl_context
    return gl_context()


class FakeCompiler:
    """A `BackgroundCompiler` stand-in whose programs are ready when the test says so."""

    def __init__(self):
        self.requested = []
        self.finished = False

    def request(self, program):
        self.requested.append(program)

    def ready(self, program):
        return self.finished


@pytest.fixture
def drawn(ctx):
    """A viewer of the classroom and a drawer with a fake compiler, the scene drawn once."""
    from marchlab.view_window import ViewDrawer
    viewer = Viewer("classroom", SIZE)
    viewer.refine = False
    drawer = ViewDrawer(ctx, compiler=FakeCompiler())
    drawer.update(viewer)
    return viewer, drawer


def _gpu_image(scene):
    return render(scene, *SIZE, backend="gpu").image()


def _shown(drawer, viewer):
    return drawer.shown_image(viewer, outline=False)


def _largest_difference(a, b) -> int:
    return int(np.abs(a.astype(int) - b.astype(int)).max())


def test_a_camera_move_asks_the_compiler_for_nothing_and_draws_the_new_view(drawn):
    viewer, drawer = drawn
    viewer.drag("left", 30, 10)
    assert drawer.update(viewer)
    assert drawer.compiler.requested == [] and not drawer.compiling
    assert _largest_difference(_shown(drawer, viewer), _gpu_image(viewer.drawn_scene())) <= 1


def test_while_an_added_object_compiles_the_view_draws_the_old_scene_from_the_new_camera(drawn):
    viewer, drawer = drawn
    before = viewer.drawn_scene()
    viewer.add_object("torus")
    viewer.drag("left", 30, 10)
    drawer.update(viewer)
    assert drawer.compiling and len(drawer.compiler.requested) == 1
    old_from_new_camera = dataclasses.replace(before, camera=viewer.camera)
    assert drawer.drawn[0] == old_from_new_camera
    assert _largest_difference(_shown(drawer, viewer), _gpu_image(old_from_new_camera)) <= 1


def test_once_the_compiler_is_ready_the_view_draws_the_edited_scene(drawn):
    viewer, drawer = drawn
    viewer.add_object("torus")
    drawer.update(viewer)
    drawer.compiler.finished = True
    assert drawer.update(viewer) and not drawer.compiling
    assert drawer.drawn[0] == viewer.drawn_scene()
    assert _largest_difference(_shown(drawer, viewer), _gpu_image(viewer.drawn_scene())) <= 1


def test_a_screenshot_does_not_wait_for_the_compiler_it_draws_the_edited_scene(drawn):
    viewer, drawer = drawn
    viewer.add_object("torus")
    drawer.update(viewer)
    assert drawer.compiling
    edited = _gpu_image(rendered_scene(viewer.scene_now()))
    assert _largest_difference(drawer.image(viewer), edited) <= 1


def test_the_first_picture_is_drawn_at_once_with_nothing_older_to_show(ctx):
    from marchlab.view_window import ViewDrawer
    viewer = Viewer("csg", SIZE)
    drawer = ViewDrawer(ctx, compiler=FakeCompiler())
    assert drawer.update(viewer) and not drawer.compiling
    assert drawer.compiler.requested == []


def test_a_program_compiled_by_the_worker_process_is_ready_and_no_other_is(ctx):
    from gpu_shader.background_compile import BackgroundCompiler
    from gpu_shader.generate import generate
    from scene_model.scenefile import load_scene
    compiler = BackgroundCompiler(backend="egl")
    try:
        program = generate(load_scene("csg"), *SIZE)
        other = generate(load_scene("classroom"), *SIZE)
        assert compiler.wait(program, timeout=120)
        assert compiler.problem is None
        assert compiler.ready(program) and not compiler.ready(other)
        assert compiler.compiled == 1
    finally:
        compiler.close()
    assert compiler.problem is None          # a normal close is not a failure


def test_a_worker_that_cannot_make_a_context_says_why_and_calls_everything_ready(ctx):
    from gpu_shader.background_compile import BackgroundCompiler
    from gpu_shader.generate import generate
    from scene_model.scenefile import load_scene
    compiler = BackgroundCompiler(backend="no-such-backend")
    try:
        program = generate(load_scene("csg"), *SIZE)
        assert compiler.wait(program, timeout=120)
        assert "no-such-backend" in compiler.problem
        assert compiler.ready(program)
    finally:
        compiler.close()
