"""Planar reflections in the NumPy raster reference (`reference_cpu.planar_reflection`).

The mirror matrix against its defining properties, the clip against exact areas, the mirrored
pass's depth against the analytic length of a bent path, a hidden object against the clip
plane, and the whole picture against the NumPy sphere tracer's mirror rays (one bounce):
at 96 x 72, on every pixel both draw within the march's reach and away from an edge, the
colours agreed within 1.3e-7 (the march stops within epsilon = 1e-6 of a surface).
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import render
from marchlab.compare import boundary, dilate
from mesh_scenes import CAMERA, turned
from reference_cpu.planar_reflection import (clip_to_plane, mirror_matrix, mirror_plane,
                                             mirrored_raster, reflect_through, render_with_mirrors)
from reference_cpu.rasterise import rasterise
from reference_cpu.shading import reflect
from scene_model.builder import box, plane as sdf_plane
from scene_model.camera import Camera, camera_rays
from scene_model.meshes import TriangleMesh, cube, plane, transformed, uv_sphere
from scene_model.scene import (DirectionalLight, Material, PointLight, RenderSettings, Scene,
                               SolidBackground)

WIDTH, HEIGHT = 96, 72
LIGHTS = (PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),
          DirectionalLight(direction=(1.0, -1.0, -0.5), intensity=0.5))
MIRROR = Material(color=(0.2, 0.2, 0.25), kr=0.6, ks=0.3, shininess=40.0)
RED = Material(color=(0.8, 0.3, 0.2), ks=0.5, shininess=24.0)
GREY = Material(color=(0.6, 0.6, 0.6))


def moved(mesh, offset):
    m = np.eye(4)
    m[:3, 3] = offset
    return transformed(mesh, m)


def standing(mesh):
    """A mesh in y = 0 facing +y turned about x to face +z."""
    return transformed(mesh, [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])


def test_mirror_matrix_fixes_its_plane_and_reflects_distances_to_it():
    rng = np.random.default_rng(1)
    point, normal = rng.normal(size=3), rng.normal(size=3)
    n = normal / np.linalg.norm(normal)
    m = mirror_matrix(point, normal)
    np.testing.assert_allclose(m @ m, np.eye(4), atol=1e-14)       # its own inverse
    assert np.linalg.det(m[:3, :3]) == pytest.approx(-1.0, abs=1e-14)
    x = rng.normal(size=(50, 3))
    image = x @ m[:3, :3].T + m[:3, 3]
    np.testing.assert_allclose((image - point) @ n, -((x - point) @ n), atol=1e-13)
    on_plane = x - ((x - point) @ n)[:, None] * n
    np.testing.assert_allclose(on_plane @ m[:3, :3].T + m[:3, 3], on_plane, atol=1e-13)
    # Its linear part turns a direction as a mirror ray turns: d - 2 (d . n) n.
    d = rng.normal(size=(50, 3))
    np.testing.assert_allclose(d @ m[:3, :3].T, reflect(d, np.tile(n, (50, 1))), atol=1e-14)


def test_curved_mirror_is_refused_with_a_clear_message():
    with pytest.raises(ValueError, match="flat mirror"):
        mirror_plane(uv_sphere(1.0, 16, 8))
    with pytest.raises(ValueError, match="flat mirror"):
        render_with_mirrors([plane(2.0, 2.0), uv_sphere(0.5, 16, 8)], [GREY, MIRROR], LIGHTS,
                            CAMERA, 16, 12)
    point, normal = mirror_plane(turned(standing(plane(2.0, 1.0, 3)), 30, (0.2, 0.5, -1.0)))
    assert abs(normal @ [np.sin(np.radians(30)), 0, np.cos(np.radians(30))]) == pytest.approx(1)


def test_clip_to_plane_keeps_the_front_part_with_its_exact_area():
    """A unit cube cut through its centre by a tilted plane keeps half its surface (by
    symmetry about the centre: 3 m^2), all of it in front, wound outward."""
    normal = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])
    kept = clip_to_plane(cube(1.0), np.zeros(3), normal)
    corners = kept.positions[kept.triangles]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.linalg.norm(cross, axis=1).sum() / 2 == pytest.approx(3.0, rel=1e-12)
    assert (kept.positions @ normal).min() >= -1e-15
    outward = np.einsum("tx,tx->t", cross, kept.normals[kept.triangles[:, 0]])
    assert (outward > 0).all()


def test_mirrored_depth_is_the_length_of_the_bent_path():
    """A floor mirror at y = 0, a ceiling at y = 2, the eye at y = 1: a ray going down with
    direction d meets the mirror after 1 / |d_y| and the ceiling 2 / |d_y| later, so the
    mirrored pass must hold 3 / |d_y| wherever the mirror shows the ceiling (1e-12)."""
    camera = Camera(position=(0.0, 1.0, 0.0), look_at=(0.0, 0.2, -1.0), fov=60.0)
    ceiling = moved(transformed(plane(400.0, 400.0), np.diag([1.0, -1.0, -1.0, 1.0])),
                    (0, 2.0, 0))
    meshes = [plane(400.0, 400.0), ceiling]
    stencil = rasterise(meshes, camera, WIDTH, HEIGHT).object_id == 0
    raster = mirrored_raster(meshes, 0, camera, WIDTH, HEIGHT)
    _, d = camera_rays(camera, WIDTH, HEIGHT)
    shown = stencil & (raster.object_id == 1)
    assert shown.sum() > 1000
    np.testing.assert_allclose(raster.depth[shown], 3.0 / np.abs(d[shown][:, 1]), rtol=1e-12)


def test_object_behind_the_mirror_never_shows_in_it():
    """A sphere behind a wall mirror, reflected, lands in front of the glass, over the
    mirror's pixels: the clip plane must remove it from all of them. Without the clip (the
    plain mirrored scene) it covers 108 of them (at least 40 asserted), so the scene can
    catch a missing clip."""
    camera = Camera(position=(0.8, 1.3, 3.6), look_at=(0.0, 0.6, -0.5), fov=50.0)
    mirror = moved(standing(plane(2.4, 1.6)), (0, 0.9, -1.0))
    behind = moved(uv_sphere(0.3, 16, 8), (-0.3, 0.8, -1.8))
    meshes = [plane(6.0, 6.0), mirror, behind]
    stencil = rasterise(meshes, camera, WIDTH, HEIGHT).object_id == 1
    clipped = mirrored_raster(meshes, 1, camera, WIDTH, HEIGHT)
    assert not (clipped.object_id[stencil] == 2).any()
    m = mirror_matrix(*mirror_plane(mirror))
    nothing = TriangleMesh(mirror.positions, mirror.normals, mirror.uvs, mirror.triangles[:0])
    plain = rasterise([transformed(meshes[0], m), nothing, transformed(behind, m)],
                      camera, WIDTH, HEIGHT)
    assert (plain.object_id[stencil] == 2).sum() >= 40


def test_a_mirror_shows_a_checkered_floors_squares_as_the_floor_itself_has_them():
    """What a mirror shows is shaded as if seen directly, albedo included: the reflected
    floor's squares are the floor's, each reflected point's colour its own square's."""
    from reference_cpu.raster_shading import surface_albedo
    from scene_model.scene import Checker
    checker = Material(color=(0.5, 0.5, 0.5), checker=Checker(color_a=(0.9, 0.9, 0.9),
                                                              color_b=(0.1, 0.1, 0.1),
                                                              scale=0.5), ka=1.0, kd=0.0,
                       ks=0.0)
    turn = np.eye(4)
    turn[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    turn[:3, 3] = (0.0, 1.0, -1.0)
    meshes = [plane(6.0, 6.0), transformed(plane(2.0, 2.0), turn)]
    mirror = Material(color=(0.0, 0.0, 0.0), ka=0.0, kd=0.0, ks=0.0, kr=1.0)
    camera = Camera(position=(0.0, 1.2, 3.0), look_at=(0.0, 0.8, -1.0), fov=50.0)
    raster = rasterise(meshes, camera, 64, 48)
    stencil = raster.object_id == 1
    color, mirrored = reflect_through(meshes, 1, stencil, [checker, mirror], [], camera, 64,
                                      48, ambient=(1.0, 1.0, 1.0))
    floor = stencil & (mirrored.object_id == 0)
    assert floor.sum() > 100
    origin, d = camera_rays(camera, 64, 48)
    m = mirror_matrix((0.0, 1.0, -1.0), (0.0, 0.0, 1.0))
    real = (origin + mirrored.depth[floor][:, None] * d[floor]) @ m[:3, :3].T + m[:3, 3]
    up = np.tile([0.0, 1.0, 0.0], (floor.sum(), 1))
    expected = surface_albedo([checker], np.zeros(floor.sum(), int), real, up,
                              np.zeros((floor.sum(), 2)))
    np.testing.assert_allclose(color[floor], expected, atol=1e-12)
    assert len(np.unique(color[floor][:, 0])) == 2                  # both colours of squares


def test_floor_mirror_shows_what_the_sphere_tracers_mirror_rays_show():
    """A mirror floor under a cube, rasterised, against the NumPy sphere tracer's float64
    frame of an SDF plane and box with one bounce (reflection_depth 1, no shadows, secondary
    rays offset by 1e-5). Which pixels are hit differs only where the march runs out of steps
    on the grazed floor (it reaches 29.3 m at most, and misses only floor beyond 29 m);
    colours, wherever both draw and not within a pixel of an edge seen directly or
    in the mirror, agree within 1e-6 (measured 1.3e-7)."""
    settings = RenderSettings(shadows="none", reflection_depth=1, epsilon=1e-6,
                              surface_offset=1e-5,
                              background=SolidBackground(color=(0.2, 0.3, 0.4)))
    scene = Scene(camera=CAMERA, render=settings, materials={"mirror": MIRROR, "red": RED},
                  lights=LIGHTS, objects=(sdf_plane(material="mirror"),
                                          box(0.4, material="red").rotate(0, 25, 0)
                                          .at(-0.3, 0.6, 0.2)))
    frame = render(scene, WIDTH, HEIGHT, backend="numpy", precision="float64")
    meshes = [plane(400.0, 400.0), turned(cube(0.8), 25, (-0.3, 0.6, 0.2))]
    color = np.clip(render_with_mirrors(meshes, [MIRROR, RED], LIGHTS, CAMERA, WIDTH, HEIGHT,
                                        settings.ambient, background=(0.2, 0.3, 0.4)), 0, 1)
    raster = rasterise(meshes, CAMERA, WIDTH, HEIGHT)
    mirrored = mirrored_raster(meshes, 0, CAMERA, WIDTH, HEIGHT)
    in_mirror = (raster.object_id == 0) & mirrored.hit
    faces = np.where(raster.hit, raster.object_id * 1000 + raster.triangle // 2, -1)
    edges = (dilate(boundary(faces), 1)
             | dilate(boundary(np.where(in_mirror, mirrored.triangle // 2, -1)), 1))
    missed = raster.hit & ~frame.hit
    np.testing.assert_array_equal(raster.hit | frame.hit, raster.hit)
    assert raster.depth[missed].min() > 29.0
    compared = raster.hit & frame.hit & ~edges
    assert (compared & in_mirror).sum() > 100                      # the cube, in the mirror
    assert np.abs(color - frame.color).max(axis=-1)[compared].max() <= 1e-6


def test_a_mesh_cut_by_the_mirror_plane_is_named_by_its_original_triangles():
    # A wall mirror standing on a floor that runs on behind it: the floor is cut at the
    # mirror's plane, and the mirrored picture must still name the floor's own triangles
    # (the path labels look up each triangle's smooth patch by them).
    from reference_cpu.planar_reflection import mirrored_raster
    turn = np.eye(4)
    turn[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]           # +y to +z: faces the eye
    turn[:3, 3] = (0.0, 1.0, -1.0)
    floor = plane(6.0, 6.0, subdivisions=3)
    meshes = [floor, transformed(plane(2.0, 2.0), turn)]
    camera = Camera(position=(0.0, 1.2, 3.0), look_at=(0.0, 0.8, -1.0), fov=50.0)
    raster = mirrored_raster(meshes, 1, camera, 64, 48)
    shown = raster.object_id == 0
    assert shown.sum() > 100
    assert raster.triangle[shown].max() < len(floor.triangles)
    # Each named triangle holds the real point behind its mirrored fragment.
    origin, directions = camera_rays(camera, 64, 48)
    m = mirror_matrix((0.0, 1.0, -1.0), (0.0, 0.0, 1.0))
    seen = origin + raster.depth[shown][:, None] * directions[shown]
    real = seen @ m[:3, :3].T + m[:3, 3]
    corners = floor.positions[floor.triangles[raster.triangle[shown]]]
    low, high = corners.min(axis=1) - 1e-9, corners.max(axis=1) + 1e-9
    assert np.all((real >= low) & (real <= high))
