"""The Embree ground truth (meshes ray-cast in float32) against the analytic truth and the
NumPy reference, and the meshes themselves against closed forms.

A mesh point p lies at distance |sdf(p)| from the true surface (exact SDF); along a ray that
meets the surface at angle theta to its normal, that is a depth error of |sdf(p)| / |cos theta|
to first order in the surface's curvature. Every depth tolerance below is of that form, with
the bound the method states or the error it measured, and is checked away from silhouettes
(within 1 px of one, a mesh's edge may lie on either side of the true edge).
"""

import math

import numpy as np
import pytest
from truth_scenes import (CSG, EPSILON, HEIGHT, SPHERE_PLANE_BOX, WIDTH, cos_incidence,
                          near_silhouette)

import marchlab
from reference_cpu.scene_sdf import build_scene_sdf
from reference_cpu.truth import ground_truth
from scene_model.builder import Camera, RenderSettings, Scene, box, sphere
from scene_model.errors import SceneError
from scene_model.shapes import Scale

pytestmark = pytest.mark.usefixtures("embree")

RESOLUTION = 64


@pytest.fixture(scope="module")
def tessellated(embree):
    """SPHERE_PLANE_BOX by both methods: its sphere is an icosphere, its boxes and plane exact."""
    return (ground_truth(SPHERE_PLANE_BOX, WIDTH, HEIGHT, "embree", RESOLUTION),
            ground_truth(SPHERE_PLANE_BOX, WIDTH, HEIGHT, "analytic"))


@pytest.fixture(scope="module")
def csg(embree):
    """The CSG scene meshed by marching cubes, and the reference's render of it."""
    return (ground_truth(CSG, WIDTH, HEIGHT, "embree", RESOLUTION),
            marchlab.render(CSG, WIDTH, HEIGHT, backend="numpy"))


def rays(scene):
    return marchlab.camera_rays(scene.camera, WIDTH, HEIGHT)


# --- Embree against the analytic truth --------------------------------------------------------

def test_embree_hits_and_ids_match_analytic_away_from_silhouettes(tessellated):
    mesh, exact = tessellated
    away = ~near_silhouette(exact.object_id)
    np.testing.assert_array_equal(mesh.hit[away], exact.hit[away])
    np.testing.assert_array_equal(mesh.object_id[away], exact.object_id[away])


def test_embree_depth_matches_analytic_within_its_computed_bound(tessellated):
    # The bound is the icosphere's computed distance from the sphere plus float32 rounding
    # (the boxes and the plane are exact meshes); as a depth, over |cos theta|.
    mesh, exact = tessellated
    _, directions = rays(SPHERE_PLANE_BOX)
    core = mesh.hit & exact.hit & ~near_silhouette(exact.object_id)
    error = np.abs(mesh.depth[core] - exact.depth[core])
    cos = cos_incidence(exact.normal, directions)[core]
    assert mesh.error_terms["tessellation"] > 0 and mesh.error_terms["mesh"] == 0
    assert np.all(error * cos <= mesh.error_bound), (error * cos).max()


def test_embree_normals_match_analytic_within_a_facets_tilt(tessellated):
    # On the exact boxes and plane only float32 rounding separates the normals (1e-5). A flat
    # facet of an icosphere whose vertices lie on a sphere of radius r, at most delta inside
    # it, tilts from the sphere's normal by at most asin(rho / r) ~ sqrt(2 delta / r), with
    # rho its circumradius; r = 0.8 here. 2e-3 covers the analytic normal being taken at the
    # true hit, a little way along the ray from the facet's.
    mesh, exact = tessellated
    core = mesh.hit & exact.hit & ~near_silhouette(exact.object_id)
    error = np.linalg.norm(mesh.normal - exact.normal, axis=-1)
    on_sphere = core & (exact.object_id == 1)
    assert error[core & ~on_sphere].max() <= 1e-5
    assert error[on_sphere].max() <= math.sqrt(2 * mesh.error_terms["tessellation"] / 0.8) + 2e-3


def test_embree_from_inside_overlapping_solids_leaves_through_the_union(embree):
    # The camera sits inside a sphere that overlaps another and a box: the shells crossed
    # inside the other solids are not surfaces of the union, and Embree, which sees every
    # triangle, must be cast again past them (reference_cpu.truth.embree).
    scene = Scene(camera=Camera(position=(0, 0, 0.2), look_at=(0, 0, -1), fov=90),
                  objects=(sphere(1.0), sphere(0.8).at(0.9, 0, 0),
                           sphere(0.5).at(0, 0, -1.2)))
    mesh = ground_truth(scene, 32, 24, "embree", RESOLUTION)
    exact = ground_truth(scene, 32, 24, "analytic")
    _, directions = marchlab.camera_rays(scene.camera, 32, 24)
    core = ~near_silhouette(exact.object_id)
    assert exact.hit.all() and mesh.hit.all()
    np.testing.assert_array_equal(mesh.object_id[core], exact.object_id[core])
    cos = cos_incidence(exact.normal, directions)[core]
    error = np.abs(mesh.depth[core] - exact.depth[core])
    assert np.all(error * cos <= mesh.error_bound), (error * cos).max()


@pytest.mark.parametrize("factor", (1e-3, 1e3))
def test_embree_depth_scales_with_the_scene(embree, factor):
    # Embree works in float32 in a box 100 units wide whatever the scene's size, as trimesh
    # does; so a scene scaled by 1000 or by 1/1000 gives the same depths scaled, to float32
    # rounding (relative 1e-5 leaves room for the rescaling's own few ulps).
    scene = SPHERE_PLANE_BOX
    camera = scene.camera
    scaled = Scene(camera=Camera(position=tuple(factor * c for c in camera.position),
                                 look_at=tuple(factor * c for c in camera.look_at),
                                 fov=camera.fov),
                   render=RenderSettings(epsilon=EPSILON * factor,
                                         max_distance=scene.render.max_distance * factor),
                   objects=tuple(Scale(node, factor) for node in scene.objects))
    small = ground_truth(scene, 32, 24, "embree", 32)
    big = ground_truth(scaled, 32, 24, "embree", 32)
    np.testing.assert_array_equal(big.hit, small.hit)
    np.testing.assert_allclose(big.depth[big.hit] / factor, small.depth[small.hit], rtol=1e-5)
    assert big.error_bound / factor == pytest.approx(small.error_bound, rel=1e-5)


def test_limited_repeat_meshed_by_marching_cubes_matches_the_analytic_copies(embree):
    # repeat(sphere, period 1 along x, count 1) is three spheres: marching cubes meshes the
    # repeat node, the analytic method intersects the three spheres one by one.
    camera = Camera(position=(0.2, 1.0, 4.0), look_at=(0, 0, 0), fov=45)
    repeated = Scene(camera=camera, objects=(sphere(0.35).repeat((1.0, 0.0, 0.0), (1, 0, 0)),))
    copies = Scene(camera=camera, objects=tuple(sphere(0.35).at(x, 0, 0) for x in (-1, 0, 1)))
    mesh = ground_truth(repeated, 32, 24, "embree", RESOLUTION)
    exact = ground_truth(copies, 32, 24, "analytic")
    _, directions = marchlab.camera_rays(camera, 32, 24)
    core = mesh.hit & exact.hit & ~near_silhouette(exact.hit.astype(int))
    error = np.abs(mesh.depth[core] - exact.depth[core])
    assert mesh.error_terms["mesh"] > 0
    assert np.all(error * cos_incidence(exact.normal, directions)[core] <= mesh.error_bound)


@pytest.mark.parametrize("t", [0.0, 0.6])
def test_a_morph_is_meshed_through_its_sdf_and_agrees_with_the_reference(embree, t):
    """Marching cubes meshes a morph like any other subtree, from its field. At t = 0 it is
    the sphere, hit where the analytic sphere is hit; at t = 0.6 its hits and ids (the box's,
    past one half) are the NumPy reference's, away from the silhouette."""
    camera = Camera(position=(0.2, 1.0, 4.0), look_at=(0, 0, 0), fov=45)
    morphed = Scene(camera=camera, objects=(sphere(0.6).morph(box(0.45).rotate(0, 30, 0), t),))
    mesh = ground_truth(morphed, 32, 24, "embree", RESOLUTION)
    if t == 0.0:
        exact = ground_truth(Scene(camera=camera, objects=(sphere(0.6),)), 32, 24, "analytic")
    else:
        exact = marchlab.render(morphed, 32, 24, backend="numpy")
    core = ~near_silhouette(exact.hit.astype(int))
    np.testing.assert_array_equal(mesh.hit[core], exact.hit[core])
    np.testing.assert_array_equal(mesh.object_id[core], exact.object_id[core])
    assert set(np.unique(mesh.object_id[mesh.hit])) == {0 if t <= 0.5 else 1}


def test_an_empty_solid_is_no_mesh_and_hides_nothing(embree):
    # Two disjoint spheres intersected hold no point: marching cubes finds no surface, and
    # the sphere behind is seen as if the intersection were not there.
    camera = Camera(position=(0, 0, 5), look_at=(0, 0, 0), fov=40)
    empty = sphere(0.5).at(-1, 0, 2) & sphere(0.5).at(1, 0, 2)
    alone = ground_truth(Scene(camera=camera, objects=(empty,)), 16, 12, "embree", 16)
    assert not alone.hit.any()
    behind = ground_truth(Scene(camera=camera, objects=(empty, sphere(1.0))), 16, 12,
                          "embree", 16)
    exact = ground_truth(Scene(camera=camera, objects=(sphere(1.0),)), 16, 12)
    np.testing.assert_array_equal(behind.hit, exact.hit)
    assert set(np.unique(behind.object_id)) == {-1, 2}     # the empty one held ids 0 and 1


def test_unbounded_repeat_is_refused_with_its_path(embree):
    scene = Scene(objects=(sphere(), sphere(0.2).repeat((1.0, 0.0, 1.0))))
    with pytest.raises(SceneError) as caught:
        ground_truth(scene, 4, 3, "embree", 16)
    assert str(caught.value) == ("objects[1]: 'repeat' repeats forever (give it a count); "
                                 "the embree method meshes bounded shapes only")


# --- Embree on CSG against the reference --------------------------------------------------------

def test_marching_cubes_error_is_measured_within_the_half_cell_bound(csg):
    mesh, _ = csg
    assert mesh.error_terms["mesh"] > 0
    assert 0 < mesh.measured_error_p99 <= mesh.measured_error <= mesh.error_bound


def test_embree_csg_hits_and_ids_match_the_reference_away_from_silhouettes(csg):
    mesh, frame = csg
    away = ~near_silhouette(mesh.object_id)
    differ = (mesh.hit != frame.hit) & away
    assert not np.any(differ & (frame.steps < CSG.render.max_steps))
    core = away & mesh.hit & frame.hit
    np.testing.assert_array_equal(mesh.object_id[core], frame.object_id[core])


def test_embree_csg_depth_matches_the_reference_within_measured_error_plus_epsilon(csg):
    # Depth errors add: the mesh's, |sdf(p)| <= measured_error at its hit p, and the
    # tracer's, under epsilon; both become depth errors over g |cos theta|, where g = |grad
    # sdf| (1 for an exact SDF, less inside a smooth blend, where the SDF is only a bound;
    # estimated here by central differences, h = 1e-4). Float32 rounding is in the bound.
    mesh, frame = csg
    origin, directions = rays(CSG)
    core = mesh.hit & frame.hit & ~near_silhouette(mesh.object_id)
    points = origin + mesh.depth[core][:, None] * directions[core]
    sdf = build_scene_sdf(CSG.objects, np.float64)
    h = 1e-4
    g = np.linalg.norm(np.stack([sdf(points + h * e)[0] - sdf(points - h * e)[0]
                                 for e in np.eye(3)], axis=1), axis=1) / (2 * h)
    cos = cos_incidence(frame.normal, directions)[core]
    error = np.abs(mesh.depth[core] - frame.depth[core])
    allowed = (mesh.measured_error + EPSILON) / (g * cos) + mesh.error_terms["rounding"] / cos
    assert np.all(error <= allowed), (error / allowed).max()


# --- Winding ------------------------------------------------------------------------------------

@pytest.mark.parametrize("which", ("tessellated", "csg"))
def test_normals_face_the_camera_on_every_visible_surface(which, request):
    # The camera is outside every solid, so every surface it sees faces it: n . d < 0 at
    # every hit. An inward-wound mesh (or an Ng left unoriented) turns some or all around.
    truth = request.getfixturevalue(which)[0]
    scene = SPHERE_PLANE_BOX if which == "tessellated" else CSG
    _, directions = rays(scene)
    facing = np.sum(truth.normal * directions, axis=-1)[truth.hit]
    assert np.all(facing < 0)
    np.testing.assert_allclose(np.linalg.norm(truth.normal[truth.hit], axis=-1), 1, atol=1e-12)
