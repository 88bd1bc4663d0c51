"""The error measures of benchmarks/bench_mesh_vs_sdf.py against closed forms.

The benchmark's central numbers are geometric errors: a mesh's farthest point from the true
surface (sampled on a barycentric grid) and a sphere-traced frame's (|sdf| at its hits). Both
are checked here on shapes whose answer is known, without a GPU.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from reference_cpu.sdf import sdf_box, sdf_sphere
from scene_model.camera import camera_rays
from scene_model.meshes import cube, uv_sphere
from scene_model.scene import Camera

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_mesh_vs_sdf.py"
_SPEC = importlib.util.spec_from_file_location("bench_mesh_vs_sdf", _PATH)
bench = importlib.util.module_from_spec(_SPEC)
sys.modules[_SPEC.name] = bench          # its dataclasses look their module up there
_SPEC.loader.exec_module(bench)


@pytest.mark.parametrize("segments, rings", [(16, 8), (64, 32), (24, 9), (40, 7)])
def test_uv_sphere_error_matches_closed_form_within_1_percent(segments, rings):
    radius = 2.0
    mesh = uv_sphere(radius, segments, rings)
    measured = bench.mesh_error(mesh, lambda p: sdf_sphere(p, radius))
    exact = bench.uv_sphere_error(radius, segments, rings)
    assert measured == pytest.approx(exact, rel=0.01)
    # Samples of a triangle never lie farther from the sphere than its deepest point.
    assert measured <= exact * (1 + 1e-12)


def test_uv_sphere_error_is_twice_the_chord_sag_for_fine_square_cells():
    # n segments, n / 2 rings: cells pi / n on a side, each sagging 1 - cos(pi / n) both ways.
    n = 512
    sag = 1.0 - np.cos(np.pi / n)
    assert bench.uv_sphere_error(1.0, n, n // 2) == pytest.approx(2 * sag, rel=1e-4)


def test_cube_mesh_error_is_zero_at_any_subdivision():
    for subdivisions in (1, 3):
        mesh = cube(1.5, subdivisions)
        assert bench.mesh_error(mesh, lambda p: sdf_box(p, np.full(3, 0.75))) < 1e-15


def test_barycentric_grid_weights_sum_to_one_and_count_the_grid():
    weights = bench.barycentric_grid(6)
    assert weights.shape == (7 * 8 // 2, 3)
    assert np.allclose(weights.sum(axis=1), 1.0)
    assert weights.min() == 0.0


def test_hit_error_of_rays_stopped_short_is_the_gap_at_normal_incidence():
    # An odd-sized frame's middle ray passes through the sphere's centre and meets it
    # head on, so stopping every ray delta short of the sphere leaves a largest |sdf| of delta.
    camera = Camera(position=(0.0, 0.0, 4.0), look_at=(0.0, 0.0, 0.0), fov=40.0)
    width = height = 9
    origin, d = camera_rays(camera, width, height)
    # The exact hit of a unit sphere: t = -b - sqrt(b^2 - c), b = o.d, c = |o|^2 - 1.
    b = d @ origin
    disc = b * b - (origin @ origin - 1.0)
    hit = disc > 0
    delta = 1e-3
    depth = np.where(hit, -b - np.sqrt(np.where(hit, disc, 0.0)) - delta, 0.0)
    error = bench.hit_error(depth, hit, camera, lambda p: sdf_sphere(p, 1.0))
    assert error == pytest.approx(delta, rel=1e-9)
