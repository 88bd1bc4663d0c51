"""Whole scenes through ``build_scene_sdf``: distances, object ids and the dtype they keep.

A union picks the nearer primitive's id, an intersection the farther one's, ids counted depth
first; asking for ids must not change distances; an empty scene is infinitely far with id -1;
a float32 scene stays float32 through every node kind.
"""

from __future__ import annotations

import numpy as np
import pytest
from sdf_reference import EXACT, SINGLE, box_distance, sphere_distance, torus_distance

from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.shapes import Box, Cone, Repeat, Sphere, Torus


def test_object_id_is_depth_first_index_of_chosen_primitive():
    """Ids in depth-first order: 0 the sphere, 1 the box and 2 the sphere of the intersection,
    3 the torus. A union picks the nearer primitive's id, an intersection the farther one's."""
    left = Sphere(1.0).at(-2.5, 0, 0)
    lens = Box((0.8, 0.8, 0.8)) & Sphere(1.0).at(0.6, 0.0, 0.0)
    ring = Torus(1.0, 0.3).at(2.5, 0, 0)
    p = np.random.default_rng(22).uniform(-4, 4, (5000, 3))
    distance, ids = build_scene_sdf([left, lens, ring], with_ids=True)(p)

    d0 = sphere_distance(p - (-2.5, 0, 0), 1.0)
    d1 = box_distance(p, np.array([0.8, 0.8, 0.8]))
    d2 = sphere_distance(p - (0.6, 0, 0), 1.0)
    d3 = torus_distance(p - (2.5, 0, 0), 1.0, 0.3)
    lens_d, lens_id = np.where(d1 >= d2, d1, d2), np.where(d1 >= d2, 1, 2)
    candidates = np.column_stack([d0, lens_d, d3])
    nearest = np.argmin(candidates, axis=1)
    expected_ids = np.choose(nearest, [np.zeros_like(lens_id), lens_id, np.full_like(lens_id, 3)])

    np.testing.assert_allclose(distance, candidates.min(axis=1), rtol=0, atol=EXACT)
    np.testing.assert_array_equal(ids, expected_ids)
    assert set(np.unique(ids)) == {0, 1, 2, 3}          # every branch was exercised


def test_subtraction_gives_the_cutter_id_where_the_cut_is_nearest():
    """Inside a box's hollow cut by a sphere the nearest surface is the sphere's: id 1."""
    sdf = build_scene_sdf([Box((1.0, 1.0, 1.0)) - Sphere(0.5)], with_ids=True)
    p = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.6], [0.0, 0.0, 0.95], [0.0, 0.0, 3.0]])
    distance, ids = sdf(p)
    np.testing.assert_allclose(distance, [0.5, -0.1, -0.05, 2.0], atol=EXACT)
    np.testing.assert_array_equal(ids, [1, 1, 0, 0])


def test_distances_do_not_depend_on_asking_for_ids():
    objects = [Sphere(1.0).at(-1, 0, 0) | Box((0.5, 0.7, 0.2)).rotate(10, 20, 30), Torus()]
    p = np.random.default_rng(23).uniform(-3, 3, (500, 3))
    with_ids, without = build_scene_sdf(objects, with_ids=True)(p), build_scene_sdf(objects)(p)
    np.testing.assert_array_equal(with_ids[0], without[0])
    assert without[1] is None and with_ids[1].shape == (500,)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_empty_scene_is_infinitely_far_with_id_minus_1(dtype):
    p = np.zeros((4, 3), dtype=dtype)
    distance, ids = build_scene_sdf([], dtype=dtype, with_ids=True)(p)
    assert distance.dtype == dtype and np.all(np.isposinf(distance))
    np.testing.assert_array_equal(ids, [-1, -1, -1, -1])


def test_float32_scene_with_every_node_kind_stays_float32_within_1e_5():
    """build_scene_sdf casts parameters to float32; transforms and operators must keep it."""
    scene = [(Box((0.5, 0.4, 0.3)).rotate(10, 20, 30).scale(1.5) | Cone(0.5, 1.0).at(1, 0, 0))
             - Sphere(0.3),
             Repeat(Torus(0.5, 0.1), (3.0, 0.0, 3.0), (1, 0, 1)).at(0, -2, 0)]
    p = np.random.default_rng(24).uniform(-4, 4, (2000, 3))
    d64 = build_scene_sdf(scene, dtype=np.float64)(p)[0]
    d32 = build_scene_sdf(scene, dtype=np.float32)(p.astype(np.float32))[0]
    assert d32.dtype == np.float32
    np.testing.assert_allclose(d32, d64, rtol=0, atol=SINGLE)
