"""The cone-marching pre-pass (`reference_cpu.cone_prepass`): every tile's cone holds its
pixels' rays, and no point of a ray before its start lies within epsilon of a surface, on
the cases that break careless versions (thin features seen edge-on, grazing floors, objects
smaller than a tile, an eye inside a solid)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from required_backends import need_backend
from reference_cpu.cone_prepass import start_distances, tile_cones
from reference_cpu.render import render
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import Camera, RenderSettings, Scene, box, plane, sphere
from scene_model.camera import camera_rays
from scene_model.scene import rendered_scene
from scene_model.scenefile import load_scene

EPSILON = 1e-3


def with_cone_prepass(scene: Scene, tile: int) -> Scene:
    return dataclasses.replace(scene, render=dataclasses.replace(
        scene.render, prepass="cone", prepass_tile=tile))


@pytest.mark.parametrize("width, height, tile, fov", [
    (64, 48, 8, 50.0), (61, 37, 8, 90.0), (40, 30, 4, 20.0), (33, 17, 16, 120.0)])
def test_each_tiles_cone_holds_every_ray_of_its_pixels(width, height, tile, fov):
    camera = Camera(position=(0.3, 1.0, 4.0), look_at=(0.0, 0.2, 0.0), fov=fov)
    axes, tan_half = tile_cones(camera, width, height, tile)
    _, directions = camera_rays(camera, width, height)
    rows, cols = np.arange(height) // tile, np.arange(width) // tile
    axis = axes[rows][:, cols]
    cos_half = 1 / np.sqrt(1 + tan_half[rows][:, cols] ** 2)
    cos_angle = np.sum(directions * axis, axis=-1)
    assert (cos_angle >= cos_half - 1e-12).all()
    # ... and is no wider than it must be: a tile's corner pixel is near its edge.
    assert (np.degrees(np.arctan(tan_half)) < fov).all()


def _convex_min_distance(sdf, origin, directions, ends, iterations=80):
    """The least of ``sdf`` (a convex function of the point: the distance to one convex
    solid) along each ray o + s d for s in [0, end], by golden-section search."""
    lo, hi = np.zeros(len(directions)), np.asarray(ends, np.float64).copy()
    ratio = (math.sqrt(5) - 1) / 2
    at = lambda s: sdf(origin + s[:, None] * directions)[0]
    for _ in range(iterations):
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        left = at(a) < at(b)
        hi = np.where(left, b, hi)
        lo = np.where(left, lo, a)
    ends_value = np.minimum(at(np.zeros(len(directions))), at(np.asarray(ends, np.float64)))
    return np.minimum(at((lo + hi) / 2), ends_value)


HARD_CASES = {
    # A plate 1 cm thick seen almost edge-on: its SDF is tiny along many rays.
    "thin plate edge-on": Scene(
        camera=Camera(position=(0.0, 0.02, 5.0), look_at=(0.0, 0.0, 0.0), fov=50.0),
        objects=(box(2.0, 0.005, 2.0),)),
    # A floor seen from 5 cm above, toward the horizon: rays graze it for a long way.
    "grazing floor": Scene(
        camera=Camera(position=(0.0, 0.05, 0.0), look_at=(0.0, 0.0, -20.0), fov=60.0),
        objects=(plane(),)),
    # Spheres smaller than a tile's footprint at their distance.
    "objects smaller than a tile": Scene(
        camera=Camera(position=(0.0, 0.0, 6.0), fov=60.0),
        objects=tuple(sphere(0.02).at(x, y, z) for x, y, z in
                      [(-1.0, 0.3, 0.0), (0.5, -0.4, -2.0), (0.01, 0.01, 1.0),
                       (1.5, 1.0, -5.0)])),
    # The eye inside a solid: the first surface is the way out.
    "eye inside a solid": Scene(
        camera=Camera(position=(0.0, 0.0, 0.5), look_at=(0.0, 0.0, -1.0), fov=70.0),
        objects=(sphere(3.0), box(0.2).at(0.0, 0.0, -1.0))),
}


# The float32 pre-pass computes its starts with float32 rays and distances; measured against
# the float64 truth, a point may come closer by their rounding (about 1e-7 of a 20-unit
# distance, times a few), well inside this.
FLOAT32_ROUNDING = 2e-5


@pytest.mark.parametrize("name", list(HARD_CASES))
@pytest.mark.parametrize("tile", [4, 8])
@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_no_point_of_a_ray_before_its_start_is_within_epsilon_of_a_surface(name, tile,
                                                                         precision):
    scene = HARD_CASES[name]
    scene = Scene(camera=scene.camera, objects=scene.objects,
                  render=RenderSettings(epsilon=EPSILON, max_distance=50.0))
    width, height = 48, 36
    dtype = np.dtype(precision)
    start, _ = start_distances(scene.camera, width, height,
                               build_scene_sdf(scene.objects, dtype), tile, 256, EPSILON,
                               50.0, dtype)
    start = start.astype(np.float64)
    origin, directions = camera_rays(scene.camera, width, height)
    directions, start = directions.reshape(-1, 3), start.reshape(-1)
    assert (start > 0).any(), "the pre-pass moved no ray: the check would hold trivially"
    # Each object is convex, so its distance along a ray is convex: its least value over
    # [0, start] is found exactly by a line search, and the scene's is the least of those.
    least = np.full(len(directions), np.inf)
    for solid in scene.objects:
        sdf = build_scene_sdf((solid,), np.float64)
        least = np.minimum(least, np.abs(_convex_min_distance(sdf, origin, directions,
                                                              start)))
    slack = EPSILON * 1e-9 if precision == "float64" else FLOAT32_ROUNDING
    assert least.min() >= EPSILON - slack


BACKENDS = [("numpy", "float64"), ("numpy", "float32"), ("opencl", "float64"),
            ("opencl", "float32"), ("gpu", "float32")]


def _render(scene, width, height, backend, precision):
    from marchlab.render import render as render_with
    if backend != "numpy":
        need_backend(backend)
    return render_with(scene, width, height, backend=backend, precision=precision)


@pytest.mark.parametrize("backend, precision", BACKENDS)
@pytest.mark.parametrize("name", ["classroom", "lights", "bounce", "csg"])
def test_a_ray_marched_from_the_prepass_stops_in_the_same_surfaces_epsilon_band(
        name, backend, precision):
    # Starting later changes where a ray samples the SDF, not the surfaces ahead of it:
    # where both marches stop on the same object, both stopped within epsilon of it, so
    # their distances differ by at most 2 epsilon / |cos| of the angle of incidence. Where
    # they stop on different objects, one of them stopped at a graze (a silhouette passed
    # within epsilon) or ran out of steps: a few pixels, as between float32 and float64.
    scene = rendered_scene(load_scene(name))
    plain = _render(scene, 96, 72, backend, precision)
    cone = _render(with_cone_prepass(scene, 4), 96, 72, backend, precision)
    _, directions = camera_rays(scene.camera, 96, 72)
    same = plain.hit & cone.hit & (plain.object_id == cone.object_id)
    cosine = np.abs(np.sum(plain.normal.astype(np.float64) * directions, axis=-1))[same]
    gap = np.abs(cone.depth[same].astype(np.float64) - plain.depth[same])
    # float32: the surface is found to its rounding at distances up to ~20 (2e-6), and the
    # normal's angle to about 1e-3 rad.
    slack = 1e-6 if precision == "float64" else 1e-4
    assert (gap * cosine <= 2 * scene.render.epsilon * (1 + slack)).all()
    differing = (plain.hit != cone.hit) | (plain.object_id != cone.object_id)
    assert differing.mean() < 0.01


@pytest.mark.parametrize("backend, precision", BACKENDS)
def test_the_prepass_cuts_the_classrooms_primary_steps_by_a_third_or_more(backend, precision):
    # Measured (docs/performance.md): 26.9 -> 16.2 steps a pixel at 160 x 120, tile 4. The
    # steps buffer counts each ray's own evaluations, in every backend.
    scene = rendered_scene(load_scene("classroom"))
    plain = _render(scene, 160, 120, backend, precision)
    cone = _render(with_cone_prepass(scene, 4), 160, 120, backend, precision)
    assert cone.steps.mean() <= 2 / 3 * plain.steps.mean()


@pytest.mark.parametrize("name", list(HARD_CASES))
def test_opencl_float32_starts_every_ray_where_the_reference_does(name):
    # Same operations in the same order (glsl/cone.glsl, reference_cpu/cone_prepass.py): the
    # one-ray and packet programs find the reference's starts to the bit, so their frames'
    # steps and depths are the reference's exactly.
    from gpu_shader import opencl
    need_backend("opencl")
    scene = with_cone_prepass(HARD_CASES[name], 4)
    reference = render(scene, 37, 29, "float32")
    for packets in (True, False):
        frame = opencl.render(scene, 37, 29, "float32", packets=packets)
        np.testing.assert_array_equal(frame.steps, reference.steps)
        np.testing.assert_array_equal(frame.depth, reference.depth)


def test_the_start_on_a_grazing_floor_gets_most_of_the_way_to_the_floors_band():
    # The other side of safety: the start is not trivially small. On a floor y = 0 a ray
    # from height y0 falling at dy < 0 per unit enters the band within epsilon of the floor
    # at s = (y0 - epsilon) / -dy: no start may pass it (the test above), and the best of
    # the pre-pass's starts come within a few tile widths of it.
    scene = HARD_CASES["grazing floor"]
    width, height, tile = 48, 36, 4
    start, _ = start_distances(scene.camera, width, height,
                               build_scene_sdf(scene.objects, np.float64), tile, 256, EPSILON,
                               50.0)
    _, directions = camera_rays(scene.camera, width, height)
    falling = directions[..., 1] < 0
    band = (scene.camera.position[1] - EPSILON) / -directions[..., 1][falling]
    reached = start[falling] / band
    assert reached.max() <= 1.0
    assert np.median(reached) >= 0.5
