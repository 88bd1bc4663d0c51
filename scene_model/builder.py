"""Build scenes in Python, for notebooks::

    from scene_model.builder import *
    floor = plane(material="floor")
    ball = sphere(1, material="red").at(0, 1, 0)
    cut = box(1) - sphere(1.3)
    blob = sphere(0.6).smooth_union(sphere(0.6).at(0.8, 0, 0), k=0.3)
    scene = Scene(objects=[floor, ball, cut.rotate(0, 45, 0).at(3, 1, 0), blob],
                  materials={"floor": Material(checker=Checker()), "red": Material(color=(1, 0, 0)),
                             "default": Material()})

Each function returns a node of `scene_model.shapes`; the node's methods ``at``, ``rotate``,
``scale``, ``repeat``, ``smooth_union``..., ``morph`` (``a.morph(b, t)``: a turning into b as t
goes from 0 to 1) and the operators ``|``, ``&``, ``-`` combine them.

Triangle meshes (`scene_model.mesh_objects`, drawn by the raster backends) are built the same
way, by the functions ending in ``_mesh`` and by ``group``; a mesh node's ``at``, ``rotate``
and ``scaled`` set its own transform (always T R S: scale, then turn, then move), and
``holding`` places children in its frame::

    mobile = group(cylinder_mesh(0.015, 1.4).rotate(0, 0, 90),
                   uv_sphere_mesh(0.16, material="blue").at(-0.7, -0.25, 0)).at(0, 3, 0)
    scene = Scene(meshes=[plane_mesh(6, 6, subdivisions=4), mobile], ...)
"""

from __future__ import annotations

from functools import reduce

from .bodies import Body, PhysicsSettings
from .scene import (Camera, Checker, CubeMapBackground, DirectionalLight, EquirectBackground, Fog,
                    Material, PointLight, RenderSettings, Scene, SkyBackground, SolidBackground,
                    SpotLight, StudioBackground, Texture)
from .shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Node, Plane, Pyramid,
                     RoundBox, Sphere, Torus)
from .mesh_objects import (ConeMesh, CubeMesh, CubeSphereMesh, CylinderMesh, DiskMesh, MeshGroup,
                           MeshObject, ObjMesh, PlaneMesh, PyramidMesh, TorusMesh, UvSphereMesh)

__all__ = ["sphere", "box", "round_box", "plane", "torus", "capped_cylinder", "capsule", "cone",
           "pyramid", "disk", "hex_prism", "union", "intersection", "Scene", "Camera",
           "RenderSettings", "Material", "Checker", "PointLight", "DirectionalLight", "SpotLight",
           "Fog", "SkyBackground", "SolidBackground", "CubeMapBackground", "EquirectBackground",
           "StudioBackground", "Texture", "Body", "PhysicsSettings", "plane_mesh", "cube_mesh",
           "cube_sphere_mesh", "uv_sphere_mesh", "disk_mesh", "cylinder_mesh", "cone_mesh",
           "pyramid_mesh", "torus_mesh", "obj_mesh", "group"]


def _half_size(x, y, z):
    return (x, x, x) if y is None and z is None else (x, y, z)


def sphere(radius: float = 1.0, material: str = "default") -> Sphere:
    """Sphere of ``radius`` at the origin."""
    return Sphere(radius, material=material)


def box(x: float = 0.5, y: float | None = None, z: float | None = None,
        material: str = "default") -> Box:
    """Box with half-extents (x, y, z); ``box(h)`` is a cube of side 2h."""
    return Box(_half_size(x, y, z), material=material)


def round_box(x: float = 0.5, y: float | None = None, z: float | None = None,
              radius: float = 0.1, material: str = "default") -> RoundBox:
    """Box with half-extents (x, y, z) and edges rounded by ``radius``."""
    return RoundBox(_half_size(x, y, z), radius, material=material)


def plane(normal=(0.0, 1.0, 0.0), offset: float = 0.0, material: str = "default") -> Plane:
    """The solid below the plane ``n . x = offset`` with n = normal / |normal| (by default the
    floor y = 0). The normal need not be unit length; ``offset`` is measured along n, so
    ``plane((0, 2, 0), 1)`` is the floor y = 1, not y = 0.5."""
    return Plane(normal, offset, material=material)


def torus(major_radius: float = 1.0, minor_radius: float = 0.25,
          material: str = "default") -> Torus:
    """Torus lying in the xz-plane."""
    return Torus(major_radius, minor_radius, material=material)


def capped_cylinder(radius: float = 0.5, half_height: float = 0.5,
                    material: str = "default") -> CappedCylinder:
    """Cylinder along y from -half_height to +half_height."""
    return CappedCylinder(radius, half_height, material=material)


def capsule(a=(0.0, -0.5, 0.0), b=(0.0, 0.5, 0.0), radius: float = 0.25,
            material: str = "default") -> Capsule:
    """Points within ``radius`` of the segment a-b."""
    return Capsule(a, b, radius, material=material)


def cone(radius: float = 0.5, height: float = 1.0, material: str = "default") -> Cone:
    """Cone with its base disc at y = 0 and its apex at y = height."""
    return Cone(radius, height, material=material)


def pyramid(base: float = 1.0, height: float = 1.0, material: str = "default") -> Pyramid:
    """Square pyramid with its base (side ``base``) at y = 0 and its apex at y = height."""
    return Pyramid(base, height, material=material)


def disk(radius: float = 1.0, thickness: float = 0.25, material: str = "default") -> Disk:
    """Round disk in the xz-plane, ``radius`` wide and ``thickness`` thick, its rim rounded."""
    return Disk(radius, thickness, material=material)


def hex_prism(apothem: float = 0.5, half_length: float = 0.5,
              material: str = "default") -> HexPrism:
    """Hexagonal prism along z; its hexagon's flat sides are ``apothem`` from the axis."""
    return HexPrism(apothem, half_length, material=material)


def union(*nodes: Node) -> Node:
    """All the nodes joined."""
    return reduce(lambda a, b: a | b, nodes)


def intersection(*nodes: Node) -> Node:
    """Where all the nodes overlap."""
    return reduce(lambda a, b: a & b, nodes)


# --- Triangle meshes ----------------------------------------------------------------------------

def plane_mesh(width: float = 1.0, depth: float = 1.0, subdivisions: int = 1,
               material: str = "default") -> PlaneMesh:
    """A width x depth rectangle in the xz-plane facing +y, cut into subdivisions^2 cells."""
    return PlaneMesh(width=width, depth=depth, subdivisions=subdivisions, material=material)


def cube_mesh(size: float = 1.0, subdivisions: int = 1, material: str = "default") -> CubeMesh:
    """A cube of edge ``size`` centred on the origin."""
    return CubeMesh(size=size, subdivisions=subdivisions, material=material)


def cube_sphere_mesh(radius: float = 1.0, subdivisions: int = 8,
                     material: str = "default") -> CubeSphereMesh:
    """A sphere made from a subdivided cube pushed out to ``radius``."""
    return CubeSphereMesh(radius=radius, subdivisions=subdivisions, material=material)


def uv_sphere_mesh(radius: float = 1.0, segments: int = 32, rings: int = 16,
                   material: str = "default") -> UvSphereMesh:
    """A sphere of longitude segments and latitude rings."""
    return UvSphereMesh(radius=radius, segments=segments, rings=rings, material=material)


def disk_mesh(radius: float = 1.0, segments: int = 32, material: str = "default") -> DiskMesh:
    """A flat disk in the xz-plane facing +y."""
    return DiskMesh(radius=radius, segments=segments, material=material)


def cylinder_mesh(radius: float = 0.5, height: float = 1.0, segments: int = 32,
                  material: str = "default") -> CylinderMesh:
    """A closed cylinder around the y axis, from y = -height/2 to height/2."""
    return CylinderMesh(radius=radius, height=height, segments=segments, material=material)


def cone_mesh(radius: float = 0.5, height: float = 1.0, segments: int = 32,
              material: str = "default") -> ConeMesh:
    """A closed cone around the y axis, its base at y = 0."""
    return ConeMesh(radius=radius, height=height, segments=segments, material=material)


def pyramid_mesh(base: float = 1.0, height: float = 1.0,
                 material: str = "default") -> PyramidMesh:
    """A square pyramid, its base at y = 0."""
    return PyramidMesh(base=base, height=height, material=material)


def torus_mesh(major: float = 1.0, minor: float = 0.25, segments: int = 32, sides: int = 16,
               material: str = "default") -> TorusMesh:
    """A ring around the y axis."""
    return TorusMesh(major=major, minor=minor, segments=segments, sides=sides,
                     material=material)


def obj_mesh(file: str, material: str | None = None) -> ObjMesh:
    """An OBJ model (its MTL colours unless ``material`` names one of the scene's)."""
    return ObjMesh(file=file, material=material)


def group(*children: MeshObject) -> MeshGroup:
    """A frame holding ``children``: move, turn or scale it and they follow."""
    return MeshGroup(children=tuple(children))

