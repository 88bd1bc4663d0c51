"""The rasteriser's planar reflection against Embree's reflection rays, pixel by pixel.

Two ways to one picture: the raster reference draws the scene mirrored about the mirror's
plane through a stencil, clipped at the plane (`reference_cpu.planar_reflection`); the truth
casts, from each mirror pixel's hit, the reflected ray and shades its first hit
(`reference_cpu.truth.mesh_compositing`), both with the same shading functions. The scene: a
wall mirror behind a cube and a sphere on a floor, a cube poking through the glass (only its
front half may show in it) and a sphere hidden behind it (which must never show).

Measured at 96 x 72: the same object on every pixel, directly and in the mirror, and colours
equal within 6e-15, edges included. Asserted: the same objects and colours within 1e-9 on
every pixel but those beside a change of object (seen directly or in the mirror, in either
picture), where a pixel centre may lie within rounding of a silhouette.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab.compare import boundary
from mesh_scenes import turned
from reference_cpu.planar_reflection import mirrored_raster, render_with_mirrors
from reference_cpu.rasterise import rasterise
from reference_cpu.truth.mesh_compositing import ray_traced_mirrors
from scene_model.camera import Camera
from scene_model.meshes import cube, plane, transformed, uv_sphere
from scene_model.scene import (DirectionalLight, Material, PointLight, SkyBackground)

WIDTH, HEIGHT = 96, 72
CAMERA = Camera(position=(0.8, 1.3, 3.6), look_at=(0.0, 0.6, -0.5), fov=50.0)
LIGHTS = (PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),
          DirectionalLight(direction=(1.0, -1.0, -0.5), intensity=0.5))
MIRROR, THROUGH, BEHIND = 1, 4, 5


def moved(mesh, offset):
    m = np.eye(4)
    m[:3, 3] = offset
    return transformed(mesh, m)


def standing(mesh):
    """A mesh in y = 0 facing +y turned about x to face +z."""
    return transformed(mesh, [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])


MESHES = [plane(6.0, 6.0), moved(standing(plane(2.4, 1.6)), (0.0, 0.9, -1.0)),
          turned(cube(0.6), 25, (-0.1, 0.3, 0.5)), moved(uv_sphere(0.4, 24, 12), (0.7, 0.5, 0.4)),
          turned(cube(0.5), 40, (-0.8, 0.7, -1.0)), moved(uv_sphere(0.3, 16, 8), (-0.3, 0.8, -1.8))]
MATERIALS = [Material(color=(0.6, 0.6, 0.6)),
             Material(color=(0.1, 0.1, 0.15), kr=0.8, ks=0.3, shininess=40.0),
             Material(color=(0.8, 0.3, 0.2), ks=0.5, shininess=24.0),
             Material(color=(0.2, 0.5, 0.8), ks=0.4, shininess=32.0),
             Material(color=(0.3, 0.8, 0.3)), Material(color=(0.9, 0.9, 0.1))]
SKY = SkyBackground(top=(0.2, 0.3, 0.6), bottom=(0.8, 0.8, 0.7))


def pictures(model: str):
    shade = dict(ambient=(0.1, 0.1, 0.1), model=model, background=SKY)
    color = render_with_mirrors(MESHES, MATERIALS, LIGHTS, CAMERA, WIDTH, HEIGHT, **shade)
    truth, part, reflected_part = ray_traced_mirrors(MESHES, MATERIALS, LIGHTS, CAMERA, WIDTH,
                                                     HEIGHT, **shade)
    raster = rasterise(MESHES, CAMERA, WIDTH, HEIGHT)
    stencil = raster.object_id == MIRROR
    shown = np.where(stencil, mirrored_raster(MESHES, MIRROR, CAMERA, WIDTH, HEIGHT).object_id,
                     -1)
    return color, truth, raster.object_id, part, shown, reflected_part


@pytest.mark.parametrize("model", ["phong", "blinn_phong", "toon"])
def test_mirror_shows_what_reflection_rays_see(embree, model):
    color, truth, drawn, part, shown, reflected_part = pictures(model)
    # What each pixel shows, directly and in the mirror, as one label.
    labels = np.where(drawn == MIRROR, 100 + shown, drawn)
    truth_labels = np.where(part == MIRROR, 100 + reflected_part, part)
    edges = boundary(labels) | boundary(truth_labels)
    np.testing.assert_array_equal(labels[~edges], truth_labels[~edges])
    in_mirror = (drawn == MIRROR) & ~edges
    assert in_mirror.sum() > 400
    assert (shown[in_mirror] == 2).sum() >= 20 and (shown[in_mirror] == 3).sum() >= 10
    for k in (0, THROUGH):                   # the floor, and the front half of the cube
        assert (shown == k).sum() >= 10      # through the glass: thin strips
    assert np.abs(color - truth).max(axis=-1)[~edges].max() <= 1e-9


def test_object_behind_the_mirror_is_seen_neither_by_rays_nor_by_the_raster(embree):
    """The sphere behind the glass: not in the mirrored pass on any mirror pixel, and not met
    by any reflection ray (which start on the glass)."""
    _, _, drawn, _, shown, reflected_part = pictures("phong")
    assert (drawn == MIRROR).sum() > 500
    assert not (shown == BEHIND).any()
    assert not (reflected_part == BEHIND).any()
