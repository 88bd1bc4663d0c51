"""Rasterisation and sphere tracing draw the same picture: a cube mesh, rasterised
(`reference_cpu.rasterise`) and shaded by the sphere tracer's own functions
(`reference_cpu.raster_shading`), against the NumPy sphere tracer's float64 frame of the SDF
box it is (the same surface exactly: a box has flat faces).

Measured at 96 x 72: the same pixels hit; inside each face, colours within 1.2e-7, depths
within 5e-6 (the march stops within epsilon = 1e-6 of the surface, along a slanted ray) and
normals within 5e-14. Within a pixel of a cube edge the pictures differ by up to 0.08 in
colour: the sphere tracer's central-difference normal there mixes two faces (h = 1e-3), the
raster's is the face's own.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import render
from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, turned
from reference_cpu.rasterise import rasterise
from reference_cpu import shading
from reference_cpu.raster_shading import shade_raster
from scene_model.builder import box, union
from scene_model.camera import camera_rays
from scene_model.meshes import MeshNode, cube, world_meshes
from scene_model.scene import (DirectionalLight, Material, PointLight, RenderSettings, Scene,
                               SolidBackground, SpotLight, StudioBackground)

WIDTH, HEIGHT = 96, 72
MATERIAL = Material(color=(0.8, 0.3, 0.2), ks=0.5, shininess=24.0)
LIGHTS = (PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),
          DirectionalLight(direction=(1.0, -1.0, -0.5), intensity=0.5),
          SpotLight(position=(2.0, 3.0, 2.0), direction=(-1.0, -1.5, -1.0), intensity=0.8,
                    diffuse=(1.0, 0.9, 0.7), specular=(0.5, 0.5, 1.0), ambient=(0.05, 0, 0)))
TURN, OFFSET = 25, (-0.2, 0.5, 0.0)


def sdf_frame(model: str):
    settings = RenderSettings(shadows="none", reflection_depth=0, shading=model,
                              background=SolidBackground(color=(0.0, 0.0, 0.0)), epsilon=1e-6)
    scene = Scene(camera=CAMERA, render=settings, materials={"m": MATERIAL}, lights=LIGHTS,
                  objects=(box(0.5, material="m").rotate(0, TURN, 0).at(*OFFSET),))
    return render(scene, WIDTH, HEIGHT, backend="numpy", precision="float64"), settings


@pytest.mark.parametrize("model", ["phong", "blinn_phong", "toon", "normals"])
def test_cube_mesh_is_shaded_as_the_sdf_box_is(model):
    frame, settings = sdf_frame(model)
    raster = rasterise([turned(cube(1.0), TURN, OFFSET)], CAMERA, WIDTH, HEIGHT)
    color = np.clip(shade_raster(raster, CAMERA, [MATERIAL], LIGHTS, settings.ambient, model,
                                 toon_bands=settings.toon_bands), 0, 1)
    np.testing.assert_array_equal(raster.hit, frame.hit)
    faces = np.where(raster.hit, raster.triangle // 2, -1)         # two triangles a face
    inside = raster.hit & ~dilate(boundary(faces), 1)
    assert inside.sum() > 200
    assert np.abs(color - frame.color).max(axis=-1)[inside].max() <= 1e-6
    assert np.abs(raster.depth[inside] - frame.depth[inside]).max() <= 10 * settings.epsilon
    np.testing.assert_array_equal(color[~raster.hit], 0.0)


def test_unknown_model_is_refused():
    raster = rasterise([cube(1.0)], CAMERA, 16, 12)
    with pytest.raises(ValueError, match="unknown shading model 'depth'"):
        shade_raster(raster, CAMERA, [MATERIAL], LIGHTS, model="depth")


def test_mesh_hierarchy_draws_the_sdf_tree_of_the_same_transforms():
    """A group turned and moved, holding a scaled cube and a turned, moved one, against the
    SDF union of the two boxes under the same Rotate and Translate nodes: the same objects
    on the same pixels, and the same colours inside each face."""
    group = MeshNode(None, translate=(0.3, 0.2, 0.0), rotate=(0.0, 30.0, 0.0), children=(
        MeshNode(cube(1.0), scale=0.6),
        MeshNode(cube(0.6), translate=(0.9, 0.6, 0.2), rotate=(20.0, 0.0, 10.0))))
    tree = union(box(0.3, material="m"),
                 box(0.3, material="m").rotate(20, 0, 10).at(0.9, 0.6, 0.2)
                 ).rotate(0, 30, 0).at(0.3, 0.2, 0.0)
    settings = RenderSettings(shadows="none", reflection_depth=0, epsilon=1e-6,
                              background=SolidBackground(color=(0.0, 0.0, 0.0)))
    scene = Scene(camera=CAMERA, render=settings, materials={"m": MATERIAL}, lights=LIGHTS,
                  objects=(tree,))
    frame = render(scene, WIDTH, HEIGHT, backend="numpy", precision="float64")
    meshes = world_meshes(group)
    raster = rasterise(meshes, CAMERA, WIDTH, HEIGHT)
    color = np.clip(shade_raster(raster, CAMERA, [MATERIAL] * 2, LIGHTS, settings.ambient),
                    0, 1)
    np.testing.assert_array_equal(raster.object_id, frame.object_id)
    faces = np.where(raster.hit, raster.object_id * 100 + raster.triangle // 2, -1)
    inside = raster.hit & ~dilate(boundary(faces), 1)
    assert (raster.object_id[inside] == 1).sum() > 20
    assert (raster.object_id[inside] == 0).sum() > 20
    assert np.abs(color - frame.color).max(axis=-1)[inside].max() <= 1e-6


def test_background_is_looked_up_only_where_nothing_is_drawn_with_the_same_bits(monkeypatch):
    """A cube-map background (the studio) behind a cube: `shading.background` is asked for
    the pixels nothing is drawn on and no others, and the picture is, bit for bit, the one
    made by looking it up on every pixel and shading over the drawn ones."""
    background = StudioBackground()
    raster = rasterise([turned(cube(1.0), TURN, OFFSET)], CAMERA, WIDTH, HEIGHT)
    assert 200 < raster.hit.sum() < WIDTH * HEIGHT - 200
    asked = []
    original = shading.background

    def counting(direction, bg):
        asked.append(len(direction))
        return original(direction, bg)

    monkeypatch.setattr(shading, "background", counting)
    color = shade_raster(raster, CAMERA, [MATERIAL], LIGHTS, background=background)
    assert asked == [(~raster.hit).sum()]
    monkeypatch.undo()
    _, directions = camera_rays(CAMERA, WIDTH, HEIGHT)
    everywhere = original(directions.reshape(-1, 3), background).reshape(HEIGHT, WIDTH, 3)
    drawn = shade_raster(raster, CAMERA, [MATERIAL], LIGHTS)
    expected = np.where(raster.hit[..., None], drawn, everywhere).astype(np.float64)
    assert color.dtype == expected.dtype and color.tobytes() == expected.tobytes()
    assert np.ptp(color[~raster.hit], axis=0).max() > 0.05        # the map varies
