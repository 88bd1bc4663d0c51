"""Meshes in the scene format: ``[[meshes]]`` tables, their hierarchy, their errors, and the
mesh backends at the command line.

The hierarchy is checked against hand-worked matrices: a child's vertex lands where its
parent's T R S carries the child's own T R S of it (exact up to float64 rounding, 1e-12 m).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run_cli
from marchlab import load_scene, render, save_scene
from scene_model.errors import SceneError
from scene_model.mesh_objects import CubeMesh, MeshGroup, UvSphereMesh
from scene_model.mesh_world import scene_meshes
from scene_model.meshes import cone, cube, plane, smooth_groups, uv_sphere
from scene_model.scene import Material, Scene
from scene_model.scenefile import bundled_scene_names, scene_from_dict
from scene_model.timeline import scene_at_time


def test_bundled_mesh_scenes_are_the_museum_and_the_small_one():
    assert bundled_scene_names(meshes=True) == ["meshes", "museum"]
    assert "classroom" in bundled_scene_names(meshes=False)


@pytest.mark.parametrize("name", ["meshes", "museum"])
def test_mesh_scene_comes_back_equal_from_its_file(name, tmp_path):
    scene = load_scene(name)
    save_scene(scene, tmp_path / "scene.toml")
    assert load_scene(tmp_path / "scene.toml") == scene


def test_child_vertex_is_carried_by_its_parents_turn_and_move_within_1e_12():
    # The parent turns 90 degrees about y (x -> -z) and moves up 2; the child sits at x = 1
    # in the parent's frame, scaled by 2 along x: the cube's corner (0.5, 0.5, 0.5) goes to
    # child frame (1 + 1, 0.5, 0.5), then to world (0.5, 2.5, -2).
    child = CubeMesh(size=1.0, position=(1.0, 0.0, 0.0), scale=(2.0, 1.0, 1.0))
    parent = MeshGroup(position=(0.0, 2.0, 0.0), rotation=(0.0, 90.0, 0.0), children=(child,))
    (mesh,), _ = scene_meshes(Scene(meshes=(parent,)))
    corner = np.all(np.isclose(cube(1.0).positions, 0.5), axis=1)
    np.testing.assert_allclose(mesh.positions[corner], [[0.5, 2.5, -2.0]] * corner.sum(),
                               atol=1e-12)


def test_objects_are_numbered_depth_first_a_node_before_its_children():
    tree = (CubeMesh(material="a", children=(UvSphereMesh(material="b"),)),
            UvSphereMesh(material="c"))
    scene = Scene(meshes=tree, materials={"a": Material(color=(1, 0, 0)),
                                          "b": Material(color=(0, 1, 0)),
                                          "c": Material(color=(0, 0, 1))})
    meshes, materials = scene_meshes(scene)
    assert [m.color for m in materials] == [(1, 0, 0), (0, 1, 0), (0, 0, 1)]
    assert [len(m.triangles) for m in meshes] == [12] + [len(uv_sphere().triangles)] * 2


def test_a_number_scales_all_three_axes():
    assert CubeMesh(scale=2).scale == (2.0, 2.0, 2.0)


def test_keyframes_turn_a_mobiles_arm():
    scene = load_scene("museum")
    quarter = scene_at_time(scene, 3.0)            # 12 s a turn: a quarter at 3 s
    assert quarter.meshes[7].rotation == pytest.approx((0.0, 90.0, 0.0))
    assert quarter.meshes[7].children[2].rotation[1] == pytest.approx(-360.0 * 3 / 5)


@pytest.mark.parametrize("table, where, problem", [
    ({"type": "cub"}, "meshes[0].type", "did you mean 'cube'?"),
    ({"type": "cube", "material": "nope"}, "meshes[0].material", "unknown material 'nope'"),
    ({"type": "cube", "size": -1}, "meshes[0].size", "must be positive"),
    ({"type": "group", "children": [{"type": "torus", "sides": 2}]},
     "meshes[0].children[0].sides", "must be >= 3"),
    ({"type": "uv_sphere", "radius": 1, "colour": 2}, "meshes[0].colour", "unknown key"),
])
def test_bad_mesh_table_is_refused_naming_its_field(table, where, problem):
    with pytest.raises(SceneError) as caught:
        scene_from_dict({"materials": {"default": {}}, "meshes": [table]})
    assert str(caught.value).startswith(where) and problem in str(caught.value)


def test_groups_nested_beyond_the_limit_are_refused():
    node = CubeMesh()
    with pytest.raises(SceneError, match="nested deeper"):
        for _ in range(40):
            node = MeshGroup(children=(node,))


def test_a_plane_is_one_smooth_patch_and_every_cube_triangle_lies_on_a_crease():
    assert len(np.unique(smooth_groups(plane(1.0, 1.0, 4)))) == 1
    # Each face of a cube keeps its own vertices: every triangle of an undivided cube has an
    # edge on a crease, so each is a piece of its own; subdivided, a face's inner triangles
    # (one of the 8 of a 2 x 2 face) join one patch per face.
    assert len(np.unique(smooth_groups(cube(1.0)))) == 12
    assert len(np.unique(smooth_groups(cube(1.0, subdivisions=2)))) == 6 * 7


def test_a_cones_apex_triangles_are_creased_from_each_other():
    # Each side triangle at the apex has an apex vertex of its own, with its own normal.
    mesh = cone(0.5, 1.0, 24)
    groups = smooth_groups(mesh)
    apex = np.isclose(mesh.positions[mesh.triangles][:, :, 1], 1.0).any(axis=1)
    assert apex.sum() == 24 and len(np.unique(groups[apex])) == 24


@pytest.mark.parametrize("backend", ["numpy", "gpu", "opencl"])
def test_sdf_backend_refuses_a_mesh_scene_in_one_line(backend, capsys, tmp_path):
    code, _, err = run_cli(capsys, "render", "meshes", "--backend", backend, "--size", "16x12",
                           "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert "triangle meshes" in err and "numpy-raster" in err
    assert not (tmp_path / "x.png").exists()


def test_mesh_backend_refuses_an_sdf_scene_in_one_line(capsys, tmp_path):
    code, _, err = run_cli(capsys, "render", "classroom", "--backend", "numpy-raster",
                           "--size", "16x12", "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert "SDF objects" in err


def test_march_steps_view_is_refused_for_meshes(capsys, tmp_path):
    code, _, err = run_cli(capsys, "render", "meshes", "--set", "render.shading=steps",
                           "--size", "16x12", "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert "render.shading = 'steps'" in err


@pytest.mark.parametrize("backend", ["numpy-raster", "embree"])
def test_soft_shadows_are_refused_for_meshes_not_drawn_hard(backend, capsys, tmp_path):
    code, _, err = run_cli(capsys, "render", "meshes", "--set", "render.shadows=soft",
                           "--backend", backend, "--size", "16x12", "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert "render.shadows = 'soft'" in err and "'hard'" in err
    assert not (tmp_path / "x.png").exists()


def test_mesh_scene_renders_with_the_numpy_rasteriser_by_default(capsys, tmp_path):
    code, out, _ = run_cli(capsys, "render", "meshes", "--size", "32x24", "-o",
                           tmp_path / "m.npz")
    assert code == 0 and "numpy-raster float64" in out
    data = np.load(tmp_path / "m.npz")
    assert data["hit"].mean() > 0.5 and np.all(data["steps"] == 0)


@pytest.mark.parametrize("a, b", [("numpy-raster", "embree"), ("numpy-raster", "raster"),
                                  ("embree", "raster")])
def test_mesh_backends_pass_the_gates_against_each_other(a, b, capsys):
    code, out, _ = run_cli(capsys, "compare", "meshes", "--a", a, "--b", b,
                           "--size", "96x72")
    assert code == 0, out
    assert out.rstrip().endswith("PASS")


def test_mesh_frames_without_meshes_drawn_are_background(tmp_path):
    scene = dataclasses.replace(load_scene("meshes"),
                                camera=dataclasses.replace(load_scene("meshes").camera,
                                                           look_at=(0.3, 10.0, 40.0)))
    frame = render(scene, 16, 12, backend="numpy-raster")
    assert not frame.hit.any() and np.all(np.isinf(frame.depth))


def test_the_builder_makes_the_mobile_the_museum_file_describes():
    from scene_model.builder import cone_mesh, cube_mesh, cylinder_mesh, group, uv_sphere_mesh
    lower = group(cylinder_mesh(0.012, 0.8, material="frame").rotate(0, 0, 90),
                  cone_mesh(0.12, 0.3, 24, material="red").at(-0.4, -0.35, 0),
                  cube_mesh(0.18, material="jade").at(0.4, -0.25, 0).rotate(0, 45, 0))
    mobile = group(cylinder_mesh(0.015, 1.4, material="frame").rotate(0, 0, 90),
                   uv_sphere_mesh(0.16, 24, 12, material="blue").at(-0.7, -0.25, 0),
                   lower.at(0.7, -0.3, 0)).at(0.6, 3.1, 0.6)
    assert mobile == load_scene("museum").meshes[7]
    assert cube_mesh().scaled(2).scale == (2.0, 2.0, 2.0)
    assert group().holding(cube_mesh()).children == (cube_mesh(),)


def test_a_missing_obj_file_is_reported_at_load_as_the_field_that_names_it(capsys, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text('[materials.default]\n\n[[meshes]]\ntype = "group"\n\n'
                     '[[meshes.children]]\ntype = "obj"\nfile = "models/nope.obj"\n')
    code, _, err = run_cli(capsys, "render", scene, "--size", "16x12", "-o", tmp_path / "x.png")
    assert_one_line_error(code, err)
    assert f"{scene}: meshes[0].children[0].file: " in err
    assert str(tmp_path / "models" / "nope.obj") in err
    assert not (tmp_path / "x.png").exists()
