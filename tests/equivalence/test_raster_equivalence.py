"""The three mesh backends against each other, under the gates of `marchlab.compare`.

Two chains, each through the readable NumPy rasteriser: Embree's ray casts (the truth, float32
hits) against ``numpy-raster`` (float64), and ``numpy-raster`` against the GPU's ``raster``
pipeline (float32, shadows, mirrors and transparency all drawn on the GPU:
`gpu_shader.raster_render`). Both must pass `gates_against(precision, meshes=True)`: hit
flags and path labels may differ only within a pixel of an edge (on at most 0.05% and 0.2%
of the pixels), the interior's depth within max(2 epsilon, 1e-5 t), normals within 0.5
degrees, colours within 1/255 (2/255 against the float64 reference) and the 8-bit pictures
within one level. On a hardware GPU, which samples each pixel up to 1/512 of a pixel from
its centre, the reference is also drawn around the centres (`marchlab.compare.reference_around`;
docs/equivalence.md, "Sub-pixel precision").

The cases: the bundled mesh scenes ``meshes`` and ``museum``, then the small ``meshes``
scene changed in one feature each (a shading model, a light type with its shadows, a
pattern, a background, a mirror, a glass pane peeled or sorted, a turned hierarchy, fog), so
that a failure names the feature. At 96 x 72 the suite takes about 20 s on 2 cores.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from marchlab import load_scene, render
from marchlab.compare import (boundary, compare_frames, dilate, failures, gates_against,
                              reference_around)
from required_backends import need_backend
from scene_model.scenefile import scene_from_dict, scene_to_dict

WIDTH, HEIGHT = 96, 72
BASE = scene_to_dict(load_scene("meshes"))

MIRROR = {"type": "plane", "width": 3.0, "depth": 1.6, "material": "mirror",
          "position": [0.0, 0.9, -3.1], "rotation": [90.0, 0.0, 0.0]}
PANE = {"type": "cube", "material": "glass", "position": [-0.2, 0.75, 1.6],
        "rotation": [0.0, 20.0, 0.0], "scale": [1.6, 1.2, 0.05]}
HIERARCHY = {"type": "group", "position": [0.0, 1.4, 0.4], "rotation": [0.0, 40.0, 15.0],
             "children": [{"type": "cube", "size": 0.3, "material": "red",
                           "position": [0.5, 0.0, 0.0], "rotation": [30.0, 0.0, 0.0]},
                          {"type": "group", "position": [-0.5, 0.0, 0.0],
                           "rotation": [0.0, 0.0, 60.0],
                           "children": [{"type": "cone", "radius": 0.15, "height": 0.4,
                                         "material": "blue"}]}]}


def changed(render=None, lights=None, materials=None, meshes=()):
    """The ``meshes`` scene with ``render`` settings, ``lights`` and ``materials`` replaced
    (by name) and ``meshes`` added."""
    data = copy.deepcopy(BASE)
    data["render"].update(render or {})
    if lights is not None:
        data["lights"] = lights
    data["materials"].update(materials or {})
    data["meshes"] += list(meshes)
    return scene_from_dict(data)


def floor_with(pattern):
    return {"default": {**BASE["materials"]["default"], **pattern}}


SPOT = {"type": "spot", "position": [-1.5, 3.5, 2.0], "direction": [0.4, -1.0, -0.5],
        "intensity": 1.5, "inner_angle": 20.0, "outer_angle": 30.0}
MIRROR_MATERIAL = {"mirror": {"color": [0.9, 0.9, 0.95], "kd": 0.1, "ks": 0.6, "kr": 0.8}}
THREE = [BASE["lights"][0], SPOT, {"type": "directional", "direction": [-0.3, -1.0, 0.6],
                                   "intensity": 0.4}]
CASES = {
    **{f"shading {model}": lambda model=model: changed({"shading": model})
       for model in ("phong", "blinn_phong", "toon", "stripes", "normals", "depth")},
    "point light, shadows": lambda: changed(),
    "directional light, shadows": lambda: changed(lights=[
        {"type": "directional", "direction": [0.5, -1.0, -0.4], "intensity": 0.9}]),
    "spot light, shadows": lambda: changed(lights=[SPOT]),
    "three lights, shadows": lambda: changed(lights=THREE),
    "checker": lambda: changed(materials=floor_with(
        {"checker": {"color_a": [0.9, 0.9, 0.85], "color_b": [0.2, 0.2, 0.25], "scale": 0.5}})),
    "uv texture": lambda: changed(materials=floor_with(
        {"texture": {"mapping": "uv", "scale": 0.5}})),
    "triplanar texture": lambda: changed(materials=floor_with(
        {"texture": {"mapping": "triplanar", "scale": 0.7}})),
    "studio background": lambda: changed({"background": {"type": "studio", "size": 16}}),
    "solid background": lambda: changed({"background": {"type": "solid",
                                                         "color": [0.1, 0.2, 0.3]}}),
    "mirror": lambda: changed({"reflection_depth": 1}, meshes=[MIRROR],
                              materials=MIRROR_MATERIAL),
    "mirror of a uv-textured floor": lambda: changed({"reflection_depth": 1}, meshes=[MIRROR],
                                                    materials={**MIRROR_MATERIAL, **floor_with(
                                                        {"texture": {"mapping": "uv",
                                                                     "scale": 0.5}})}),
    "glass pane, depth peeling": lambda: changed(meshes=[PANE], materials={
        "glass": {"color": [0.7, 0.85, 0.95], "ks": 0.8, "transparency": 0.6}}),
    "glass pane, sorted": lambda: changed({"blending": "sorted"}, meshes=[PANE], materials={
        "glass": {"color": [0.7, 0.85, 0.95], "ks": 0.8, "transparency": 0.6}}),
    "turned hierarchy": lambda: changed(meshes=[HIERARCHY]),
    "fog": lambda: changed({"fog": {"color": [0.8, 0.85, 0.9], "density": 0.15}}),
    "three lights, shadow maps": lambda: changed({"shadow_method": "map"}, lights=THREE),
}
def museum_with_shadow_maps():
    """The museum's three lights shadowed by maps: its point light, among the exhibits, by a
    cube map of six faces (reference_cpu/shadow_map.py)."""
    data = scene_to_dict(load_scene("museum"))
    data["render"].update({"shadow_method": "map", "shadow_map_size": 1024})
    return scene_from_dict(data)


SCENES = {"bundled meshes": lambda: load_scene("meshes"),
          "bundled museum": lambda: load_scene("museum"),
          "bundled museum, shadow maps": museum_with_shadow_maps, **CASES}


def assert_passes(reference_backend, candidate_backend, scene):
    a = render(scene, WIDTH, HEIGHT, backend=reference_backend)
    b = render(scene, WIDTH, HEIGHT, backend=candidate_backend)
    # A hardware GPU samples off the pixel centres: the reference is drawn around them.
    around = reference_around(scene, WIDTH, HEIGHT, reference_backend,
                              max(a.subpixel, b.subpixel))
    c = compare_frames(a, b, epsilon=scene.render.epsilon, around=around)
    assert a.hit.sum() > 1000                     # the case draws something
    assert failures(c, gates_against(a.precision, meshes=True)) == []


# Sorted blending orders whole triangles by their centroids, which is not the order along
# every ray (reference_cpu/transparency.py): against the ray-cast truth, which composites every
# surface by its depth, only depth peeling is held to the gates. Shadow maps are an
# approximation the ray caster does not make (it has exact shadows only).
EXACT = [name for name in SCENES if "sorted" not in name and "map" not in name]


@pytest.mark.parametrize("case", EXACT)
def test_numpy_raster_matches_embree_under_the_mesh_gates(case):
    need_backend("embree")
    assert_passes("embree", "numpy-raster", SCENES[case]())


@pytest.mark.parametrize("case", SCENES)
def test_gpu_raster_matches_numpy_raster_under_the_mesh_gates(case):
    need_backend("raster")
    assert_passes("numpy-raster", "raster", SCENES[case]())


def test_gpu_shadow_maps_differ_from_numpy_only_on_rounding_pixels_at_shadow_edges():
    """The two maps hold the same depths but for float32 rounding (the NumPy one float64),
    so a pixel whose depth lies within rounding of the stored depth plus the bias may fall
    on the other side. At 96 x 72 (the case above) no pixel does; at 320 x 240 under three
    lights, 5 of 76,800 did on llvmpipe, each on a shadow's edge: at most 0.02% may, and
    only within a pixel of an edge of the reference's path labels."""
    need_backend("raster")
    scene = changed({"shadow_method": "map"}, lights=THREE)
    a = render(scene, 320, 240, backend="numpy-raster")
    b = render(scene, 320, 240, backend="raster")
    differ = a.path != b.path
    assert a.hit.sum() > 30000                     # the floor and the shapes fill the view
    assert differ.sum() <= 0.0002 * differ.size
    assert not (differ & ~dilate(boundary(a.path), 1)).any()
    wrong = np.abs(a.color - b.color).max(axis=-1) > 2 / 255
    assert not (wrong & ~dilate(differ, 1)).any()
