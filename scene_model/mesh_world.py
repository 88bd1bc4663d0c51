"""A scene's mesh nodes (`scene_model.mesh_objects`) as world-space triangles.

`scene_meshes` walks the hierarchy depth first, a node before its children, composing each
node's matrix with its parent's (M = M_parent T R S, `scene_model.meshes.local_matrix`), and
returns one `TriangleMesh` and one `Material` per object: object k of a raster picture is
entry k. Procedural meshes are generated once per distinct set of parameters and OBJ files
read once per version of the file, since a live view asks for the meshes every frame.
"""

from __future__ import annotations

import functools
import os

import numpy as np

from .meshes import PRIMITIVES, MeshNode, TriangleMesh, local_matrix, transformed
from .mesh_objects import MeshObject, ObjMesh, ProceduralMesh


def node_parts(node: MeshObject, folder=None) -> list[tuple[TriangleMesh, object]]:
    """The node's own triangles in its own frame, as (mesh, material) pairs: a material's
    name, or an OBJ file's own `Material` for a part the node names none for."""
    if isinstance(node, ProceduralMesh):
        return [(_generated(node.kind, tuple(node.arguments().items())), node.material)]
    if isinstance(node, ObjMesh):
        path = node.file if folder is None or os.path.isabs(node.file) else \
            os.path.join(folder, node.file)
        return [(part.mesh, node.material or part.material or "default")
                for part in _obj_parts(path, _modified(path))]
    return []                                              # a group


@functools.lru_cache(maxsize=256)
def _generated(kind: str, arguments: tuple) -> TriangleMesh:
    return PRIMITIVES[kind](**dict(arguments))


def _modified(path: str) -> float:
    try:
        return os.stat(path).st_mtime
    except OSError:
        return 0.0                              # load_obj says what is wrong with the file


@functools.lru_cache(maxsize=32)
def _obj_parts(path: str, modified: float):
    from .obj_files import load_obj
    return load_obj(path)


def check_obj_files(nodes, path=("meshes",)) -> None:
    """Read every OBJ file under ``nodes`` (kept for drawing), so that a missing or broken one
    is reported when the scene is loaded, as the field that names it (``meshes[2].file``)."""
    from .errors import SceneError
    for index, node in enumerate(nodes):
        if isinstance(node, ObjMesh):
            try:
                node_parts(node)
            except SceneError as err:
                raise SceneError(str(err), path + (index, "file")) from None
        check_obj_files(node.children, path + (index, "children"))


def scene_meshes(scene, folder=None) -> tuple[list[TriangleMesh], list]:
    """A scene's meshes in world coordinates, and the material of each.

    Parameters
    ----------
    scene : Scene
    folder : str or os.PathLike, optional
        Where relative OBJ file names start (a loaded scene's are already resolved against
        its file's folder, `scene_model.scenefile.with_files_from`).

    Returns
    -------
    meshes : list of TriangleMesh
        Depth first: a node's own parts, then its children's. Mesh k is object k.
    materials : list of Material
        The material of each mesh: the scene's by name, or an OBJ file's own.
    """
    meshes, materials = [], []

    def walk(node, parent):
        world = parent @ local_matrix(MeshNode(translate=node.position, rotate=node.rotation,
                                               scale=node.scale))
        for mesh, material in node_parts(node, folder):
            meshes.append(transformed(mesh, world))
            materials.append(scene.materials[material] if isinstance(material, str)
                             else material)
        for child in node.children:
            walk(child, world)

    for node in scene.meshes:
        walk(node, np.eye(4))
    return meshes, materials
