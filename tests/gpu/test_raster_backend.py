"""The raster backend's GPU pipeline (`gpu_shader.raster_render.MeshRenderer`): what a live
view draws is the frame `render` reads back, a kept renderer draws a moved camera as a new
one does, and its passes leave the context as they found it. Its pictures are held to the
NumPy rasteriser's in tests/equivalence/test_raster_equivalence.py."""

from __future__ import annotations

import dataclasses

import numpy as np

from gpu_shader.raster_lit import read_planes
from gpu_shader.raster_render import MeshRenderer
from marchlab import load_scene, render
from scene_model.scene import Camera

WIDTH, HEIGHT = 64, 48


def test_the_live_view_draws_the_colour_the_frame_reads_back(gpu):
    scene = load_scene("museum")
    renderer = MeshRenderer(scene)
    try:
        fbo = renderer.draw(scene, WIDTH, HEIGHT)
        color, raster = read_planes(renderer.ctx, fbo, WIDTH, HEIGHT)
    finally:
        renderer.release()
    frame = render(scene, WIDTH, HEIGHT, backend="raster")
    np.testing.assert_array_equal(np.clip(color, 0, 1).astype(np.float32), frame.color)
    np.testing.assert_array_equal(raster.object_id, frame.object_id)


def test_a_kept_renderer_draws_a_moved_camera_as_a_new_one(gpu):
    scene = load_scene("museum")
    moved = dataclasses.replace(scene, camera=Camera(position=(-1.5, 2.0, 6.0),
                                                     look_at=(0.3, 1.0, 0.0), fov=55.0))
    renderer = MeshRenderer(scene)
    try:
        renderer.frame(scene, WIDTH, HEIGHT)
        kept = renderer.frame(moved, WIDTH, HEIGHT)
    finally:
        renderer.release()
    fresh = render(moved, WIDTH, HEIGHT, backend="raster")
    np.testing.assert_array_equal(kept.color, fresh.color)
    np.testing.assert_array_equal(kept.path, fresh.path)


def test_the_sphere_tracer_draws_the_same_after_the_raster_backend(gpu):
    before = render(load_scene("classroom"), 32, 24, backend="gpu")
    render(load_scene("museum"), 32, 24, backend="raster")
    after = render(load_scene("classroom"), 32, 24, backend="gpu")
    np.testing.assert_array_equal(after.color, before.color)
    np.testing.assert_array_equal(after.depth, before.depth)
