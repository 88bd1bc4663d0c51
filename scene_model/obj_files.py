"""Wavefront OBJ files: triangle meshes made elsewhere, with their MTL materials.

An OBJ file lists positions (``v``), texture coordinates (``vt``) and normals (``vn``), each
numbered from 1 in the order written, and faces (``f``) whose corners name one of each by
number: ``f 1/4/2 ...`` is position 1, texture coordinate 4 and normal 2. A face may have
any number of corners; groups (``g``) and objects (``o``) name runs of faces, and ``usemtl``
picks a material from the MTL file named by ``mtllib`` (Wavefront's specifications of both
formats, kept at https://paulbourke.net/dataformats/obj/ and .../mtl/).

marchlab's `TriangleMesh` has one index per vertex instead, so a vertex here is one
distinct (position, normal, texture coordinate) triple of a face corner: a cube corner used
by three faces with three normals becomes three vertices. The file is read by tinyobjloader
(Syoyo Fujita's loader, https://github.com/tinyobjloader/tinyobjloader), which also cuts
faces of more than three corners into triangles; this module turns what it read into
`ObjPart` records, and what a user got wrong into one-line `SceneError` messages.

OBJ faces turn counter-clockwise seen from outside, which is marchlab's outward winding
(`scene_model.meshes`): the winding is kept as in the file.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

import numpy as np
import tinyobjloader

from .errors import SceneError
from .meshes import TriangleMesh
from .scene import Material, Texture


@dataclass(frozen=True)
class ObjPart:
    """One object of an OBJ file: a group's triangles of one material.

    Attributes
    ----------
    name : str
        The group's (or object's) name; ``"group/material"`` where a group uses several
        materials (its faces without one keep the bare ``"group"``). Faces before any
        ``g`` or ``o`` line are named after the file (``pawn`` for pawn.obj).
    mesh : TriangleMesh
        Its triangles, in the file's own units and winding.
    material : Material or None
        Its MTL material; None where the faces have none (the scene then gives one).
    """
    name: str
    mesh: TriangleMesh
    material: Material | None


def load_obj(path) -> list[ObjPart]:
    """The parts of an OBJ file, in the order their groups first appear in it.

    Parameters
    ----------
    path : str or os.PathLike
        The OBJ file. Its ``mtllib`` files, and the images they name, are read relative to
        the OBJ file's folder.

    Returns
    -------
    list of ObjPart
        One per group or object (faces of groups of one name are gathered), and within a
        group one per material. A corner without a normal gets its triangle's own (flat
        shading: a planar face's normal), a corner without texture coordinates (0, 0).
        Normals are made unit length. Triangles of no area whose corners lack a normal are
        left out: they cover no pixel and have no normal. Points (``p``) and lines (``l``)
        are ignored.

    Raises
    ------
    SceneError
        The file is missing or unreadable, is not UTF-8 text, cannot be parsed, names a
        position, texture coordinate or normal it does not have, holds no triangles, or names
        an MTL file, a material or a texture image that does not exist.
    """
    source = os.fspath(path)
    _check_readable(source)
    reader = tinyobjloader.ObjReader()
    config = tinyobjloader.ObjReaderConfig()
    config.triangulate = True
    if not reader.ParseFromFile(source, config):
        raise SceneError(f"cannot parse it: {_first_line(reader.Error())}", (), source)
    try:
        return _parts(reader, source)
    except UnicodeDecodeError:        # pybind11 decodes the MTL file's names as UTF-8
        raise SceneError("a name in its MTL file (of a material or an image) is not UTF-8 "
                         "text", (), source) from None


def _check_readable(source: str) -> None:
    """Read the file once ourselves: tinyobjloader reads a folder or a missing file as an
    empty model, and pybind11 would fail on names that are not UTF-8 with a traceback."""
    try:
        with open(source, "rb") as file:
            file.read().decode("utf-8")
    except IsADirectoryError:
        raise SceneError("is a folder, not an OBJ file", (), source) from None
    except OSError as err:
        raise SceneError(f"cannot read: {err.strerror}", (), source) from None
    except UnicodeDecodeError as err:
        raise SceneError(f"not UTF-8 text (byte {err.object[err.start]:#04x} at offset "
                         f"{err.start})", (), source) from None


def _first_line(text: str) -> str:
    return text.strip().splitlines()[0] if text.strip() else "unknown problem"


# tinyobjloader reports these as warnings and goes on, with a grey model or without the
# face; a user would rather hear of them. (Its line numbers are those where a group ends,
# not the face's, so they are not repeated.)
_MISSING_MATERIALS = (
    (re.compile(r"Material file \[ (.*?) \] not found"),
     lambda m: f"its material library {m[1]!r} is not found (relative to the OBJ file)"),
    (re.compile(r"material \[ '(.*?)' \] not found"),
     lambda m: f"usemtl {m[1]!r}: no material of that name in its MTL file"),
)
_BAD_INDEX = re.compile(r"indices out of bounds|invalid vertex index")


def _parts(reader, source: str) -> list[ObjPart]:
    warnings = reader.Warning()
    for pattern, problem in _MISSING_MATERIALS:
        found = pattern.search(warnings)
        if found:
            raise SceneError(problem(found), (), source)
    attrib = reader.GetAttrib()
    positions = np.asarray(attrib.vertices, np.float64).reshape(-1, 3)
    normals = np.asarray(attrib.normals, np.float64).reshape(-1, 3)
    uvs = np.asarray(attrib.texcoords, np.float64).reshape(-1, 2)
    # (Their numpy_* twins return zeros in tinyobjloader 2.0.0rc13: the lists are read.)
    if not all(np.isfinite(a).all() for a in (positions, normals, uvs)):
        raise SceneError("a v, vt or vn line holds a number beyond float64 (inf or NaN)", (),
                         source)

    # Groups of one name are gathered: (T, 3 corners, 3) indices of (position, normal, uv),
    # and each face's material number (-1: none).
    stem = os.path.splitext(os.path.basename(source))[0]
    groups: dict[str, list] = {}
    for shape in reader.GetShapes():
        faces = shape.mesh                # (its .indices, an object a corner, are slow)
        indices = (faces.vertex_indices(), faces.normal_indices(), faces.texcoord_indices())
        if not indices[0]:
            continue
        corners = np.array(indices, np.int64).T.reshape(-1, 3, 3)
        _check_indices(corners, (len(positions), len(normals), len(uvs)), source)
        group = groups.setdefault(shape.name or stem, [[], []])
        group[0].append(corners)
        group[1].append(np.asarray(faces.material_ids, np.int64))
    if _BAD_INDEX.search(warnings):                 # a face tinyobjloader left out
        raise SceneError("a face names a position, texture coordinate or normal the file "
                         "does not have", (), source)

    library = reader.GetMaterials()
    folder = os.path.dirname(os.path.abspath(source))
    materials: dict[int, Material] = {}
    parts = []
    for name, (corner_list, id_list) in groups.items():
        corners, material_ids = np.concatenate(corner_list), np.concatenate(id_list)
        used = list(dict.fromkeys(material_ids.tolist()))        # in the order first used
        for number in used:
            mesh = _unindexed(corners[material_ids == number], positions, normals, uvs)
            if len(mesh.triangles) == 0:
                continue
            if number >= 0 and number not in materials:
                materials[number] = _material(library[number], folder, source)
            several = len(used) > 1 and number >= 0
            parts.append(ObjPart(f"{name}/{library[number].name}" if several else name,
                                 mesh, materials.get(number)))
    if not parts:
        raise SceneError("holds no triangles (no 'f' line of three corners or more, not all "
                         "on one line)", (), source)
    return parts


def _check_indices(corners: np.ndarray, counts: tuple, source: str) -> None:
    """Every index within its array (-1, for a normal or a texture coordinate: none given)."""
    for k, (what, count) in enumerate(zip(("position", "normal", "texture coordinate"),
                                          counts)):
        index = corners[..., k]
        lowest = 0 if k == 0 else -1
        bad = (index < lowest) | (index >= count)
        if bad.any():
            raise SceneError(f"a face names {what} {int(index[bad][0]) + 1}, but the file "
                             f"has {count}", (), source)


def _unindexed(corners: np.ndarray, positions, normals, uvs) -> TriangleMesh:
    """The triangles of ``corners`` ((T, 3, 3) indices of position, normal and texture
    coordinate, -1 for none) with one vertex per distinct triple, numbered in the order the
    faces first use them."""
    # Index -1 picks a row appended to the end: a zero normal (none) and uv (0, 0).
    normals = np.concatenate([normals, np.zeros((1, 3))])
    uvs = np.concatenate([uvs, np.zeros((1, 2))])
    p = positions[corners[..., 0]]                                      # (T, 3, 3)
    flat = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])               # right-hand normal
    flat_length = np.linalg.norm(flat, axis=1)                          # (T,)
    given = normals[corners[..., 1]]                                    # (T, 3, 3)
    given_length = np.linalg.norm(given, axis=2)                        # (T, 3)
    usable = given_length > 0                          # "vn 0 0 0" is no normal either
    keep = usable.all(axis=1) | (flat_length > 0)
    corners, flat, flat_length, given, given_length, usable = (
        a[keep] for a in (corners, flat, flat_length, given, given_length, usable))

    own = flat / np.maximum(flat_length, 1e-300)[:, None]
    corner_normals = np.where(usable[..., None],
                              given / np.maximum(given_length, 1e-300)[..., None],
                              own[:, None, :])                          # (T, 3, 3)
    # A flat-shaded corner is its triangle's alone: its key names the triangle, not a normal.
    triangle = np.arange(len(corners))[:, None]
    keys = np.stack([corners[..., 0], np.where(usable, corners[..., 1], -2 - triangle),
                     corners[..., 2]], axis=-1).reshape(-1, 3)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    corner = first[order]                      # the first corner (flat index) of each vertex
    return TriangleMesh(positions[keys[corner, 0]], corner_normals.reshape(-1, 3)[corner],
                        uvs[keys[corner, 2]], rank[inverse.ravel()].reshape(-1, 3))


def _material(mtl, folder: str, source: str) -> Material:
    """marchlab's Phong `Material` for an MTL material.

    MTL's Kd is the diffuse reflectance, colour and weight in one, so it becomes ``color``
    with ``kd = 1``; Ks is a colour where marchlab has a weight, so ``ks`` is its mean; Ns,
    the Phong exponent, is kept within marchlab's [1, 10000]. tinyobjloader reads a missing
    Kd or Ks as black. Ka is left for marchlab's ambient weight 0.1 (exporters often write
    Ka 1 1 1, which would wash a picture out). Dissolve (d, Tr) is not glass, which is
    what ``transparency`` means here, so it is ignored, as are the other maps and illum.
    map_Kd becomes a ``uv`` texture of the image, read relative to the OBJ file's folder.
    """
    texture = None
    if mtl.diffuse_texname:
        name = mtl.diffuse_texname.replace("\\", "/")           # written on Windows
        image = os.path.normpath(os.path.join(folder, name))
        if not os.path.isfile(image):
            raise SceneError(f"material {mtl.name!r}: its map_Kd image {name!r} does not "
                             f"exist (looked for {image})", (), source)
        texture = Texture(image=image, mapping="uv", scale=1.0)
    try:
        return Material(color=_unit(mtl.diffuse), ka=0.1, kd=1.0,
                        ks=float(np.mean(_unit(mtl.specular))),
                        shininess=float(np.clip(mtl.shininess, 1.0, 10000.0)), texture=texture)
    except SceneError as err:        # NaN, which no clip mends, or an odd image name
        raise SceneError(f"material {mtl.name!r}: {err}", (), source) from None


def _unit(values) -> tuple:
    """A colour clipped to [0, 1]: MTL allows more, marchlab's materials do not."""
    return tuple(float(np.clip(v, 0.0, 1.0)) for v in values)
