"""Bounding spheres (scene_model.bounds) and the ray test (reference_cpu.culling) of culling.

Culling is safe when three things hold; the first two are tested here, the third in
test_culling_march.py:

1. ``ray_meets_sphere`` is right: the ray o + t d, t >= 0, touches the sphere iff it starts
   inside (c' = |o - c|^2 - r^2 <= 0) or the sphere lies ahead (b = (o - c).d <= 0) and its
   line meets it (b^2 - c' >= 0);
2. every bounding sphere holds its node's solid (the points where the node's SDF is <= 0),
   for every node type: sampled with hypothesis over random trees;
3. so a culled march sees the objects it may reach and marches as the plain one does.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from test_march import ray_sphere, unit

from reference_cpu.culling import ray_meets_sphere
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.bounds import bounding_sphere, enclosing_sphere
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Intersection,
                                Morph, Plane, Pyramid, Repeat, Rotate, RoundBox, Scale,
                                SmoothIntersection, SmoothSubtraction, SmoothUnion, Sphere,
                                Subtraction, Torus, Translate, Union)


# --- ray_meets_sphere ----------------------------------------------------------------------

CENTRE = np.array([1.0, -2.0, 0.5])


def meets(origin, direction, radius=1.0, centre=CENTRE):
    return bool(ray_meets_sphere(np.asarray(origin, float), unit([direction]), centre,
                                 radius)[0])


def test_a_ray_starting_inside_the_sphere_meets_it_in_every_direction():
    rng = np.random.default_rng(31)
    directions = unit(rng.normal(size=(500, 3)))
    origin = CENTRE + [0.3, 0.2, -0.4]
    assert ray_meets_sphere(origin, directions, CENTRE, 1.0).all()
    # Exactly on the surface counts as inside (c' = 0).
    assert ray_meets_sphere(CENTRE + [0.0, 1.0, 0.0], directions, CENTRE, 1.0).all()


def test_a_sphere_ahead_is_met_and_the_same_sphere_behind_is_not():
    origin = CENTRE + [0.0, 0.0, 5.0]
    assert meets(origin, [0.0, 0.0, -1.0])                  # straight at it
    assert meets(origin, [0.15, 0.0, -1.0])                 # off-centre, line still inside
    assert not meets(origin, [0.0, 0.0, 1.0])               # straight away: b > 0
    assert not meets(origin, [0.15, 0.0, 1.0])              # the line meets it, behind


def test_a_ray_passing_beside_the_sphere_misses_it():
    origin = CENTRE + [0.0, 0.0, 5.0]
    assert not meets(origin, [0.3, 0.0, -1.0])              # passes ~1.44 from the centre
    assert not meets(origin, [0.0, 1.0, 0.0])


def test_a_tangent_ray_meets_the_sphere_and_one_a_rounding_farther_out_misses_it():
    """From (-5, 1, 0) along +x past the unit sphere at the origin: b = -5, c' = 25, and
    b^2 - c' = 0 exactly: tangent counts as meeting. A radius smaller by 1e-9 misses."""
    origin, direction = np.array([-5.0, 1.0, 0.0]), np.array([[1.0, 0.0, 0.0]])
    assert ray_meets_sphere(origin, direction, np.zeros(3), 1.0)[0]
    assert not ray_meets_sphere(origin, direction, np.zeros(3), 1.0 - 1e-9)[0]
    assert ray_meets_sphere(origin, direction, np.zeros(3), 1.0 + 1e-9)[0]


def test_ray_meets_sphere_matches_the_ray_sphere_equation_on_random_rays():
    """Against the roots of t^2 + 2 b t + c' = 0 with t >= 0, away from tangency."""
    rng = np.random.default_rng(32)
    origins = rng.uniform(-4, 4, (20000, 3))
    directions = unit(rng.normal(size=(20000, 3)))
    t, closest = ray_sphere(origins, directions, CENTRE, 1.5)
    clear = np.abs(closest - 1.5) > 1e-9
    met = ray_meets_sphere(origins, directions, CENTRE, 1.5)
    np.testing.assert_array_equal(met[clear], np.isfinite(t)[clear])
    assert met.sum() > 1000 and (~met).sum() > 10000


# --- bounding spheres hold the solid ----------------------------------------------------------

size = st.floats(0.05, 1.5)
offset = st.tuples(*[st.floats(-2, 2)] * 3)
angles = st.tuples(*[st.floats(-180, 180)] * 3)
blend = st.floats(0.01, 2.0)


@st.composite
def round_boxes(draw):
    half = draw(st.tuples(size, size, size))
    return RoundBox(half, draw(st.floats(0.01, 1.0)) * min(half))


@st.composite
def capsules(draw):
    a, b = draw(offset), draw(offset)
    assume(a != b)
    return Capsule(a, b, draw(size))


primitive_nodes = st.one_of(
    st.builds(Sphere, size),
    st.builds(lambda x, y, z: Box((x, y, z)), size, size, size),
    round_boxes(),
    st.builds(Torus, size, size),
    st.builds(CappedCylinder, size, size),
    capsules(),
    st.builds(Cone, size, size),
    st.builds(Pyramid, size, size),
    st.builds(lambda r, f: Disk(r, 2 * r * f), size, st.floats(0.01, 1.0)),
    st.builds(HexPrism, size, size),
)


def compound_nodes(children):
    some = st.lists(children, min_size=1, max_size=3).map(tuple)
    period = st.tuples(*[st.sampled_from([0.0, 0.7, 1.5, 3.0])] * 3).filter(any)
    count = st.tuples(*[st.integers(0, 2)] * 3)
    return st.one_of(
        st.builds(Translate, children, offset),
        st.builds(Rotate, children, angles),
        st.builds(Scale, children, st.floats(0.3, 2.0)),
        st.builds(Union, some), st.builds(Intersection, some), st.builds(Subtraction, some),
        st.builds(SmoothUnion, some, blend), st.builds(SmoothIntersection, some, blend),
        st.builds(SmoothSubtraction, some, blend),
        st.builds(Morph, st.tuples(children, children), st.floats(0.0, 1.0)),
        st.builds(Repeat, children, period, count),
    )


trees = st.recursive(primitive_nodes, compound_nodes, max_leaves=4)


def solid_points_outside(node, seed, n=20000):
    """Sample points near and far from the node's bounding sphere; return how many lie in
    the solid (SDF <= 0) and the largest |p - c| / r among them."""
    centre, radius = bounding_sphere(node)
    rng = np.random.default_rng(seed)
    sdf = build_scene_sdf([node])
    # A shell from 0 to 3 radii around the sphere (dense just outside it), and a wide box.
    directions = unit(rng.normal(size=(n, 3)))
    shell = centre + directions * radius * rng.uniform(0, 3, (n, 1)) ** 0.5 * 1.8
    wide = rng.uniform(-15, 15, (n, 3))
    points = np.concatenate([shell, wide])
    solid = points[sdf(points)[0] <= 0]
    if len(solid) == 0:
        return 0, 0.0
    return len(solid), float((np.linalg.norm(solid - centre, axis=1) / radius).max())


@given(node=trees, seed=st.integers(0, 2**32 - 1))
def test_bounding_sphere_holds_the_solid_of_any_bounded_tree(node, seed):
    sphere_ = bounding_sphere(node)
    assert sphere_ is not None                      # no plane or endless repeat in these
    inside, farthest = solid_points_outside(node, seed)
    assume(inside > 0)                              # e.g. an empty intersection
    assert farthest <= 1 + 1e-9


@pytest.mark.parametrize("node", [
    Sphere(0.7), Box((0.3, 0.5, 0.9)), RoundBox((0.4, 0.4, 0.6), 0.2), Torus(1.0, 0.3),
    Torus(0.2, 0.5), CappedCylinder(0.4, 1.2), Capsule((-0.5, 0.2, 0.0), (0.4, 1.0, 0.3), 0.2),
    Cone(0.6, 1.5), Pyramid(1.2, 0.7), Pyramid(0.3, 1.5), Disk(0.9, 0.2), Disk(0.5, 1.0),
    HexPrism(0.6, 0.3), HexPrism(0.2, 1.1),
    Translate(Rotate(Scale(Box((0.2, 0.6, 0.3)), 1.7), (20.0, 35.0, -50.0)), (1.0, -0.5, 2.0)),
    Union((Sphere(0.5), Translate(Box((0.3, 0.3, 0.3)), (1.2, 0.0, 0.0)))),
    Intersection((Sphere(0.8), Box((0.6, 0.6, 0.6)))),
    Subtraction((Sphere(0.8), Translate(Box((0.3, 0.3, 1.0)), (0.3, 0.0, 0.0)))),
    SmoothUnion((Translate(Sphere(0.4), (-0.6, 0, 0)), Translate(Sphere(0.4), (0.6, 0, 0))),
                2.0),
    SmoothIntersection((Sphere(0.8), Box((0.6, 0.6, 0.6))), 0.5),
    SmoothSubtraction((Sphere(0.8), Translate(Box((0.3, 0.3, 1.0)), (0.3, 0.0, 0.0))), 0.3),
    Repeat(Sphere(0.3), (1.0, 0.0, 1.5), (2, 0, 1)),
    Morph((Translate(Sphere(0.6), (-0.2, 0, 0)), Translate(Box((0.3, 0.6, 0.3)), (0.4, 0, 0))),
          0.35),
], ids=lambda n: n.kind)
def test_bounding_sphere_holds_the_solid_of_each_node_type(node):
    inside, farthest = solid_points_outside(node, 33)
    assert inside > 40 and farthest <= 1 + 1e-9


def test_smooth_union_sphere_grows_by_k_over_4_which_its_solid_can_reach():
    """Two unit spheres 2.2 apart, k = 2: the blend fills the gap between them and reaches
    out sideways; the rule's radius (1.1 + 1) + k/4 = 2.6 holds it."""
    node = SmoothUnion((Translate(Sphere(1.0), (-1.1, 0, 0)), Translate(Sphere(1.0), (1.1, 0, 0))),
                       2.0)
    centre, radius = bounding_sphere(node)
    np.testing.assert_allclose(centre, 0.0, atol=1e-15)
    assert radius == pytest.approx(2.1 + 0.5)
    inside, farthest = solid_points_outside(node, 34)
    assert inside > 100 and farthest <= 1


def test_bounding_sphere_holds_a_smooth_union_of_three_children():
    node = SmoothUnion((Sphere(1.0), Sphere(1.0), Sphere(1.0)), 1.0)
    inside, farthest = solid_points_outside(node, 38)
    assert inside > 100 and farthest <= 1 + 1e-9


@pytest.mark.parametrize("node", [
    Plane(), Repeat(Sphere(0.3), (1.0, 0.0, 1.0)), Union((Sphere(1.0), Plane())),
    Translate(Plane(), (0, 1, 0)), Subtraction((Plane(), Sphere(1.0))),
], ids=["plane", "endless-repeat", "union-with-plane", "moved-plane", "plane-minus-sphere"])
def test_unbounded_nodes_have_no_bounding_sphere(node):
    assert bounding_sphere(node) is None


def test_an_intersection_with_a_plane_keeps_the_bounded_childs_sphere():
    centre, radius = bounding_sphere(Intersection((Plane(), Translate(Sphere(0.5), (0, 1, 0)))))
    np.testing.assert_array_equal(centre, [0, 1, 0]) and radius == 0.5


def test_enclosing_sphere_reaches_the_far_side_of_every_sphere():
    rng = np.random.default_rng(35)
    spheres = [(rng.uniform(-3, 3, 3), rng.uniform(0.1, 1)) for _ in range(6)]
    centre, radius = enclosing_sphere(spheres)
    for c, r in spheres:
        assert np.linalg.norm(c - centre) + r <= radius + 1e-12
