"""OBJ files (`scene_model.obj_files`): a hand-written cube and tetrahedron load with the
positions, normals, texture coordinates, groups and materials written in them; the shipped
pawn is closed, wound outward and encloses the volume Pappus gives for its profile; and each
mistake a user can make in an OBJ or MTL file is one `SceneError` line naming the file."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from scene_model.errors import SceneError
from scene_model.geometry import dot
from scene_model.meshes import merged
from scene_model.obj_files import load_obj
from test_meshes import directed_edges, volume

MODELS = Path(__file__).resolve().parent.parent / "scene_model" / "scenes" / "models"

# The unit cube [0, 1]^3: each face a quad of its own normal, its corners counter-clockwise
# seen from outside with texture coordinates (0, 0), (1, 0), (1, 1), (0, 1). The walls come
# in two runs of one group; the caps are a group of two materials.
CUBE = """\
mtllib cube.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 1 0 0
vn -1 0 0
vn 0 1 0
vn 0 -1 0
vn 0 0 1
vn 0 0 -2
g walls
usemtl painted
f 2/1/1 3/2/1 7/3/1 6/4/1
f 1/1/2 5/2/2 8/3/2 4/4/2
g caps
f 4/1/3 8/2/3 7/3/3 3/4/3
usemtl tiled
f 1/1/4 2/2/4 6/3/4 5/4/4
g walls
usemtl painted
f 5/1/5 6/2/5 7/3/5 8/4/5
f 1/1/6 4/2/6 3/3/6 2/4/6
"""

CUBE_MTL = """\
newmtl painted
Kd 0.2 1.5 0.4
Ks 0.2 0.4 0.6
Ns 20000
newmtl tiled
Kd 1 1 1
map_Kd -s 1 1 1 images\\tiles.png
"""

# A tetrahedron of no normals and no texture coordinates, its faces wound outward.
TETRA = """\
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
"""


def write(folder: Path, name: str, text: str, mtl: str | None = None) -> Path:
    (folder / name).write_text(text)
    if mtl is not None:
        (folder / "cube.mtl").write_text(mtl)
    return folder / name


@pytest.fixture
def cube_parts(tmp_path):
    (tmp_path / "images").mkdir()
    (tmp_path / "images" / "tiles.png").write_bytes(b"")     # load_obj only looks for it
    return load_obj(write(tmp_path, "cube.obj", CUBE, CUBE_MTL))


def test_cube_groups_split_by_material_and_gather_by_name(cube_parts):
    assert [p.name for p in cube_parts] == ["walls", "caps/painted", "caps/tiled"]
    # A quad is two triangles of four vertices: one vertex per (position, normal, uv).
    assert [len(p.mesh.triangles) for p in cube_parts] == [8, 2, 2]
    assert [len(p.mesh.positions) for p in cube_parts] == [16, 4, 4]


def test_cube_loads_its_exact_positions_normals_and_uvs(cube_parts):
    mesh = merged(*(p.mesh for p in cube_parts))
    corners = {(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)}
    assert set(map(tuple, mesh.positions)) == corners
    # "vn 0 0 -2" is made unit; each vertex lies on the face its normal names.
    assert set(map(tuple, mesh.normals)) == {tuple(n) for n in np.vstack([np.eye(3),
                                                                          -np.eye(3)])}
    side = mesh.normals.sum(axis=1) > 0                      # the face at 1, or at 0
    assert np.all(dot(mesh.positions, np.abs(mesh.normals)) == side)
    for n in np.unique(mesh.normals, axis=0):
        face = np.all(mesh.normals == n, axis=1)
        uv_to_p = {tuple(uv): p for uv, p in zip(mesh.uvs[face], mesh.positions[face])}
        assert set(uv_to_p) == {(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)}
        # Not mirrored: dp/du x dp/dv is the outward normal, as the file's corners turn.
        dp_du = uv_to_p[1.0, 0.0] - uv_to_p[0.0, 0.0]
        dp_dv = uv_to_p[0.0, 1.0] - uv_to_p[0.0, 0.0]
        np.testing.assert_array_equal(np.cross(dp_du, dp_dv), n)


def test_cube_triangulated_quads_keep_the_files_outward_winding(cube_parts):
    mesh = merged(*(p.mesh for p in cube_parts))
    np.testing.assert_array_equal(mesh.face_normals(), mesh.normals[mesh.triangles[:, 0]])
    assert volume(mesh) == pytest.approx(1.0, abs=1e-15)
    edges = directed_edges(mesh)
    assert all(count == 1 for count in edges.values()) and all((b, a) in edges
                                                               for a, b in edges)


def test_mtl_colours_are_clipped_and_its_image_becomes_a_uv_texture(cube_parts, tmp_path):
    painted, tiled = cube_parts[1].material, cube_parts[2].material
    assert cube_parts[0].material == painted
    assert painted.color == (0.2, 1.0, 0.4)                  # Kd 1.5 clipped to 1
    assert (painted.kd, painted.ka) == (1.0, 0.1)
    assert painted.ks == pytest.approx(0.4, abs=1e-15)       # the mean of Ks
    assert painted.shininess == 10000.0                      # Ns 20000, marchlab's limit
    assert painted.texture is None and painted.transparency == 0.0
    assert tiled.ks == 0.0 and tiled.shininess == 1.0        # no Ks, no Ns
    # Written with a Windows backslash, read relative to the OBJ file, made absolute.
    assert tiled.texture.image == str(tmp_path / "images" / "tiles.png")
    assert (tiled.texture.mapping, tiled.texture.scale) == ("uv", 1.0)


def test_faces_without_normals_get_their_own_flat_normal_and_uv_zero(tmp_path):
    (part,) = load_obj(write(tmp_path, "tetra.obj", TETRA))
    assert part.name == "tetra" and part.material is None     # no group: the file's name
    mesh = part.mesh
    assert len(mesh.positions) == 12 and len(mesh.triangles) == 4   # no corner shared
    third = 1 / math.sqrt(3)
    expected = {(0.0, 0.0, -1.0), (0.0, -1.0, 0.0), (-1.0, 0.0, 0.0), (third,) * 3}
    for triangle in mesh.triangles:
        n = mesh.normals[triangle]
        np.testing.assert_array_equal(n, np.broadcast_to(n[0], (3, 3)))
        assert min(np.abs(n[0] - e).max() for e in expected) < 1e-15
    assert len({tuple(np.round(n, 15)) for n in mesh.normals}) == 4
    np.testing.assert_array_equal(mesh.uvs, 0.0)
    assert volume(mesh) == pytest.approx(1 / 6, rel=1e-15)


# --- The pawn -----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def pawn():
    return load_obj(MODELS / "pawn.obj")


def test_pawn_has_a_body_and_a_head_of_the_mtls_colours(pawn):
    assert [p.name for p in pawn] == ["body", "head"]
    # tinyobjloader parses "0.62" to 0.6200000000000001.
    assert pawn[0].material.color == pytest.approx((0.8, 0.62, 0.38), abs=1e-15)
    assert pawn[1].material.color == pytest.approx((0.08, 0.06, 0.05), abs=1e-15)


def test_pawn_is_watertight_across_its_two_groups(pawn):
    edges = directed_edges(merged(*(p.mesh for p in pawn)))
    assert all(count == 1 for count in edges.values())
    assert all((b, a) in edges for a, b in edges)


def test_pawn_faces_the_way_its_unit_normals_do(pawn):
    mesh = merged(*(p.mesh for p in pawn))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    assert np.all(dot(mesh.face_normals(), mesh.normals[mesh.triangles].mean(axis=1)) > 0.5)
    assert mesh.uvs.min() >= 0.0 and mesh.uvs.max() <= 1.0


def test_pawn_encloses_the_volume_pappus_gives_for_its_profile(pawn):
    """The pawn is its profile turned in n steps: each ring an n-gon of area
    (n / 2) sin(2 pi / n) r^2, so its volume is n sin(2 pi / n) times the first moment
    M = integral of r dA of the profile polygon (Pappus: a full turn gives 2 pi M). The
    profile is read off the mesh, the meridian u = 0 ordered by v; within 2e-5, the file's
    rounding of positions to 1e-5 m."""
    mesh = merged(*(p.mesh for p in pawn))
    x, _, z = mesh.positions.T
    meridian = (z == 0) & (x >= 0)
    points, first = np.unique(mesh.positions[meridian][:, :2], axis=0, return_index=True)
    r, y = points[np.argsort(mesh.uvs[meridian][first, 1])].T
    assert r[0] == 0 and r[-1] == 0                         # from the axis to the axis
    moment = np.sum((r[:-1] + r[1:]) * (r[:-1] * y[1:] - r[1:] * y[:-1])) / 6
    n = len(np.unique(np.round(np.arctan2(-z, x)[x ** 2 + z ** 2 > 1e-6], 2)))
    assert n == 20
    assert volume(mesh) > 0                                   # outward
    assert volume(mesh) == pytest.approx(n * math.sin(2 * math.pi / n) * moment, rel=2e-5)


def test_pawn_files_are_what_make_pawn_writes():
    spec = importlib.util.spec_from_file_location("make_pawn", MODELS / "make_pawn.py")
    make_pawn = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_pawn)
    assert (MODELS / "pawn.obj").read_text() == make_pawn.obj_text()
    assert (MODELS / "pawn.mtl").read_text() == make_pawn.MTL


# --- Mistakes a user can make -------------------------------------------------------------

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"

BAD = {
    "missing file": (None, "cannot read: No such file"),
    "folder": ("folder", "is a folder"),
    "not UTF-8": (b"g caf\xe9\n" + TRIANGLE.encode() + b"f 1 2 3\n", "not UTF-8 text"),
    "position out of range": (TRIANGLE + "f 1 2 4\n",
                              "a face names position 4, but the file has 3"),
    "uv out of range": (TRIANGLE + "vt 0 0\nf 1/1 2/2 3/1\n",
                        "a face names texture coordinate 2, but the file has 1"),
    "normal out of range": (TRIANGLE + "vn 0 0 1\nf 1//1 2//1 3//2\n",
                            "a face names normal 2, but the file has 1"),
    "quad out of range": (TRIANGLE + "f 1 2 3\nf 1 2 3 4\n", "a face names a position"),
    "infinite": ("v 1e999 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "beyond float64"),
    "only a sliver": ("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "holds no triangles"),
    "index 0": (TRIANGLE + "f 0 1 2\n", "cannot parse it"),
    "no triangles": (TRIANGLE + "l 1 2\n", "holds no triangles"),
    "missing MTL": ("mtllib nowhere.mtl\n" + TRIANGLE + "f 1 2 3\n", "'nowhere.mtl'"),
    "unknown material": ("mtllib cube.mtl\n" + TRIANGLE + "usemtl gold\nf 1 2 3\n",
                         "usemtl 'gold'"),
    "MTL not UTF-8": (("mtllib cube.mtl\n" + TRIANGLE + "usemtl wood\nf 1 2 3\n",
                       b"newmtl wood\nmap_Kd caf\xe9.png\n"), "image) is not UTF-8"),
    "missing texture": ("mtllib cube.mtl\n" + TRIANGLE + "usemtl tiled\nf 1 2 3\n",
                        "map_Kd image 'images/tiles.png' does not exist"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_obj_is_one_scene_error_line_naming_the_file(tmp_path, case):
    content, problem = BAD[case]
    path = tmp_path / "model.obj"
    if content == "folder":
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, tuple):                       # an OBJ file and its MTL file
        path.write_text(content[0])
        (tmp_path / "cube.mtl").write_bytes(content[1])
    elif content is not None:
        write(tmp_path, "model.obj", content, CUBE_MTL)
    with pytest.raises(SceneError) as caught:
        load_obj(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    assert problem in message
