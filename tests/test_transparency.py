"""Transparency in the NumPy raster reference (`reference_cpu.transparency`): one pane against
Porter and Duff's "over" written out, depth peeling's independence of the order triangles
come in, and what too few peeling passes drop; the batched fragments
(`transparent_fragments_batched`) are the one-triangle-at-a-time ones, bit for bit. Against
the ray-cast truth: tests/truth/test_raster_transparency_against_embree.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import marchlab
from mesh_scenes import CAMERA, turned
from reference_cpu.rasterise import rasterise
from reference_cpu.rasterise_batched import clipped_triangle_batch
from reference_cpu.raster_shading import shade_raster
from reference_cpu.transparency import (depth_complexity, depth_peel, opaque_pass,
                                        sorted_blend, transparent_fragments)
from scene_model.camera import Camera
from scene_model.mesh_world import scene_meshes
from scene_model.meshes import TriangleMesh, cube, plane, transformed, uv_sphere
from scene_model.scene import DirectionalLight, Material, PointLight

WIDTH, HEIGHT = 96, 72
LIGHTS = (PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),
          DirectionalLight(direction=(1.0, -1.0, -0.5), intensity=0.5))
SHADE = dict(ambient=(0.1, 0.1, 0.1), background=(0.2, 0.3, 0.4))
GREY, RED = Material(color=(0.6, 0.6, 0.6)), Material(color=(0.8, 0.3, 0.2))
BLUE = Material(color=(0.2, 0.4, 0.9), transparency=0.6)
YELLOW = Material(color=(0.9, 0.8, 0.2), transparency=0.4)
GREEN = Material(color=(0.3, 0.9, 0.3), transparency=0.5)


def pane(width, height, degrees, offset):
    """A width x height rectangle standing upright (facing +z), turned about y and moved."""
    upright = transformed(plane(width, height), [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0],
                                                 [0, 0, 0, 1]])
    return turned(upright, degrees, offset)


def ball(radius, offset):
    m = np.eye(4)
    m[:3, 3] = offset
    return transformed(uv_sphere(radius, 16, 8), m)


# Panes one behind the other (a centroid sort orders every pixel right) and a see-through
# ball (its front and back faces are two layers), over an opaque floor and cube.
SEPARATE = ([plane(6.0, 6.0), turned(cube(0.6), 20, (0.3, 0.3, -1.5)),
             pane(1.6, 1.2, 0, (-0.3, 0.7, 0.6)), pane(1.4, 1.0, 10, (0.2, 0.6, -0.3)),
             ball(0.35, (0.6, 0.4, 1.2))],
            [GREY, RED, BLUE, YELLOW, GREEN])
# Two panes crossing in an X: on part of the picture each is in front of the other.
CROSSED = ([plane(6.0, 6.0), pane(1.6, 1.2, 35, (0.0, 0.7, 0.0)),
            pane(1.6, 1.2, -35, (0.0, 0.7, 0.0))],
           [GREY, BLUE, YELLOW])


def test_one_pane_is_its_colour_over_the_picture_behind_it():
    """alpha c + (1 - alpha) C_behind with alpha = 1 - transparency = 0.4, each colour from
    `shade_raster` of the pane alone and of the floor alone (1e-15)."""
    floor, glass = plane(6.0, 6.0), pane(1.6, 1.2, 20, (0.0, 0.7, 0.0))
    got = depth_peel([floor, glass], [GREY, BLUE], LIGHTS, CAMERA, WIDTH, HEIGHT, 4, **SHADE)
    behind = shade_raster(rasterise([floor], CAMERA, WIDTH, HEIGHT), CAMERA, [GREY], LIGHTS,
                          **SHADE)
    nothing = TriangleMesh(floor.positions, floor.normals, floor.uvs, floor.triangles[:0])
    front = rasterise([nothing, glass], CAMERA, WIDTH, HEIGHT)
    pane_color = shade_raster(front, CAMERA, [GREY, BLUE], LIGHTS, **SHADE)
    expected = np.where(front.hit[..., None], 0.4 * pane_color + 0.6 * behind, behind)
    assert front.hit.sum() > 500
    np.testing.assert_allclose(got, expected, atol=1e-15)
    np.testing.assert_allclose(sorted_blend([floor, glass], [GREY, BLUE], LIGHTS, CAMERA,
                                            WIDTH, HEIGHT, **SHADE), expected, atol=1e-15)


def test_without_transparent_materials_both_are_the_opaque_picture():
    meshes, materials = SEPARATE[0], [GREY, RED, GREY, RED, GREY]
    expected = shade_raster(rasterise(meshes, CAMERA, WIDTH, HEIGHT), CAMERA, materials, LIGHTS,
                            **SHADE)
    np.testing.assert_array_equal(sorted_blend(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT,
                                               **SHADE), expected)
    np.testing.assert_array_equal(depth_peel(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT,
                                             3, **SHADE), expected)


def test_depth_peeling_does_not_depend_on_the_order_triangles_come_in():
    """The crossed panes listed in the other order, each with its triangles reversed: the
    same picture (1e-15), as order-independent transparency must draw."""
    meshes, materials = CROSSED
    reversed_meshes = [TriangleMesh(m.positions, m.normals, m.uvs, m.triangles[::-1].copy())
                       for m in meshes]
    swapped = ([reversed_meshes[0], reversed_meshes[2], reversed_meshes[1]],
               [materials[0], materials[2], materials[1]])
    peeled = [depth_peel(m, mat, LIGHTS, CAMERA, WIDTH, HEIGHT, 4, **SHADE)
              for m, mat in (CROSSED, swapped)]
    np.testing.assert_allclose(peeled[0], peeled[1], atol=1e-15)


def test_too_few_passes_change_exactly_the_pixels_with_more_layers():
    """With k passes, a pixel differs from the full peel exactly where more than k
    transparent surfaces lie in front of the opaque ones."""
    meshes, materials = SEPARATE
    f = transparent_fragments(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT, **SHADE)
    _, opaque_depth = opaque_pass(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT, **SHADE)
    layers = depth_complexity(f, opaque_depth)
    assert layers.max() >= 3 and (layers > 1).sum() > 200
    full = depth_peel(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT, layers.max(), **SHADE)
    for k in range(1, layers.max()):
        fewer = depth_peel(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT, k, **SHADE)
        changed = np.abs(fewer - full).max(axis=-1) > 1e-12
        assert (layers > k).any()
        np.testing.assert_array_equal(changed, layers > k)


def assert_same_fragments(fast, loop):
    """Two `Fragments` equal field by field, in the same order, bit for bit."""
    for name in ("pixel", "depth", "color", "alpha", "order"):
        a, b = getattr(fast, name), getattr(loop, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert a.tobytes() == b.tobytes(), f"{name}: {np.sum(a != b)} values differ"


@pytest.mark.parametrize("model", ["phong", "toon", "normals"])
@pytest.mark.parametrize("scene", ["separate", "crossed"])
def test_batched_fragments_are_the_one_by_one_fragments(scene, model):
    meshes, materials = SEPARATE if scene == "separate" else CROSSED
    shade = dict(SHADE, model=model)
    fast = transparent_fragments(meshes, materials, LIGHTS, CAMERA, WIDTH, HEIGHT, **shade)
    assert len(fast.pixel) > 1000
    assert_same_fragments(fast, transparent_fragments(meshes, materials, LIGHTS, CAMERA, WIDTH,
                                                      HEIGHT, textbook=True, **shade))


def test_batched_fragments_are_the_one_by_one_fragments_through_the_near_plane():
    """The eye half a millimetre from a pane, looking along it: one of its triangles is cut
    at the near plane into two pieces that make one picture."""
    meshes, materials = SEPARATE
    camera = Camera(position=(-0.3, 0.7, 0.6005), look_at=(-2.0, 0.6, 0.0), fov=100.0)
    index, _ = clipped_triangle_batch(meshes[2], camera)
    assert len(index) == 3 and len(np.unique(index)) == 2
    fast = transparent_fragments(meshes, materials, LIGHTS, camera, 48, 36, **SHADE)
    assert len(fast.pixel) > 200
    assert_same_fragments(fast, transparent_fragments(meshes, materials, LIGHTS, camera, 48, 36,
                                                      textbook=True, **SHADE))


def test_batched_fragments_are_the_one_by_one_fragments_in_the_museum():
    """The museum's glass under its own lights and skybox background."""
    scene = marchlab.load_scene("museum")
    meshes, materials = scene_meshes(scene)
    r = scene.render
    shade = dict(ambient=r.ambient, model=r.shading, background=r.background,
                 toon_bands=r.toon_bands)
    fast = transparent_fragments(meshes, materials, scene.lights, scene.camera, 64, 48, **shade)
    assert len(fast.pixel) > 100
    assert_same_fragments(fast, transparent_fragments(meshes, materials, scene.lights,
                                                      scene.camera, 64, 48, textbook=True,
                                                      **shade))
