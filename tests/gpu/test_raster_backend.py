"""The raster backend's GPU pipeline (`gpu_shader.raster_render.MeshRenderer`): what a live
view draws is the frame `render` reads back, a kept renderer draws a moved camera as a new
one does, its passes leave the context as they found it, and culling the back faces of the
solids the camera is outside of changes nothing the exact ray cast agrees with. Its pictures
are held to the NumPy rasteriser's in tests/equivalence/test_raster_equivalence.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import gpu_shader.raster_render
import gpu_shader.raster_shadows
from gpu_shader.raster_lit import read_planes
from gpu_shader.raster_render import MeshRenderer
from marchlab import load_scene, render
from required_backends import need_backend
from reference_cpu.truth.mesh_cast import cast_raster
from scene_model.mesh_world import scene_meshes
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


def orbit(camera: Camera, degrees: float) -> Camera:
    """``camera`` carried ``degrees`` about the vertical through the point it looks at."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    x, y, z = np.subtract(camera.position, camera.look_at)
    return dataclasses.replace(camera, position=tuple(
        np.add(camera.look_at, (c * x + s * z, y, -s * x + c * z))))


@pytest.mark.parametrize("name", ["museum", "meshes"])
def test_culling_hidden_back_faces_changes_only_what_the_ray_cast_disagrees_with(
        gpu, monkeypatch, name):
    # The opaque pass and the shadow volumes' depth pass skip the back faces of closed
    # meshes the camera is outside of (reference_cpu.back_faces). Drawn with and without
    # that, from five cameras about the scene (skybox, mirror and glass included), the
    # pictures show the same object at every pixel, and differ in triangle or colour only
    # where the unculled pipeline's triangle is not Embree's either: silhouette pixels where
    # a back face's depth came out a hair in front (tests/truth/test_back_faces_against_embree.py).
    need_backend("embree")
    scene = load_scene(name)
    meshes = scene_meshes(scene)[0]
    renderer = MeshRenderer(scene)
    assert sum(renderer.solid) >= 3
    changed = 0
    try:
        for degrees in (0, 40, 130, 220, 310):
            moved = dataclasses.replace(scene, camera=orbit(scene.camera, degrees))
            drawn = {}
            for culling in (True, False):
                with monkeypatch.context() as patch:
                    if not culling:
                        for module in (gpu_shader.raster_render, gpu_shader.raster_shadows):
                            patch.setattr(module, "culled_meshes",
                                          lambda solid, *_: np.zeros(len(solid), bool))
                    fbo = renderer.draw(moved, WIDTH, HEIGHT)
                    drawn[culling] = read_planes(renderer.ctx, fbo, WIDTH, HEIGHT)
            (color, culled), (plain_color, plain) = drawn[True], drawn[False]
            np.testing.assert_array_equal(culled.object_id, plain.object_id)
            differ = ((culled.triangle != plain.triangle)
                      | np.any(color != plain_color, axis=-1))
            if differ.any():
                truth = cast_raster(meshes, moved.camera, WIDTH, HEIGHT)
                wrong = (plain.object_id != truth.object_id) | (plain.triangle != truth.triangle)
                assert wrong[differ].all(), np.argwhere(differ & ~wrong)
                changed += int(differ.sum())
    finally:
        renderer.release()
    assert changed <= 0.002 * 5 * WIDTH * HEIGHT
