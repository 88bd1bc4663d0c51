"""Which meshes may have their back faces culled (`reference_cpu.back_faces`): the closed,
outward-wound ones (their signed volume is the volume they enclose), and only while every
pixel ray meets them from outside, beyond the near plane's reach. Near that, culling would
change the picture: the last test shows it does.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from reference_cpu.back_faces import (bounds_a_solid, box_distance, culled_meshes, near_reach,
                                      signed_volume)
from reference_cpu.rasterise import NEAR, rasterise
from scene_model.camera import Camera, camera_basis, camera_rays
from scene_model.meshes import (cone, cube, cube_sphere, cylinder, disk, flipped, plane,
                                pyramid, torus, transformed, uv_sphere)


def box(mesh):
    return mesh.positions.min(axis=0), mesh.positions.max(axis=0)


def test_signed_volume_is_the_volume_enclosed():
    assert signed_volume(cube(2.0, subdivisions=3)) == pytest.approx(8.0, rel=1e-12)
    assert signed_volume(pyramid(1.0, 1.0)) == pytest.approx(1.0 / 3.0, rel=1e-12)
    # A UV sphere is inscribed in its sphere: a little less than 4/3 pi, and closer with more
    # segments.
    coarse, fine = signed_volume(uv_sphere(1.0, 16, 8)), signed_volume(uv_sphere(1.0, 128, 64))
    assert coarse < fine < 4.0 / 3.0 * math.pi
    assert fine == pytest.approx(4.0 / 3.0 * math.pi, rel=2e-3)
    # The origin does not matter (the divergence theorem), the winding does.
    moved = transformed(cube(1.0), np.array([[1, 0, 0, 5.0], [0, 1, 0, -3.0], [0, 0, 1, 7.0],
                                             [0, 0, 0, 1.0]]))
    assert signed_volume(moved) == pytest.approx(1.0, rel=1e-12)
    assert signed_volume(flipped(cube(1.0))) == pytest.approx(-1.0, rel=1e-12)


@pytest.mark.parametrize("mesh, solid", [
    (cube(1.0), True), (uv_sphere(1.0, 12, 6), True), (cube_sphere(1.0, 3), True),
    (torus(1.0, 0.3, 16, 8), True), (cylinder(0.5, 1.0, 12), True), (cone(0.5, 1.0, 12), True),
    (pyramid(), True), (plane(2.0, 2.0, 3), False), (disk(1.0, 12), False),
    (flipped(uv_sphere(1.0, 12, 6)), False)],
    ids=["cube", "uv sphere", "cube sphere", "torus", "cylinder", "cone", "pyramid", "plane",
         "disk", "inside-out sphere"])
def test_only_closed_outward_meshes_bound_a_solid(mesh, solid):
    assert bounds_a_solid(mesh) is solid


def test_near_reach_is_where_the_farthest_pixel_ray_meets_the_near_plane():
    camera = Camera(position=(0.0, 0.0, 0.0), look_at=(0.0, 0.0, -1.0), fov=90.0)
    assert near_reach(camera, 200, 100) == pytest.approx(NEAR * math.sqrt(1 + 4 + 1), rel=1e-15)
    # Every pixel ray (through pixel centres) crosses the near plane within the reach, the
    # corner pixels' within half a pixel of it.
    for width, height, fov in ((64, 48, 50.0), (31, 97, 120.0)):
        camera = Camera(position=(1.0, 2.0, 3.0), look_at=(0.5, 1.0, -2.0), fov=fov)
        _, directions = camera_rays(camera, width, height)
        forward = camera_basis(camera)[0]
        crossing = NEAR / (directions.reshape(-1, 3) @ forward)      # unit rays: distance
        reach = near_reach(camera, width, height)
        assert crossing.max() <= reach and crossing.max() > reach * (1 - 2.0 / min(width,
                                                                                   height))


def test_box_distance_is_zero_inside_and_euclidean_outside():
    low, high = np.array([0.0, 0.0, 0.0]), np.array([1.0, 2.0, 3.0])
    assert box_distance((0.5, 1.0, 1.5), low, high) == 0.0
    assert box_distance((-3.0, 1.0, 1.5), low, high) == 3.0
    assert box_distance((4.0, 6.0, 1.5), low, high) == 5.0          # the edge's corner


def test_a_mesh_is_culled_only_while_every_ray_meets_it_from_outside():
    solid, sheet = cube(1.0), plane(1.0, 1.0)
    camera = Camera(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=60.0)
    reach = near_reach(camera, 64, 48)

    def culled(eye, mesh=solid):
        moved = Camera(position=eye, look_at=(0.0, 0.0, eye[2] - 1.0), fov=60.0)
        return culled_meshes([bounds_a_solid(mesh)], [box(mesh)], moved, 64, 48)[0]

    assert culled((0.0, 0.0, 5.0))
    assert not culled((0.0, 0.0, 5.0), sheet)                 # open: its back shows
    assert not culled((0.1, 0.2, 0.3))                        # inside
    assert not culled((0.0, 0.0, 0.5 + 1.5 * reach))          # its front is cut by the near
    assert culled((0.0, 0.0, 0.5 + 2.5 * reach))              # plane: drawn whole


def test_culling_a_solid_the_near_plane_cuts_would_change_the_picture():
    # The guard is needed: half the near distance from a cube's face, the near plane lies
    # inside the cube, the face in front is clipped away and the inside of the far faces
    # fills the picture. Culled, those back faces would leave it empty.
    mesh = cube(1.0)
    camera = Camera(position=(0.0, 0.0, 0.5 + 0.5 * NEAR), look_at=(0.0, 0.0, 0.0), fov=60.0)
    assert not culled_meshes([True], [box(mesh)], camera, 32, 24)[0]
    drawn = rasterise([mesh], camera, 32, 24)
    culled = rasterise([mesh], camera, 32, 24, cull_back_faces=True)
    assert np.all(drawn.object_id == 0) and np.allclose(drawn.depth[12, 16], 1.0, rtol=2e-3)
    assert np.all(culled.object_id == -1)
