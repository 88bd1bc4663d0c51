"""The NumPy rasteriser against Embree's ray casts of the same triangles, pixel by pixel.

Two independent programs answer one question, which triangle each pixel centre's ray meets
first and how far away: the rasteriser by projecting triangles and testing edge functions
(`reference_cpu.rasterise`), Embree by intersecting rays in float32 (`reference_cpu.truth.
embree`). They must agree on every pixel but where a centre lies within rounding of a
silhouette or of an edge between two triangles: the rasteriser snaps corners to 1/256 of a
pixel, Embree rounds in float32. Where both meet the same triangle, the depths agree within
Embree's stated float32 rounding of the hit point, over the cosine of the angle at which
the ray meets the surface (a point moved by r along the surface moves t by r / cos).
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, HEIGHT, SCENES, WIDTH
from reference_cpu.rasterise import rasterise
from reference_cpu.truth.embree import cast_triangles
from reference_cpu.truth.mesh import Mesh
from scene_model.camera import camera_rays
from scene_model.geometry import dot
from scene_model.meshes import plane

SILHOUETTE_SHARE = 0.02       # of the pixels next to a silhouette, at most 2% may disagree


@pytest.mark.parametrize("name", SCENES)
def test_rasterised_picture_is_the_ray_cast_picture(embree, name):
    meshes = SCENES[name]
    raster = rasterise(meshes, CAMERA, WIDTH, HEIGHT)
    origin, directions = camera_rays(CAMERA, WIDTH, HEIGHT)
    truth_meshes = [Mesh(m.positions, m.triangles.astype(np.int32), 0.0, None, "exact")
                    for m in meshes]
    t, normal, part, triangle, rounding = cast_triangles(truth_meshes, origin,
                                                         directions.reshape(-1, 3))
    cosine = np.abs(dot(normal, directions.reshape(-1, 3)))
    t, part, triangle, rounding, cosine = (a.reshape(HEIGHT, WIDTH) for a in (
        t, part, triangle, rounding, cosine))

    # Which object each pixel shows: the same but beside an edge where it changes.
    near_edge = dilate(boundary(part), 1)
    differ = part != raster.object_id
    assert not (differ & ~near_edge).any()
    assert differ.sum() <= SILHOUETTE_SHARE * near_edge.sum()
    # Which triangle: the same but within a pixel of an edge between two.
    faces = np.where(part >= 0, part * 100_000 + triangle, -1)
    other_face = ~differ & (triangle != raster.triangle)
    assert not (other_face & ~dilate(boundary(faces), 1)).any()
    # How far, where both meet the same triangle.
    same = (part >= 0) & ~differ & ~other_face
    assert same.sum() > 1000
    error = np.abs(raster.depth[same] - t[same])
    assert np.all(error <= rounding[same] / cosine[same] + 1e-9 * t[same])


def test_watertight_mesh_shows_no_background_through_its_seams(embree):
    """Where Embree sees the floor's 32 triangles with no gap, so does the rasteriser: every
    pixel of the floor's interior is drawn, exactly once."""
    floor = plane(6.0, 6.0, subdivisions=4)
    raster = rasterise([floor], CAMERA, WIDTH, HEIGHT)
    inside = ~dilate(boundary(raster.hit), 1) & raster.hit
    assert inside.sum() > 1000
    assert np.all(raster.coverage[inside] == 1)
