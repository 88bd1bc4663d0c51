"""Shadow volumes in NumPy (`reference_cpu.shadow_volumes`) against Embree's shadow rays
(`reference_cpu.truth.mesh_rays`), pixel by pixel.

Hard shadows of a point or a directional light are one set of points, found two
independent ways: by counting shadow volume faces behind each pixel's surface, and by
casting a ray from the surface to the light. They must agree on every pixel but those within
a pixel of a shadow's edge or a silhouette, where a centre lies within rounding of the
boundary. Measured on "cube and cone on a floor" at 96 x 72: the point light's shadow
covers 1,799 pixels and one pixel differs, beside an edge; the directional light's 1,042
and none; the spot light's is the point light's (spot lights cast from their position).
The shadow rays start 0.1 mm off the surface along the normal of the facet drawn: the
volumes are built from the facets, so the truth looks at the facets too.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu.rasterise import Raster, rasterise
from reference_cpu.shadow_map import surface_points
from reference_cpu.shadow_volumes import shadow_volume_visibility
from reference_cpu.truth.mesh_rays import shadow_rays
from scene_model.meshes import cube, plane, transformed
from scene_model.scene import Camera, DirectionalLight, PointLight, SpotLight

LIGHTS = {"point": PointLight(position=(-1.0, 3.0, -2.5)),
          "directional": DirectionalLight(direction=(0.5, -1.0, 0.9)),
          "spot": SpotLight(position=(-1.0, 3.0, -2.5), direction=(0.3, -1.0, 0.8))}
BOUNDARY_SHARE = 0.01     # of the pixels beside an edge, at most 1% may disagree


def ray_traced_visibility(meshes, raster: Raster, camera, light) -> np.ndarray:
    """Embree's visibility (H, W) of ``light`` from each pixel's surface; 1 where none."""
    facet_normal = np.zeros(raster.normal.shape)
    for k, mesh in enumerate(meshes):
        drawn = raster.object_id == k
        facet_normal[drawn] = mesh.face_normals()[raster.triangle[drawn]]
    visibility = np.ones(raster.depth.shape)
    visibility[raster.hit] = shadow_rays(meshes, surface_points(raster, camera)[raster.hit],
                                         facet_normal[raster.hit], light, offset=1e-4)
    return visibility


def assert_same_shadows(truth, candidate, raster, min_shadowed):
    assert (truth[raster.hit] == 0).sum() >= min_shadowed         # the test sees a shadow
    excused = dilate(boundary(truth) | boundary(raster.object_id), 1)
    differ = truth != candidate
    assert not (differ & ~excused).any()
    assert differ.sum() <= BOUNDARY_SHARE * excused.sum()


@pytest.mark.parametrize("name", LIGHTS)
def test_shadow_volumes_shadow_the_pixels_shadow_rays_find(embree, name):
    meshes = SCENES["cube and cone on a floor"]
    raster = rasterise(meshes, CAMERA, WIDTH, HEIGHT)
    light = LIGHTS[name]
    truth = ray_traced_visibility(meshes, raster, CAMERA, light)
    candidate = shadow_volume_visibility(meshes, raster, CAMERA, light)
    assert_same_shadows(truth, candidate, raster, min_shadowed=1000)


def test_depth_fail_works_with_the_eye_inside_a_shadow(embree):
    """Light skims the floor past a cube and the eye sits in the cube's shadow: the volume's
    faces cross the near plane round the eye, and depth-fail never counts them."""
    meshes = [transformed(cube(1.0), np.array([[1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, 1, 0],
                                               [0, 0, 0, 1.0]])), plane(8.0, 8.0, 4)]
    light = DirectionalLight(direction=(1.0, -0.3, 0.0))
    camera = Camera(position=(2.0, 0.3, 0.0), look_at=(4.0, 0.0, 1.0), fov=60.0)
    raster = rasterise(meshes, camera, WIDTH, HEIGHT)
    eye = np.array([camera.position])
    assert shadow_rays(meshes, eye, np.zeros((1, 3)), light)[0] == 0     # the eye is shadowed
    truth = ray_traced_visibility(meshes, raster, camera, light)
    candidate = shadow_volume_visibility(meshes, raster, camera, light)
    assert_same_shadows(truth, candidate, raster, min_shadowed=1000)
