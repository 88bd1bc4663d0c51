"""The scene's SDF tree as plain data: primitives, CSG operators and transforms.

These classes hold parameters only. The distance formulas live in each backend under the same
names (``sdf_sphere`` in reference_cpu/sdf.py, later in GLSL and OpenCL C). Each node type has a
``kind``, the ``type`` it is given in a scene file. Python operators build trees:
``a | b`` (union), ``a & b`` (intersection), ``a - b`` (subtraction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Iterator

from .errors import SceneError
from .fields import (COORDINATE, DIRECTION, MAX_DEGREES, MIN_SIZE, POINT, SIZE, SIZES, Each, Int3,
                     Range, Record, Rule, Vec3, number_text, param, show, unit_interval)

# The deepest tree a scene may hold: a primitive is 1 level, each operator or transform above
# it one more. Every engine walks the tree recursively (Python allows 1000 frames, a shader
# compiler fewer), so depth is bounded where a tree is made, not where it is walked.
MAX_DEPTH = 64
TOO_DEEP = f"nested deeper than the limit of {MAX_DEPTH} levels"


class Node(Record):
    """Base of every node of the SDF tree; carries the builder's operators."""

    kind: ClassVar[str] = ""

    def __post_init__(self):
        super().__post_init__()
        # A node's children were checked when they were made, so one more level is all that
        # can go over the limit here, and the depth is known without walking the tree.
        depth = 1 + max((node_depth(c) for c in children(self)), default=0)
        if depth > MAX_DEPTH:
            raise SceneError(TOO_DEEP, path_to_depth(self, MAX_DEPTH + 1))
        object.__setattr__(self, "_depth", depth)     # not a field: equality ignores it

    # CSG: Python's set operators, as in fogleman/sdf.
    def __or__(self, other: Node) -> Node:
        return Union(_flat(Union, self) + _flat(Union, other))

    def __and__(self, other: Node) -> Node:
        return Intersection(_flat(Intersection, self) + _flat(Intersection, other))

    def __sub__(self, other: Node) -> Node:
        return Subtraction((self, other))

    def smooth_union(self, other: Node, k: float) -> Node:
        return SmoothUnion((self, other), k)

    def smooth_intersection(self, other: Node, k: float) -> Node:
        return SmoothIntersection((self, other), k)

    def smooth_subtraction(self, other: Node, k: float) -> Node:
        return SmoothSubtraction((self, other), k)

    def morph(self, other: Node, t: float) -> Node:
        return Morph((self, other), t)

    # Transforms wrap the node; they apply in the order written, like matrix products read
    # right to left: ``box.rotate(0, 45, 0).at(0, 1, 0)`` turns the box, then moves it.
    def at(self, x: float, y: float, z: float) -> Node:
        return Translate(self, (x, y, z))

    translate = at

    def rotate(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Node:
        return Rotate(self, (x, y, z))

    def scale(self, factor: float) -> Node:
        return Scale(self, factor)

    def repeat(self, period, count=None) -> Node:
        return Repeat(self, period, count)


def _flat(cls, node: Node) -> tuple[Node, ...]:
    """Children of ``node`` if it is already a ``cls`` (so ``a | b | c`` is one union)."""
    return node.children if type(node) is cls else (node,)


# --- Primitives ----------------------------------------------------------------------------
# Exact SDFs from Inigo Quilez, "Distance functions" (iquilezles.org/articles/distfunctions).
# Every primitive is centred on its local origin; move it with translate/rotate/scale.

@dataclass(frozen=True)
class Primitive(Node):
    """A leaf of the tree: a shape with a material. Its object id is its depth-first index."""

    material: str = param("default", "Name of a material in the scene's [materials] table.",
                          kw_only=True)


@dataclass(frozen=True)
class Sphere(Primitive):
    """Sphere of ``radius`` around the origin."""
    kind: ClassVar[str] = "sphere"
    radius: float = param(1.0, "Radius.", SIZE)


@dataclass(frozen=True)
class Box(Primitive):
    """Axis-aligned box from ``-half_size`` to ``+half_size``."""
    kind: ClassVar[str] = "box"
    half_size: Vec3 = param((0.5, 0.5, 0.5), "Half the box's extent along x, y, z.", SIZES)


@dataclass(frozen=True)
class RoundBox(Primitive):
    """Box with edges rounded by ``radius``; its outer extent is still ``half_size``."""
    kind: ClassVar[str] = "round_box"
    half_size: Vec3 = param((0.5, 0.5, 0.5), "Half the box's extent along x, y, z.", SIZES)
    radius: float = param(0.1, "Radius of the rounded edges.", SIZE)

    def check(self):
        if self.radius > min(self.half_size):
            raise SceneError(f"must not exceed the smallest half_size component "
                             f"{show(min(self.half_size))} (got {show(self.radius)})", ("radius",))


@dataclass(frozen=True)
class Plane(Primitive):
    """Half-space below the plane ``n . x = offset``, where n = normal / |normal| (the normal
    need not be unit length: it is normalised); n points out of the solid."""
    kind: ClassVar[str] = "plane"
    normal: Vec3 = param((0.0, 1.0, 0.0), "Outward normal (normalised when evaluated).",
                         DIRECTION)
    offset: float = param(0.0, "Distance of the plane from the origin along the normalised "
                               "normal.", COORDINATE)


@dataclass(frozen=True)
class Torus(Primitive):
    """Torus in the xz-plane: a circle of ``major_radius`` swept by a disc of ``minor_radius``."""
    kind: ClassVar[str] = "torus"
    major_radius: float = param(1.0, "Radius of the ring's centre line.", SIZE)
    minor_radius: float = param(0.25, "Radius of the tube.", SIZE)


@dataclass(frozen=True)
class CappedCylinder(Primitive):
    """Solid cylinder along y, from ``-half_height`` to ``+half_height``."""
    kind: ClassVar[str] = "capped_cylinder"
    radius: float = param(0.5, "Radius.", SIZE)
    half_height: float = param(0.5, "Half the height.", SIZE)


@dataclass(frozen=True)
class Capsule(Primitive):
    """All points within ``radius`` of the segment from ``a`` to ``b``."""
    kind: ClassVar[str] = "capsule"
    a: Vec3 = param((0.0, -0.5, 0.0), "One end of the segment.", POINT)
    b: Vec3 = param((0.0, 0.5, 0.0), f"The other end of the segment, at least "
                                     f"{number_text(MIN_SIZE)} from a.", POINT)
    radius: float = param(0.25, "Radius.", SIZE)

    def check(self):
        # The SDF divides by |b - a|^2.
        if self.a == self.b:
            raise SceneError("must differ from a (a capsule with a == b is a sphere)", ("b",))
        if math.dist(self.a, self.b) < MIN_SIZE:
            raise SceneError(f"must be at least {number_text(MIN_SIZE)} from a (got "
                             f"{show(self.b)}, a = {show(self.a)})", ("b",))


@dataclass(frozen=True)
class Cone(Primitive):
    """Solid cone along y: base disc of ``radius`` at y = 0, apex at y = ``height``."""
    kind: ClassVar[str] = "cone"
    radius: float = param(0.5, "Radius of the base.", SIZE)
    height: float = param(1.0, "Height of the apex above the base.", SIZE)


@dataclass(frozen=True)
class Pyramid(Primitive):
    """Square pyramid along y: base of side ``base`` at y = 0 (|x|, |z| <= base / 2), apex at
    y = ``height``."""
    kind: ClassVar[str] = "pyramid"
    base: float = param(1.0, "Side of the square base (the whole side, not half of it).", SIZE)
    height: float = param(1.0, "Height of the apex above the base.", SIZE)


@dataclass(frozen=True)
class Disk(Primitive):
    """Round disk in the xz-plane: the points within ``thickness`` / 2 of the flat circle of
    radius ``radius`` - ``thickness`` / 2 in y = 0, so ``thickness`` thick, ``radius`` wide
    and its rim rounded."""
    kind: ClassVar[str] = "disk"
    radius: float = param(1.0, "Outer radius, rounded rim included.", SIZE)
    thickness: float = param(0.25, "Thickness along y, at most twice the radius.", SIZE)

    def check(self):
        # The flat circle inside has radius radius - thickness / 2, which must not be negative
        # (at thickness = 2 radius the disk is a sphere).
        if self.thickness > 2 * self.radius:
            raise SceneError(f"must not exceed twice the radius {show(self.radius)} "
                             f"(got {show(self.thickness)})", ("thickness",))


@dataclass(frozen=True)
class HexPrism(Primitive):
    """Hexagonal prism along z: a regular hexagon in the xy-plane with flat sides at
    y = +-``apothem``, from z = -``half_length`` to z = +``half_length``."""
    kind: ClassVar[str] = "hex_prism"
    apothem: float = param(0.5, "Distance from the axis to each flat side of the hexagon.", SIZE)
    half_length: float = param(0.5, "Half the prism's length along z.", SIZE)


# --- CSG operators -----------------------------------------------------------------------

at_least_one = Rule(lambda children: len(children) >= 1, "must have at least one child",
                   "at least 1")


@dataclass(frozen=True)
class Union(Node):
    """min of the children's distances."""
    kind: ClassVar[str] = "union"
    children: tuple[Node, ...] = param(doc="The shapes joined.", check=at_least_one)


@dataclass(frozen=True)
class Intersection(Node):
    """max of the children's distances."""
    kind: ClassVar[str] = "intersection"
    children: tuple[Node, ...] = param(doc="The shapes intersected.", check=at_least_one)


@dataclass(frozen=True)
class Subtraction(Node):
    """The first child minus all others: max(d0, -d1, -d2, ...)."""
    kind: ClassVar[str] = "subtraction"
    children: tuple[Node, ...] = param(doc="The shape, then what is cut from it.",
                                       check=at_least_one)


@dataclass(frozen=True)
class SmoothUnion(Node):
    """Union blended over a width ``k`` (Quilez's polynomial smooth minimum)."""
    kind: ClassVar[str] = "smooth_union"
    children: tuple[Node, ...] = param(doc="The shapes joined, left to right.",
                                       check=at_least_one)
    k: float = param(0.25, "Width of the blend.", SIZE)


@dataclass(frozen=True)
class SmoothIntersection(Node):
    """Intersection blended over a width ``k``."""
    kind: ClassVar[str] = "smooth_intersection"
    children: tuple[Node, ...] = param(doc="The shapes intersected, left to right.",
                                       check=at_least_one)
    k: float = param(0.25, "Width of the blend.", SIZE)


@dataclass(frozen=True)
class SmoothSubtraction(Node):
    """The first child minus the others, blended over a width ``k``."""
    kind: ClassVar[str] = "smooth_subtraction"
    children: tuple[Node, ...] = param(doc="The shape, then what is cut from it.",
                                       check=at_least_one)
    k: float = param(0.25, "Width of the blend.", SIZE)


def exactly_two(kids) -> None:
    """The check of a morph's children: a blend has two ends."""
    if len(kids) != 2:
        raise SceneError(f"must have exactly 2 children (got {len(kids)})")


exactly_two.allowed = "exactly 2"


@dataclass(frozen=True)
class Morph(Node):
    """The first child turning into the second: d = (1 - t) d0 + t d1 (GLSL's mix).

    A bound, not an exact distance: with weights 1 - t and t in [0, 1] the mix of two
    1-Lipschitz distances is 1-Lipschitz, so |d| never exceeds the distance to the surface
    d = 0 and the march needs no safety factor (docs/sphere-tracing.md, "Morph"). Outside
    [0, 1] the constant would be |1 - t| + |t| > 1: such t is refused. The object id is the
    first child's where t <= 1/2, the second's above.
    """
    kind: ClassVar[str] = "morph"
    children: tuple[Node, ...] = param(doc="The two shapes: the first at t = 0, the second at "
                                           "t = 1.", check=exactly_two)
    t: float = param(0.5, "How far the first shape has turned into the second.",
                     unit_interval)


# --- Transforms ----------------------------------------------------------------------------
# A transform maps the query point into the child's frame (the inverse of moving the shape).

@dataclass(frozen=True)
class Translate(Node):
    """The child moved by ``offset``."""
    kind: ClassVar[str] = "translate"
    child: Node = param(doc="The shape moved.")
    offset: Vec3 = param((0.0, 0.0, 0.0), "Displacement.", POINT)


@dataclass(frozen=True)
class Rotate(Node):
    """The child turned by Euler angles in degrees: R = Rz(z) Ry(y) Rx(x), about x first."""
    kind: ClassVar[str] = "rotate"
    child: Node = param(doc="The shape rotated.")
    degrees: Vec3 = param((0.0, 0.0, 0.0), "Angles about x, y and z in degrees.",
                          Each(Range(-MAX_DEGREES, MAX_DEGREES)))


@dataclass(frozen=True)
class Scale(Node):
    """The child scaled uniformly by ``factor`` (the distance is multiplied back)."""
    kind: ClassVar[str] = "scale"
    child: Node = param(doc="The shape scaled.")
    factor: float = param(1.0, "Uniform scale factor.", SIZE)


MAX_COUNT = 100_000      # copies each way along an axis
PERIOD = Rule(lambda v: all(c == 0 or MIN_SIZE <= c <= SIZE.hi for c in v) and any(v),
              f"components must be 0 or in {SIZE.allowed}, not all 0",
              f"each 0 or in {SIZE.allowed}, not all 0")


@dataclass(frozen=True)
class Repeat(Node):
    """Copies of the child every ``period`` along each axis whose period is not 0.

    With ``count``, only the copies at cell indices -count..+count along each axis exist
    (Quilez's limited repetition); without it the repetition is infinite.
    """
    kind: ClassVar[str] = "repeat"
    child: Node = param(doc="The shape repeated.")
    period: Vec3 = param((1.0, 1.0, 1.0), "Spacing of the copies along x, y, z (0: no repeat).",
                         PERIOD)
    count: Int3 | None = param(None, "Copies on each side of the original along x, y, z; "
                                     "absent for infinite repetition.",
                               Each(Range(0, MAX_COUNT)))


def children(node: Node) -> tuple[Node, ...]:
    """The direct children of a node (none for a primitive)."""
    if hasattr(node, "children"):
        return node.children
    if hasattr(node, "child"):
        return (node.child,)
    return ()


def scene_union(objects: tuple[Node, ...]) -> Union:
    """The union joining a scene's objects, as the generated shaders draw them.

    It is the scene's list made a node, not a level anyone nested, so it may stand one level
    above `MAX_DEPTH` (a scene of one object 64 deep and the bodies' spheres): it is built
    without the depth check of `Node`, from children that each passed it.
    """
    root = object.__new__(Union)
    object.__setattr__(root, "children", tuple(objects))
    object.__setattr__(root, "_depth", 1 + max(node_depth(child) for child in objects))
    return root


def node_depth(node: Node) -> int:
    """Levels from ``node`` down to its deepest primitive (a primitive alone: 1)."""
    return node.__dict__["_depth"]


def path_to_depth(node: Node, level: int) -> tuple:
    """The path from ``node`` (level 1) down its deepest branch to the node at ``level``,
    e.g. ``("child", "children", 0)``."""
    path = []
    for _ in range(level - 1):
        if hasattr(node, "child"):
            path.append("child")
            node = node.child
        else:
            index = max(range(len(node.children)), key=lambda i: node_depth(node.children[i]))
            path += ["children", index]
            node = node.children[index]
    return tuple(path)


def primitives(nodes) -> Iterator[Primitive]:
    """The primitives under ``nodes`` in depth-first order; a primitive's object id is its index."""
    for node in nodes:
        if isinstance(node, Primitive):
            yield node
        else:
            yield from primitives(children(node))


# The solids that are convex for any parameters: boxes, balls, half-spaces, cylinders,
# capsules, cones, pyramids, disks (a disc thickened by a ball) and hexagonal prisms. The
# torus is not; nor is a union, a subtraction, a blend or a repetition of convex solids.
CONVEX_PRIMITIVES = (Sphere, Box, RoundBox, Plane, CappedCylinder, Capsule, Cone, Pyramid, Disk,
                     HexPrism)


def is_convex(node: Node) -> bool:
    """Is the solid of ``node`` convex, whatever its parameters?

    A convex primitive is; moving, turning or uniformly scaling a convex solid keeps it
    convex (an affine map takes segments to segments), and so does intersecting convex
    solids (a segment inside each is inside all). Everything else counts as not convex,
    even where it happens to be (a union of one child): the answer is used to skip work
    safely, so it may say no to a convex solid but never yes to another.
    """
    if isinstance(node, CONVEX_PRIMITIVES):
        return True
    if isinstance(node, (Translate, Rotate, Scale)):
        return is_convex(node.child)
    if isinstance(node, Intersection):
        return all(is_convex(child) for child in node.children)
    return False


def object_of_primitive(objects) -> list[int]:
    """For each primitive of a scene (by object id, `primitives`), the index of the top-level
    object in ``objects`` it belongs to."""
    return [index for index, node in enumerate(objects) for _ in primitives([node])]


def node_kinds() -> dict[str, type[Node]]:
    """Every concrete node class by its ``kind``."""
    found, stack = {}, [Node]
    while stack:
        cls = stack.pop()
        stack.extend(cls.__subclasses__())
        if cls.kind:
            found[cls.kind] = cls
    return found
