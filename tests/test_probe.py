"""The probe (reference_cpu/probe.py): one pixel's march, step by step.

Its step count and final t must be the reference frame's ``steps`` and ``depth`` at that
pixel exactly (the same arithmetic on the same ray), and its steps must follow sphere
tracing's own rule, t[k+1] = t[k] + d[k], against a sphere whose distances are known in
closed form.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reference_cpu.probe import probe_pixel
from reference_cpu.render import render
from scene_model import builder
from scene_model.scene import Camera, RenderSettings, Scene, rendered_scene
from scene_model.scenefile import load_scene

WIDTH, HEIGHT = 32, 24


@pytest.mark.parametrize("name", ["classroom", "csg", "repetition"])
@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_the_probe_ends_where_the_frame_says_at_every_sampled_pixel(name, precision):
    scene = rendered_scene(load_scene(name))
    frame = render(scene, WIDTH, HEIGHT, precision)
    for y, x in [(0, 0), (HEIGHT // 2, WIDTH // 2), (HEIGHT - 1, 3), (7, WIDTH - 2), (15, 9)]:
        probe = probe_pixel(scene, x, y, WIDTH, HEIGHT, precision)
        assert probe.steps == frame.steps[y, x]
        assert probe.hit == frame.hit[y, x]
        assert probe.depth == frame.depth[y, x] or (np.isinf(probe.depth)
                                                    and np.isinf(frame.depth[y, x]))
        assert len(probe.t) == len(probe.distance) == probe.steps


def test_with_relaxation_and_culling_the_probe_still_ends_where_the_frame_says():
    scene = rendered_scene(load_scene("repetition"))
    scene = dataclasses.replace(scene, render=dataclasses.replace(
        scene.render, relaxation="auto", bounding_spheres=True))
    frame = render(scene, WIDTH, HEIGHT)
    for y, x in [(HEIGHT // 2, WIDTH // 2), (18, 4), (20, 28)]:
        probe = probe_pixel(scene, x, y, WIDTH, HEIGHT)
        assert (probe.steps, probe.hit) == (frame.steps[y, x], frame.hit[y, x])


def test_toward_a_sphere_each_step_is_the_distance_to_it_and_the_last_is_within_epsilon():
    """Camera at z = 5 looking at a unit sphere at the origin: along the central ray the
    distance at t is exactly 4 - t, so plain marching reaches it in one step of 4 (m)."""
    scene = Scene(camera=Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0)),
                  objects=(builder.sphere(1.0),),
                  render=RenderSettings(epsilon=1e-4))
    # An odd size puts a pixel centre exactly on the axis.
    probe = probe_pixel(scene, 2, 2, 5, 5)
    assert probe.hit and probe.depth == pytest.approx(4.0, abs=1e-12)
    np.testing.assert_allclose(probe.distance, 4.0 - probe.t, atol=1e-12)
    np.testing.assert_allclose(probe.t[1:], (probe.t + probe.distance)[:-1], rtol=0, atol=0)
    assert probe.t[0] == 0 and probe.distance[-1] < 1e-4


def test_a_ray_into_the_sky_takes_steps_until_it_passes_max_distance():
    scene = Scene(camera=Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0)),
                  objects=(builder.sphere(1.0).at(0.0, -3.0, 0.0),),
                  render=RenderSettings(max_distance=50.0))
    probe = probe_pixel(scene, 2, 0, 5, 5)           # the top row looks above the sphere
    assert not probe.hit and probe.depth == np.inf
    assert probe.t[-1] + probe.distance[-1] > 50.0 >= probe.t[-1]
    assert np.all(np.diff(probe.t) > 0)


def test_the_front_door_draws_bodies_and_refuses_a_pixel_outside_the_image():
    import marchlab
    scene = load_scene("bounce")                     # its balls are bodies, not objects
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    y, x = np.unravel_index(np.argmax(frame.object_id), frame.object_id.shape)
    probe = marchlab.probe(scene, int(x), int(y), WIDTH, HEIGHT)
    assert (probe.steps, probe.depth) == (frame.steps[y, x], frame.depth[y, x])
    for bad in [(WIDTH, 0), (0, -1), (1.5, 0), (True, 0)]:
        with pytest.raises(marchlab.MarchlabError, match="pixel index"):
            marchlab.probe(scene, *bad, WIDTH, HEIGHT)
