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
"""

from __future__ import annotations

from functools import reduce

from .bodies import Body, PhysicsSettings
from .scene import (Camera, Checker, CubeMapBackground, DirectionalLight, EquirectBackground, Fog,
                    Material, PointLight, RenderSettings, Scene, SkyBackground, SolidBackground,
                    SpotLight, StudioBackground, Texture)
from .shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Node, Plane, Pyramid,
                     RoundBox, Sphere, Torus)

__all__ = ["sphere", "box", "round_box", "plane", "torus", "capped_cylinder", "capsule", "cone",
           "pyramid", "disk", "hex_prism", "union", "intersection", "Scene", "Camera",
           "RenderSettings", "Material", "Checker", "PointLight", "DirectionalLight", "SpotLight",
           "Fog", "SkyBackground", "SolidBackground", "CubeMapBackground", "EquirectBackground",
           "StudioBackground", "Texture", "Body", "PhysicsSettings"]


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
