"""The analytic ground truth (reference_cpu.truth.analytic) against answers worked out by hand.

Every expected value below is a closed form: a ray meeting a sphere, a box face or a plane.
Tolerances are float64 rounding of a few operations on numbers of order 10: 1e-12 unless
stated.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from reference_cpu.scene_sdf import build_scene_sdf
from reference_cpu.truth import ground_truth
from reference_cpu.truth.analytic import trace_analytic
from reference_cpu.truth.parts import scene_parts
from scene_model.builder import Camera, RenderSettings, Scene, box, plane, sphere, torus, union
from scene_model.errors import SceneError

TOL = 1e-12


def trace(objects, origin, directions):
    """trace_analytic over a list of nodes, for rays (N, 3) normalised here."""
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    return trace_analytic(scene_parts(objects), np.asarray(origin, dtype=np.float64), d)


def test_sphere_depth_and_normal_at_two_pixels_match_the_hand_computed_values():
    # Camera at z = 5 looking at a unit sphere, 3x3 pixels, tan(fov / 2) = 0.3. The centre
    # pixel looks straight down -z: t = 5 - 1. Pixel (x=2, y=1) has sx = (2 * 2.5 / 3 - 1)
    # * 0.3 = 0.2, so d = (1, 0, -5) / sqrt(26); |o + t d|^2 = 1 gives t^2 - 50 t / sqrt(26)
    # + 24 = 0, whose near root is t = 24 / sqrt(26), at the point (12, 0, 5) / 13.
    scene = Scene(camera=Camera(position=(0, 0, 5), look_at=(0, 0, 0),
                                fov=2 * math.degrees(math.atan(0.3))),
                  objects=(sphere(1.0),))
    truth = ground_truth(scene, 3, 3)
    assert truth.depth[1, 1] == pytest.approx(4.0, abs=TOL)
    np.testing.assert_allclose(truth.normal[1, 1], [0, 0, 1], atol=TOL)
    assert truth.depth[1, 2] == pytest.approx(24 / math.sqrt(26), abs=TOL)
    np.testing.assert_allclose(truth.normal[1, 2], [12 / 13, 0, 5 / 13], atol=TOL)
    assert truth.hit[1, 1] and truth.object_id[1, 1] == 0


def test_sphere_far_from_the_ray_origin_keeps_full_precision():
    # A ray from 1e6 away that just skims a unit sphere: the school formula's b^2 - c
    # cancels ~12 of its 16 digits here; the Ray Tracing Gems form keeps t to 1e-9
    # relative. The ray passes the centre at distance 0.6, so t = 1e6 - 0.8.
    origin = [0.6, 0.0, 1e6]
    t, normal, _ = trace([sphere(1.0)], origin, [[0.0, 0.0, -1.0]])
    assert t[0] == pytest.approx(1e6 - 0.8, rel=1e-15, abs=1e-9)
    np.testing.assert_allclose(normal[0], [0.6, 0.0, 0.8], atol=1e-9)


@pytest.mark.parametrize("axis", range(3))
@pytest.mark.parametrize("side", (-1.0, 1.0))
def test_box_ray_hits_each_face_at_its_distance_with_its_normal(axis, side):
    # Box of half-sizes (1, 2, 3); a ray from 10 along the axis, aimed back at the box and
    # tilted by 0.1 along the next axis, meets the face at |x_axis| = h after
    # t = (10 - h) / |d_axis|.
    half = np.array([1.0, 2.0, 3.0])
    origin = np.array([0.2, -0.3, 0.1])
    origin[axis] = 10 * side
    direction = np.zeros(3)
    direction[axis] = -side
    direction[(axis + 1) % 3] = 0.1
    direction /= np.linalg.norm(direction)
    t, normal, object_id = trace([box(*half)], origin, [direction])
    expected_t = (10 - half[axis]) / abs(direction[axis])
    assert t[0] == pytest.approx(expected_t, abs=TOL)
    expected_normal = np.zeros(3)
    expected_normal[axis] = side
    np.testing.assert_allclose(normal[0], expected_normal, atol=TOL)
    point = origin + t[0] * direction
    assert np.all(np.abs(point) <= half + TOL)
    assert object_id[0] == 0


def test_box_ray_parallel_to_a_face_hits_inside_its_slab_and_misses_outside():
    # Along -z with d_x = d_y = 0: the slab test divides by zero there. Inside the slabs
    # (|y| = 1.99 < 2) the ray meets the +z face at t = 10 - 3; outside (|y| = 2.01) nothing.
    t, normal, _ = trace([box(1.0, 2.0, 3.0)], [0.0, 1.99, 10.0], [[0.0, 0.0, -1.0]])
    assert t[0] == pytest.approx(7.0, abs=TOL)
    np.testing.assert_allclose(normal[0], [0, 0, 1], atol=TOL)
    t, normal, object_id = trace([box(1.0, 2.0, 3.0)], [0.0, 2.01, 10.0], [[0.0, 0.0, -1.0]])
    assert np.isinf(t[0]) and object_id[0] == -1 and not normal[0].any()


def test_rotated_scaled_box_is_hit_on_its_front_edge_as_in_its_own_frame():
    # A cube of half-size 0.5 turned 45 degrees about y, scaled by 2 and moved to x = 1,
    # shows an edge to a camera on +z: its front faces are |x - 1| + z = sqrt(2). A ray
    # along -z from (1 + u, 0, 5) meets them at z = sqrt(2) - |u|, with normal
    # (sign(u), 0, 1) / sqrt(2).
    node = box(0.5).rotate(0, 45, 0).scale(2.0).at(1.0, 0.0, 0.0)
    for u in (-0.9, -0.3, 0.25, 1.1):
        t, normal, _ = trace([node], [1.0 + u, 0.0, 5.0], [[0.0, 0.0, -1.0]])
        assert t[0] == pytest.approx(5.0 - (math.sqrt(2) - abs(u)), abs=TOL)
        np.testing.assert_allclose(normal[0], [math.copysign(1, u) / math.sqrt(2), 0,
                                               1 / math.sqrt(2)], atol=TOL)
    t, _, _ = trace([node], [1.0 + 1.5, 0.0, 5.0], [[0.0, 0.0, -1.0]])   # past the corner
    assert np.isinf(t[0])


@pytest.mark.parametrize("angle", (1e-1, 1e-3, 1e-6))
def test_plane_grazing_ray_hits_at_height_over_sine(angle):
    # From 1 above the plane y = 0.5 (given with a normal of length 2), a ray dipping by
    # `angle` radians meets it at t = 1 / sin(angle): 1e6 for the shallowest.
    direction = [math.cos(angle), -math.sin(angle), 0.0]
    t, normal, _ = trace([plane(normal=(0, 2, 0), offset=0.5)], [0.0, 1.5, 0.0], [direction])
    assert t[0] == pytest.approx(1 / math.sin(angle), rel=1e-12)
    np.testing.assert_allclose(normal[0], [0, 1, 0], atol=TOL)


def test_plane_ray_parallel_or_rising_misses_and_from_below_sees_the_underside():
    floor = [plane()]
    t, _, _ = trace(floor, [0, 1, 0], [[1, 0, 0], [1, 0.1, 0]])
    assert np.isinf(t).all()
    # A ray that starts inside the solid (below the floor) walks out to its surface, as the
    # sphere tracer does: the floor 2 above, seen from inside (normal along the ray).
    t, normal, _ = trace(floor, [0, -2, 0], [[0, 1, 0], [0, -1, 0]])
    assert t[0] == pytest.approx(2.0, abs=TOL) and np.isinf(t[1])
    np.testing.assert_allclose(normal[0], [0, 1, 0], atol=TOL)


def test_ray_inside_overlapping_solids_leaves_through_the_union_not_the_first_shell():
    # From the centre of a unit sphere that overlaps a sphere at x = 1.5 (radius 1), a ray
    # along +x leaves the first at x = 1, inside the second, and the union at x = 2.5.
    t, normal, object_id = trace([sphere(1.0), sphere(1.0).at(1.5, 0, 0)], [0, 0, 0],
                                 [[1, 0, 0], [-1, 0, 0]])
    np.testing.assert_allclose(t, [2.5, 1.0], atol=TOL)
    np.testing.assert_allclose(normal, [[1, 0, 0], [-1, 0, 0]], atol=TOL)
    assert object_id.tolist() == [1, 0]


def test_object_ids_are_depth_first_through_unions_and_transforms():
    # ids: plane 0, union(sphere 1, box 2), sphere 3. Rays straight down onto each.
    objects = [plane(), union(sphere(0.5).at(-2, 1, 0), box(0.5).at(0, 1, 0)).at(0, 0, 1),
               sphere(0.5).at(2, 1, 0)]
    origins = {0: [5, 5, 5], 1: [-2, 5, 1], 2: [0, 5, 1], 3: [2, 5, 0]}
    for expected, origin in origins.items():
        _, _, object_id = trace(objects, origin, [[0, -1, 0]])
        assert object_id[0] == expected


def test_unsupported_node_is_named_with_its_path():
    scene = Scene(objects=(plane(), sphere(), union(box(), torus().at(0, 1, 0)).at(1, 0, 0)))
    with pytest.raises(SceneError) as caught:
        ground_truth(scene, 4, 3)
    assert str(caught.value) == ("objects[2].children[1]: 'torus' has no analytic "
                                 "intersection (the analytic method takes unions of spheres, "
                                 "boxes and planes); use --method embree")


def test_a_morph_is_refused_by_the_analytic_method_naming_it():
    scene = Scene(objects=(plane(), sphere().morph(box(), 0.5).at(0, 1, 0)))
    with pytest.raises(SceneError) as caught:
        ground_truth(scene, 4, 3)
    assert str(caught.value) == ("objects[1]: 'morph' has no analytic intersection (the "
                                 "analytic method takes unions of spheres, boxes and planes); "
                                 "use --method embree")


def test_hits_beyond_max_distance_are_misses():
    # The floor seen from 1 above at a dip of 0.01 rad lies 100 away; with max_distance 50
    # the contract (and so the truth) sees nothing there.
    scene = Scene(camera=Camera(position=(0, 1, 0), look_at=(1, 1 - math.tan(0.01), 0),
                                fov=1.0),
                  render=RenderSettings(max_distance=50.0), objects=(plane(),))
    truth = ground_truth(scene, 1, 1)
    assert not truth.hit[0, 0] and np.isinf(truth.depth[0, 0]) and truth.object_id[0, 0] == -1


# --- A property over random scenes: every hit lies on the SDF's zero set ----------------------

positions = st.tuples(*[st.floats(-2, 2)] * 3)
angles = st.tuples(*[st.floats(-180, 180)] * 3)
shapes = st.one_of(
    st.builds(lambda r, p, a, s: sphere(r).rotate(*a).scale(s).at(*p),
              st.floats(0.1, 1.5), positions, angles, st.floats(0.5, 2)),
    st.builds(lambda h, p, a, s: box(*h).rotate(*a).scale(s).at(*p),
              st.tuples(*[st.floats(0.1, 1)] * 3), positions, angles, st.floats(0.5, 2)),
    st.builds(lambda n, h: plane(normal=n, offset=h),
              st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda n: np.linalg.norm(n) > 0.1),
              st.floats(-3, -1)),
)


@settings(max_examples=40)
@given(objects=st.lists(shapes, min_size=1, max_size=4))
def test_every_analytic_hit_lies_on_the_scene_sdf_zero_set_with_its_gradient_as_normal(objects):
    # The scene SDF of reference_cpu (float64) is an independent description of the same
    # surfaces: at a true first hit it is 0 (up to rounding: 1e-9 for numbers below ~20)
    # and not negative (a hit inside another solid would be), and its gradient, by central
    # differences with h = 1e-6 (error O(h^2) plus 1e-16 / h), is the normal: 1e-6 away
    # from edges, where the normal is undefined; at least 80% of the hits are off edges.
    scene = Scene(camera=Camera(position=(0.3, 0.5, 8.0), look_at=(0, 0, 0), fov=60),
                  objects=tuple(objects))
    truth = ground_truth(scene, 16, 12)
    assert truth.measured_error <= 1e-9
    from scene_model.camera import camera_rays
    origin, directions = camera_rays(scene.camera, 16, 12)
    points = origin + np.where(truth.hit, truth.depth, 0)[..., None] * directions
    points = points[truth.hit]
    sdf = build_scene_sdf(scene.objects, np.float64)
    h = 1e-6
    gradient = np.stack([sdf(points + h * e)[0] - sdf(points - h * e)[0] for e in np.eye(3)],
                        axis=1) / (2 * h)
    normal = truth.normal[truth.hit]
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, atol=TOL)
    smooth = np.abs(np.linalg.norm(gradient, axis=1) - 1) < 1e-6   # off edges and corners
    assert smooth.sum() >= 0.8 * len(points)
    np.testing.assert_allclose(normal[smooth], gradient[smooth], atol=1e-6)
