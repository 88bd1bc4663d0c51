"""A scene's triangle meshes as plain data: what a ``[[meshes]]`` table of a scene file holds.

The SDF tree (`scene_model.shapes`) describes a surface by its distance; these records
describe one by triangles, for the raster half of the toolkit. Each names a procedural mesh
of `scene_model.meshes` with its segment counts (``type = "uv_sphere"``), an OBJ file
(``type = "obj"``) or a ``group``, and places it in its parent's frame by ``position``,
``rotation`` and ``scale``: a node's world matrix is its parent's times its own,
M = M_parent T R S (`scene_model.meshes.local_matrix`), so a mobile's arm turns with the arm
above it. ``children`` hold the nodes placed in this one's frame.

`scene_model.mesh_world.scene_meshes` turns a scene's nodes into world-space triangles.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from typing import ClassVar

from .errors import SceneError
from .fields import (MAX_DEGREES, POINT, SIZE, SIZES, Each, Range, Record, Rule, Vec3,
                     param)

# The most segments (or grid cells) along one direction of a procedural mesh: far beyond
# this its triangles are smaller than a pixel of any picture, and the NumPy rasteriser is slow.
MAX_SEGMENTS = 1024
SEGMENTS = Range(3, MAX_SEGMENTS)
SUBDIVISIONS = Range(1, MAX_SEGMENTS)
MAX_MESH_DEPTH = 32           # nested groups, as the SDF tree's depth is bounded


def _material():
    return param("default", "Name of a material in the scene's [materials] table.",
                 kw_only=True)


@dataclass(frozen=True)
class MeshObject(Record):
    """Base of the mesh node types; ``kind`` is the ``type`` in a scene file."""
    kind: ClassVar[str] = ""
    position: Vec3 = param((0.0, 0.0, 0.0), "Where the node's origin is in its parent's "
                                            "frame (m).", POINT, kw_only=True)
    rotation: Vec3 = param((0.0, 0.0, 0.0), "Euler angles in degrees, turned about x, then y, "
                                            "then z (as an object's rotation).",
                           Each(Range(-MAX_DEGREES, MAX_DEGREES)), kw_only=True)
    scale: Vec3 = param((1.0, 1.0, 1.0), "Scale along the node's own x, y, z, applied first "
                                         "(a number scales all three).", SIZES, kw_only=True)
    children: tuple[MeshObject, ...] = param((), "Nodes placed in this node's frame.",
                                             kw_only=True)

    def __post_init__(self):
        if isinstance(self.scale, (int, float)) and not isinstance(self.scale, bool):
            object.__setattr__(self, "scale", (self.scale,) * 3)
        super().__post_init__()
        if mesh_depth(self) > MAX_MESH_DEPTH:
            raise SceneError(f"groups nested deeper than the limit of {MAX_MESH_DEPTH} levels",
                             ("children",))

    # The builder's operators (`scene_model.builder`). A node's own transform is always
    # T R S, whatever order these are called in: scale, then turn, then move.
    def at(self, x: float, y: float, z: float) -> MeshObject:
        """This node moved to (x, y, z) in its parent's frame."""
        return dataclasses.replace(self, position=(x, y, z))

    def rotate(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> MeshObject:
        """This node turned by Euler angles in degrees (about x, then y, then z)."""
        return dataclasses.replace(self, rotation=(x, y, z))

    def scaled(self, x: float, y: float | None = None, z: float | None = None) -> MeshObject:
        """This node scaled along its own axes (one number: all three)."""
        return dataclasses.replace(self, scale=(x, x, x) if y is None and z is None
                                   else (x, y, z))

    def holding(self, *children: MeshObject) -> MeshObject:
        """This node with ``children`` added, placed in its frame."""
        return dataclasses.replace(self, children=self.children + tuple(children))


def mesh_depth(node: MeshObject) -> int:
    """Levels of the hierarchy under ``node``, itself included."""
    return 1 + max((mesh_depth(c) for c in node.children), default=0)


@dataclass(frozen=True)
class MeshGroup(MeshObject):
    """No triangles of its own: a frame that places its children (a mobile's arm)."""
    kind: ClassVar[str] = "group"


class ProceduralMesh(MeshObject):
    """Base of the procedural meshes: each field but the placement and the material is a
    parameter of the generator ``scene_model.meshes.<kind>`` of the same name."""
    kind: ClassVar[str] = ""

    def arguments(self) -> dict:
        """The generator's keyword arguments."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name not in PLACEMENT}


PLACEMENT = ("position", "rotation", "scale", "children", "material")


def _radius(default=1.0):
    return param(default, "Radius (m).", SIZE)


def _height():
    return param(1.0, "Height (m).", SIZE)


def _segments():
    return param(32, "Segments around the axis.", SEGMENTS)


@dataclass(frozen=True)
class PlaneMesh(ProceduralMesh):
    """A width x depth rectangle in the xz-plane facing +y, centred on the origin."""
    kind: ClassVar[str] = "plane"
    width: float = param(1.0, "Extent along x (m).", SIZE)
    depth: float = param(1.0, "Extent along z (m).", SIZE)
    subdivisions: int = param(1, "Grid cells along each side.", SUBDIVISIONS)
    material: str = _material()


@dataclass(frozen=True)
class CubeMesh(ProceduralMesh):
    """An axis-aligned cube centred on the origin."""
    kind: ClassVar[str] = "cube"
    size: float = param(1.0, "Edge length (m).", SIZE)
    subdivisions: int = param(1, "Grid cells along each edge of a face.", SUBDIVISIONS)
    material: str = _material()


@dataclass(frozen=True)
class CubeSphereMesh(ProceduralMesh):
    """A sphere made by pushing a subdivided cube's points out onto it."""
    kind: ClassVar[str] = "cube_sphere"
    radius: float = _radius()
    subdivisions: int = param(8, "Grid cells along each edge of a face.", SUBDIVISIONS)
    material: str = _material()


@dataclass(frozen=True)
class UvSphereMesh(ProceduralMesh):
    """A sphere of longitude segments and latitude rings."""
    kind: ClassVar[str] = "uv_sphere"
    radius: float = _radius()
    segments: int = _segments()
    rings: int = param(16, "Rings from pole to pole.", Range(2, MAX_SEGMENTS))
    material: str = _material()


@dataclass(frozen=True)
class DiskMesh(ProceduralMesh):
    """A flat disk in the xz-plane facing +y."""
    kind: ClassVar[str] = "disk"
    radius: float = _radius()
    segments: int = _segments()
    material: str = _material()


@dataclass(frozen=True)
class CylinderMesh(ProceduralMesh):
    """A closed cylinder around the y axis, from y = -height/2 to height/2."""
    kind: ClassVar[str] = "cylinder"
    radius: float = _radius(0.5)
    height: float = _height()
    segments: int = _segments()
    material: str = _material()


@dataclass(frozen=True)
class ConeMesh(ProceduralMesh):
    """A closed cone around the y axis, its base at y = 0 and its apex at y = height."""
    kind: ClassVar[str] = "cone"
    radius: float = _radius(0.5)
    height: float = _height()
    segments: int = _segments()
    material: str = _material()


@dataclass(frozen=True)
class PyramidMesh(ProceduralMesh):
    """A square pyramid, its base at y = 0 and its apex at y = height."""
    kind: ClassVar[str] = "pyramid"
    base: float = param(1.0, "Edge of the square base (m).", SIZE)
    height: float = _height()
    material: str = _material()


@dataclass(frozen=True)
class TorusMesh(ProceduralMesh):
    """A ring around the y axis."""
    kind: ClassVar[str] = "torus"
    major: float = param(1.0, "Radius of the ring's centre line (m).", SIZE)
    minor: float = param(0.25, "Radius of the tube (m).", SIZE)
    segments: int = _segments()
    sides: int = param(16, "Segments around the tube.", SEGMENTS)
    material: str = _material()


@dataclass(frozen=True)
class ObjMesh(MeshObject):
    """A model from a Wavefront OBJ file: one object per group (and per material within a
    group), coloured by its MTL file unless ``material`` names one of the scene's."""
    kind: ClassVar[str] = "obj"
    file: str = param("model.obj", "The OBJ file (relative to the scene file).",
                      Rule(lambda v: bool(v.strip()), "must name an OBJ file", "a file"))
    material: str | None = param(None, "A material of the scene's for every part; absent: "
                                       "the OBJ's own (its MTL file), else 'default'.",
                                 kw_only=True)



def relative_to(node: MeshObject, folder) -> MeshObject:
    """``node`` with the OBJ files under it read relative to ``folder`` (a scene file's own)."""
    kids = tuple(relative_to(child, folder) for child in node.children)
    changes = {"children": kids} if kids != node.children else {}
    if isinstance(node, ObjMesh):
        changes["file"] = _joined(folder, node.file)
    return dataclasses.replace(node, **changes) if changes else node


def _joined(folder, path: str) -> str:
    return path if os.path.isabs(path) else os.path.normpath(os.path.join(folder, path))


def mesh_kinds() -> dict[str, type]:
    """Every mesh node class by its ``kind``."""
    found = {}
    for cls in MeshObject.__subclasses__() + ProceduralMesh.__subclasses__():
        if cls.kind:
            found[cls.kind] = cls
    return found


def mesh_material_names(nodes) -> list[tuple[tuple, str]]:
    """(field path, material name) of every node that names one of the scene's materials."""
    found = []

    def walk(node, path):
        name = getattr(node, "material", None)
        if isinstance(name, str):
            found.append((path + ("material",), name))
        for k, child in enumerate(node.children):
            walk(child, path + ("children", k))

    for index, node in enumerate(nodes):
        walk(node, ("meshes", index))
    return found
