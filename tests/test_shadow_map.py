"""Shadow maps (`reference_cpu.shadow_map`) against the exact shadows and their known
artefacts, measured.

The exact shadows are the NumPy shadow volumes' (`reference_cpu.shadow_volumes`, equal to
Embree's shadow rays but beside an edge: tests/truth/test_raster_shadows_against_embree.py).
On "cube and cone on a floor" at 96 x 72 (numbers measured, bounds stated in each test):
with a good bias (1 mm and a slope bias of 1.5 texels) a 2048 map agrees but within a pixel
of an edge; with no bias half the lit pixels shadow themselves (acne); the
pixels wrong fall from 276 to 78 to 34 as the point light's map grows from 256 to 1024 to
4096 texels (aliasing); and beside a thin wall a large bias lights exactly the shadowed
floor whose occluder is nearer than the bias (peter-panning).
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu.rasterise import rasterise
from reference_cpu.shadow_map import (CUBE_AXES, cube_face, depth_map, light_view,
                                      light_views, map_coordinates, shadow_map_visibility,
                                      surface_points)
from reference_cpu.shadow_volumes import shadow_volume_visibility
from scene_model.meshes import cube, plane, transformed
from scene_model.scene import Camera, DirectionalLight, PointLight

LIGHTS = {"point": PointLight(position=(-1.0, 3.0, -2.5)),
          "directional": DirectionalLight(direction=(0.5, -1.0, 0.9))}
GOOD_BIAS, GOOD_SLOPE = 1e-3, 1.5
MESHES = SCENES["cube and cone on a floor"]


def exact_shadows(light):
    raster = rasterise(MESHES, CAMERA, WIDTH, HEIGHT)
    return raster, shadow_volume_visibility(MESHES, raster, CAMERA, light)


def test_orthographic_map_of_a_floor_holds_its_plane_depth_at_texel_centres():
    """Each texel centre's ray along the light meets the floor y = 0 at a depth known in
    closed form; the map holds it to float32 rounding (1e-5 m) wherever it meets it."""
    floor = plane(6.0, 6.0, subdivisions=4)
    view = light_view([floor], DirectionalLight(direction=(0.5, -1.0, 0.9)), 64)
    stored = depth_map([floor], view)
    j, i = np.mgrid[0:64, 0:64] + 0.5
    right, up, forward = view.frame
    q0 = view.low[0] + i * view.texel
    q1 = view.low[1] + (64 - j) * view.texel
    depth = -(right[1] * q0 + up[1] * q1) / forward[1]
    drawn = np.isfinite(stored)
    assert drawn.sum() > 0.3 * 64 * 64
    np.testing.assert_allclose(stored[drawn], depth[drawn], atol=1e-5)


@pytest.mark.parametrize("name", LIGHTS)
def test_good_bias_agrees_with_the_exact_shadows_but_beside_an_edge(name):
    raster, exact = exact_shadows(LIGHTS[name])
    visibility = shadow_map_visibility(MESHES, raster, CAMERA, LIGHTS[name], 2048, GOOD_BIAS,
                                       GOOD_SLOPE)
    near = dilate(boundary(exact) | boundary(raster.object_id), 1)
    wrong = visibility != exact
    assert (exact == 0).sum() > 1000
    assert not (wrong & ~near).any()
    assert wrong.sum() <= 0.05 * near.sum()


@pytest.mark.parametrize("name", LIGHTS)
def test_no_bias_makes_lit_surfaces_shadow_themselves(name):
    """Acne: measured 50% (point) and 49% (directional) of lit pixels shadowed at bias 0,
    0.5% and 0.2% with the good bias."""
    raster, exact = exact_shadows(LIGHTS[name])
    lit = raster.hit & (exact == 1)
    acne = {}
    for bias, slope in [(0.0, 0.0), (GOOD_BIAS, GOOD_SLOPE)]:
        visibility = shadow_map_visibility(MESHES, raster, CAMERA, LIGHTS[name], 1024, bias,
                                           slope)
        acne[bias] = (lit & (visibility < 1)).sum() / lit.sum()
    assert acne[0.0] > 0.3 and acne[GOOD_BIAS] < 0.01


@pytest.mark.parametrize("name", LIGHTS)
def test_aliasing_error_falls_as_the_map_grows(name):
    """Pixels wrong, of the 4,463 drawn: 6.2%, 1.7%, 0.76% (point) and 1.6%, 0.36%, 0.36%
    (directional, whose 1024 map is already finer than the picture) at 256, 1024, 4096."""
    raster, exact = exact_shadows(LIGHTS[name])
    error = [((shadow_map_visibility(MESHES, raster, CAMERA, LIGHTS[name], size, GOOD_BIAS,
                                     GOOD_SLOPE) != exact) & raster.hit).sum() / raster.hit.sum()
             for size in (256, 1024, 4096)]
    assert error[0] > 2 * error[1] >= 2 * error[2] * (1 - 1e-12)
    assert error[2] < 0.01


def wall_scene():
    """A wall 4 cm thick, 1 m high and 1.2 m wide on a floor, lit at 45 degrees across it."""
    wall = transformed(cube(1.0), np.array([[0.04, 0, 0, 0], [0, 1, 0, 0.5],
                                            [0, 0, 1.2, 0], [0, 0, 0, 1.0]]))
    camera = Camera(position=(1.8, 1.4, 1.8), look_at=(0.5, 0.0, 0.0), fov=50.0)
    return [wall, plane(6.0, 6.0, 4)], DirectionalLight(direction=(1.0, -1.0, 0.0)), camera


def occluder_gap(points, towards, low, high):
    """How far (N,) along ``towards`` from each point the ray leaves the box [low, high], that
    is, how far the surface the light sees first lies from the point (slab method, Kay and
    Kajiya 1986); nan where it misses."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (low - points) / towards, (high - points) / towards
    near = np.max(np.minimum(a, b), axis=-1)
    far = np.min(np.maximum(a, b), axis=-1)
    return np.where((far >= np.maximum(near, 0.0)) & (far > 0), far, np.nan)


def test_large_bias_lights_the_shadow_nearer_to_its_occluder_than_the_bias():
    """Peter-panning: a floor point in the wall's shadow whose wall is g away along the light
    passes the test when g <= bias, so the shadow comes loose from the wall's foot. Every
    floor pixel agrees with that rule but beside an edge or within 2 cm of g = bias (two
    texels of a 1024 map); the gap is measured 2.0, 4.4, 6.4 and 8.2 pixels wide (mean per
    image column) for biases of 0.2, 0.4, 0.6 and 0.8 m."""
    meshes, light, camera = wall_scene()
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    towards = -np.asarray(light.direction) / np.linalg.norm(light.direction)
    gap = occluder_gap(surface_points(raster, camera), towards, np.array([-0.02, 0, -0.6]),
                       np.array([0.02, 1.0, 0.6]))
    shadow = (raster.object_id == 1) & np.isfinite(gap)
    edge = dilate(boundary(shadow) | boundary(raster.object_id), 1)
    widths = []
    for bias in (0.2, 0.4, 0.6, 0.8):
        visibility = shadow_map_visibility(meshes, raster, camera, light, 1024, bias)
        missed = shadow & (visibility == 1)
        predicted = shadow & (gap <= bias)
        clear = ~edge & ~(np.abs(gap - bias) <= 0.02)
        assert np.array_equal(missed[clear], predicted[clear])
        widths.append(missed.sum() / len(np.unique(np.nonzero(missed)[1])))
    assert shadow.sum() > 500 and np.all(np.diff(widths) > 1.0)


def test_percentage_closer_filtering_softens_only_the_edges():
    """3 x 3 PCF gives ninths, and fractions only within 3 pixels of an exact edge
    (directional light, 256 map, where a texel is about a pixel; its slope bias covers the
    kernel's reach)."""
    raster, exact = exact_shadows(LIGHTS["directional"])
    plain = shadow_map_visibility(MESHES, raster, CAMERA, LIGHTS["directional"], 256,
                                  GOOD_BIAS, 2.5, pcf=1)
    soft = shadow_map_visibility(MESHES, raster, CAMERA, LIGHTS["directional"], 256,
                                 GOOD_BIAS, 2.5, pcf=3)
    assert set(np.unique(plain)) <= {0.0, 1.0}
    np.testing.assert_allclose(soft * 9, np.round(soft * 9), atol=1e-12)
    partial = (soft > 0) & (soft < 1)
    assert partial.sum() > 50
    assert not (partial & ~dilate(boundary(exact), 3)).any()


def test_an_even_kernel_is_refused():
    raster, _ = exact_shadows(LIGHTS["point"])
    with pytest.raises(ValueError, match="odd"):
        shadow_map_visibility(MESHES, raster, CAMERA, LIGHTS["point"], 64, GOOD_BIAS, pcf=2)


# A point light among the objects: between the cube and the cone, low, so that it shadows
# the floor on every side; no single frustum holds the scene.
AMONG = PointLight(position=(0.2, 0.45, 0.4))


def test_a_light_among_the_objects_gets_a_cube_of_six_square_maps():
    with pytest.raises(ValueError, match="cube map"):
        light_view(MESHES, AMONG, 64)
    views = light_views(MESHES, AMONG, 64)
    assert len(views) == 6 and all(v.camera.fov == 90.0 for v in views)
    assert light_views(MESHES, LIGHTS["point"], 64) == [light_view(MESHES, LIGHTS["point"], 64)]
    # Each face looks along its axis, and a point leaning towards an axis falls inside that
    # face's map, within its square (texel coordinates in [0, S]).
    rng = np.random.default_rng(5)
    points = np.asarray(AMONG.position) + rng.normal(size=(2000, 3))
    face = cube_face(points, AMONG.position)
    for k, view in enumerate(views):
        forward = np.subtract(view.camera.look_at, view.camera.position)
        np.testing.assert_allclose(forward, CUBE_AXES[k], atol=1e-15)
        image, depth = map_coordinates(view, points[face == k])
        assert np.all(depth > 0) and np.all((image >= 0) & (image <= 64))
    assert np.array_equal(np.bincount(face, minlength=6) > 200, [True] * 6)


def test_a_cube_map_agrees_with_the_exact_shadows_but_beside_an_edge_or_a_seam():
    """A point light among the objects: with a good bias a 1024 cube map shadows the pixels
    the shadow volumes do, but within a pixel of an edge of the shadows or the objects, or
    of a seam between two faces (where the 3 x 3 filter is clamped at its face's edge;
    measured: no pixel wrong away from an edge, 11 of 4,463 drawn beside one)."""
    raster, exact = exact_shadows(AMONG)
    assert (raster.hit & (exact == 0)).sum() > 500 and (raster.hit & (exact == 1)).sum() > 500
    visibility = shadow_map_visibility(MESHES, raster, CAMERA, AMONG, 1024, GOOD_BIAS,
                                       GOOD_SLOPE)
    face = np.full(raster.hit.shape, -1)
    face[raster.hit] = cube_face(surface_points(raster, CAMERA)[raster.hit], AMONG.position)
    assert len(np.unique(face[raster.hit])) >= 4          # the picture spans several faces
    near = dilate(boundary(exact) | boundary(raster.object_id) | boundary(face), 1)
    wrong = (visibility != exact) & raster.hit
    assert not (wrong & ~near).any()
    assert wrong.sum() <= 0.05 * near.sum()
