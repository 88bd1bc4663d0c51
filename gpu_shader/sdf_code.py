"""The scene's SDF tree written out as code: ``scene_sdf(p)`` and ``scene_object_id(p)``.

The generated functions do what `reference_cpu.scene_sdf.build_scene_sdf` does, node by node
and in the same order: transforms move the query point, primitives give a distance,
operators fold their children left to right, and the object id follows the distance the
operator chose. Each node's numbers live in the parameter block, so the text depends only on
the tree's shape. The physics step's colliders are the same code, one object at a time
(`sdf_functions`).
"""

from __future__ import annotations

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.geometry import rotation_matrix
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Intersection,
                                Morph, Node, Plane, Pyramid, Repeat, Rotate, RoundBox, Scale,
                                SmoothIntersection, SmoothSubtraction, SmoothUnion, Sphere,
                                Subtraction, Torus, Translate, Union, scene_union)

from reference_cpu.culling import own_objects

from .parameters import ParameterBlock

# Binary operators: (library function, the field of its number (k, t) or None, condition
# keeping the first id, where {n} is that number), as `reference_cpu.scene_sdf._COMBINE`
# and, for the morph, `reference_cpu.scene_sdf._morph`.
OPERATORS = {
    Union: ("op_union", None, "{a} <= {b}"),
    Intersection: ("op_intersection", None, "{a} >= {b}"),
    Subtraction: ("op_subtraction", None, "{a} >= -{b}"),
    SmoothUnion: ("op_smooth_union", "k", "{a} <= {b}"),
    SmoothIntersection: ("op_smooth_intersection", "k", "{a} >= {b}"),
    SmoothSubtraction: ("op_smooth_subtraction", "k", "{a} >= -{b}"),
    Morph: ("op_morph", "t", "{n} <= 0.5"),
}

PRIMITIVES = {Sphere: "sdf_sphere", Box: "sdf_box", RoundBox: "sdf_round_box",
              Plane: "sdf_plane", Torus: "sdf_torus", CappedCylinder: "sdf_capped_cylinder",
              Capsule: "sdf_capsule", Cone: "sdf_cone", Pyramid: "sdf_pyramid", Disk: "sdf_disk",
              HexPrism: "sdf_hex_prism"}

TRANSFORMS = {Translate: "op_translate", Rotate: "op_rotate", Scale: "op_scale",
              Repeat: "op_repeat"}


def scene_root(objects) -> Node | None:
    """The tree the scene's objects form: one object, or the union of all of them."""
    if not objects:
        return None
    return objects[0] if len(objects) == 1 else scene_union(tuple(objects))


def primitive_parameters(node: Node) -> tuple[list, list[str]]:
    """The parameter rows of a primitive and the arguments that read them (row ``{r}``)."""
    match node:
        case Sphere():
            return [[node.radius]], ["P[{r}].x"]
        case Box():
            return [node.half_size], ["P[{r}].xyz"]
        case RoundBox():
            return [[*node.half_size, node.radius]], ["P[{r}].xyz", "P[{r}].w"]
        case Plane():
            normal = np.divide(node.normal, np.linalg.norm(node.normal))
            return [[*normal, node.offset]], ["P[{r}].xyz", "P[{r}].w"]
        case Torus():
            return [[node.major_radius, node.minor_radius]], ["P[{r}].x", "P[{r}].y"]
        case CappedCylinder():
            return [[node.radius, node.half_height]], ["P[{r}].x", "P[{r}].y"]
        case Capsule():
            return ([[*node.a, node.radius], node.b],
                    ["P[{r}].xyz", "P[{r1}].xyz", "P[{r}].w"])
        case Cone():
            return [[node.radius, node.height]], ["P[{r}].x", "P[{r}].y"]
        case Pyramid():
            return [[node.base, node.height]], ["P[{r}].x", "P[{r}].y"]
        case Disk():
            return [[node.radius, node.thickness]], ["P[{r}].x", "P[{r}].y"]
        case HexPrism():
            return [[node.apothem, node.half_length]], ["P[{r}].x", "P[{r}].y"]
    raise unsupported(node)


def transform_parameters(node: Node) -> tuple[str, list, list[str]]:
    """(function, rows, arguments) of a transform node."""
    match node:
        case Translate():
            return "op_translate", [node.offset], ["P[{r}].xyz"]
        case Rotate():
            r = rotation_matrix(node.degrees)
            return ("op_rotate", [r[:, 0], r[:, 1], r[:, 2]],
                    ["P[{r}].xyz", "P[{r1}].xyz", "P[{r2}].xyz"])
        case Scale():
            return "op_scale", [[node.factor]], ["P[{r}].x"]
        case Repeat(count=None):
            return "op_repeat", [node.period], ["P[{r}].xyz"]
        case Repeat():
            return "op_repeat_limited", [node.period, node.count], ["P[{r}].xyz", "P[{r1}].xyz"]
    raise unsupported(node)


def unsupported(node: Node) -> MarchlabError:
    kind = getattr(node, "kind", "") or type(node).__name__
    return MarchlabError(f"the shader generator does not support {kind!r} "
                         f"({type(node).__name__}) nodes yet; render this scene with "
                         "--backend numpy")


class SdfWriter:
    """Writes the body of ``scene_sdf`` (distances) or ``scene_object_id`` (distances and ids).

    Both walks visit the tree in the same order, so they allocate the same parameter rows;
    the second walk is given the rows the first allocated (``replay``) and checks them.
    """

    def __init__(self, block: ParameterBlock, with_ids: bool, replay: list[int] | None = None):
        self.block, self.with_ids = block, with_ids
        self.lines: list[str] = []
        self.used: set[str] = set()              # library functions called
        self.rows: list[int] = []                # first row of each node, in visit order
        self._replay = iter(replay) if replay is not None else None
        self._names = 0
        self._next_id = 0

    def allocate(self, rows) -> int:
        if self._replay is not None:
            first = next(self._replay)
        else:
            first = len(self.block.rows)
            for values in rows:
                self.block.row(values)
        self.rows.append(first)
        return first

    def name(self, prefix: str) -> str:
        self._names += 1
        return f"{prefix}{self._names}"

    def call(self, function: str, args: list[str], first_row: int) -> str:
        rows = {"r": first_row, "r1": first_row + 1, "r2": first_row + 2}
        self.used.add(function)
        return f"{function}({', '.join(a.format(**rows) for a in args)})"

    def node(self, node: Node, p: str) -> tuple[str, str]:
        """Emit code for ``node`` at query point ``p``; return (distance variable, id
        expression)."""
        if type(node) in PRIMITIVES:
            object_id = self._next_id
            self._next_id += 1
            rows, args = primitive_parameters(node)
            first = self.allocate(rows)
            d = self.name("d")
            # (No material name here: which material an object wears is a parameter.)
            self.lines.append(f"// object {object_id}: {node.kind}")
            self.lines.append(f"real {d} = {self.call(PRIMITIVES[type(node)], [p] + args, first)};")
            return d, str(object_id)
        if type(node) in TRANSFORMS:
            function, rows, args = transform_parameters(node)
            first = self.allocate(rows)
            q = self.name("p")
            self.lines.append(f"vec3 {q} = {self.call(function, [p] + args, first)};")
            d, ids = self.node(node.child, q)
            if isinstance(node, Scale):                  # scale the distance back
                self.lines.append(f"{d} = {d} * P[{first}].x;")
            return d, ids
        if type(node) in OPERATORS:
            return self.combine(node, p)
        raise unsupported(node)

    def combine(self, node: Node, p: str) -> tuple[str, str]:
        """Fold the children left to right, as the reference does."""
        function, number, keeps_first = OPERATORS[type(node)]
        first = self.allocate([[getattr(node, number)]] if number else [])
        value = [f"P[{first}].x"] if number else []        # k or t, from the parameter block
        d, ids = self.node(node.children[0], p)
        result, result_id = self.name("d"), self.name("id")
        self.lines.append(f"real {result} = {d};")
        if self.with_ids:
            self.lines.append(f"int {result_id} = {ids};")
        for child in node.children[1:]:
            d2, ids2 = self.node(child, p)
            if self.with_ids:
                condition = keeps_first.format(a=result, b=d2, n=(value or [""])[0])
                self.lines.append(f"{result_id} = {condition} ? {result_id} : {ids2};")
            self.used.add(function)
            args = ", ".join([result, d2] + value)
            self.lines.append(f"{result} = {function}({args});"
                              + ("  // " + node.kind if not self.with_ids else ""))
        return result, result_id


def scene_sdf_code(objects, block: ParameterBlock, bits=None,
                   own: bool = False) -> tuple[str, set[str]]:
    """Source of ``scene_sdf``, ``scene_object_id`` and the marches' ``ray_objects`` and
    ``march_sdf``, and the library functions they use.

    ``bits``, the list of `reference_cpu.culling.object_bits`, gives the objects a march may
    leave out a bit each (bounding-sphere culling, shadow rays' own objects); None writes a
    ``march_sdf`` that is ``scene_sdf``. With ``own`` it also writes ``own_object``, each
    primitive's own object's bit, which its hard shadow rays leave out. (A packet program
    derives its own from this code: gpu_shader/packets.py.)
    """
    root = scene_root(objects)
    if root is None:
        return ("// An empty scene: every ray misses.\n"
                "real scene_sdf(vec3 p)\n{\n    return MAX_DISTANCE * 2.0;\n}\n\n"
                "int scene_object_id(vec3 p)\n{\n    return -1;\n}\n\n"
                + (_own_object(objects, []) if own else "") + _unculled_march_sdf()), set()
    source, used, rows = sdf_functions(root, block)
    if own:
        source += _own_object(objects, bits or [])
    if not bits:
        return source + _unculled_march_sdf(), used
    # The union node of several objects allocated the first (empty) entry of the walk.
    replay = rows[1:] if len(objects) > 1 else rows
    culled, culled_used = _culled_march_sdf(objects, block, bits, replay)
    return source + culled, used | culled_used


def _own_object(objects, bits) -> str:
    """``own_object(id)``: the bit of the convex object primitive id belongs to, as
    `reference_cpu.culling.own_objects` finds it, or 0u."""
    owner = own_objects(objects, bits)
    bit = {index: 1 << k for k, (index, _, _) in enumerate(bits)}
    tests = []
    for index in sorted(set(owner[owner >= 0].tolist())):
        ids = np.flatnonzero(owner == index)
        first, last = int(ids[0]), int(ids[-1])
        condition = f"id == {first}" if first == last else f"id >= {first} && id <= {last}"
        tests.append(f"    if ({condition}) {{\n        own = {bit[index]}u;\n    }}\n")
    return ("// The bit of the convex object that primitive id belongs to: its hard shadow rays\n"
            "// leave it out, as they cannot meet it again (reference_cpu/shadows.py); 0u for a\n"
            "// primitive of any other object.\n"
            "uint own_object(int id)\n{\n    uint own = 0u;\n" + "".join(tests)
            + "    return own;\n}\n\n")


def sdf_functions(root: Node, block: ParameterBlock, distance: str = "scene_sdf",
                  object_id: str = "scene_object_id",
                  what: str = "the scene") -> tuple[str, set[str], list[int]]:
    """Source of ``real distance(vec3 p)`` and ``int object_id(vec3 p)`` for the tree
    ``root``, the library functions they use, and the first parameter row of each node.

    The renderer writes the whole scene's tree as ``scene_sdf`` and ``scene_object_id``; the
    physics step writes each static object's tree under its own names
    (gpu_shader/physics_shapes.py). ``what`` is how the first comment names the tree.
    """
    distances = SdfWriter(block, with_ids=False)
    d, _ = distances.node(root, "p")
    ids = SdfWriter(block, with_ids=True, replay=distances.rows)
    _, id_value = ids.node(root, "p")
    body = "".join(f"    {line}\n" for line in distances.lines)
    id_body = "".join(f"    {line}\n" for line in ids.lines)
    source = (
        f"// The distance from p to the nearest surface of {what}.\n"
        f"real {distance}(vec3 p)\n{{\n{body}    return {d};\n}}\n\n"
        "// The object id (depth-first index of the primitive) whose distance the tree\n"
        "// chose at p: the same walk, keeping track of ids.\n"
        f"int {object_id}(vec3 p)\n{{\n{id_body}    return {id_value};\n}}\n\n")
    return source, distances.used, distances.rows


def _unculled_march_sdf() -> str:
    return ("// Bounding-sphere culling is off: every march sees every object.\n"
            "uint ray_objects(vec3 origin, vec3 direction)\n{\n    return 0u;\n}\n\n"
            "real march_sdf(vec3 p, uint objects)\n{\n    return scene_sdf(p);\n}\n")


def _culled_march_sdf(objects, block: ParameterBlock, bits, replay) -> tuple[str, set[str]]:
    """``ray_objects`` (which of the objects with a bit a ray may reach) and ``march_sdf``
    (the union of the objects a ray keeps), as `reference_cpu.culling` and
    `reference_cpu.scene_sdf.build_scene_sdf` compute them."""
    bit = {index: 1 << k for k, (index, _, _) in enumerate(bits)}
    # Objects with a bit but no sphere are met by every ray; a shadow march may still leave
    # its own object out (own_object).
    always = sum(bit[index] for index, centre, _ in bits if centre is None)
    tests = []
    for index, centre, radius in bits:
        if centre is None:
            continue
        name = f"BOUND{index}"
        block.named({name: ("xyzw", [*centre, radius])})
        tests.append(f"    if (ray_meets_sphere(origin, direction, {name})) {{\n"
                     f"        objects = objects | {bit[index]}u;\n    }}\n")
    writer = SdfWriter(block, with_ids=False, replay=replay)
    body = []
    for index, node in enumerate(objects):
        writer.lines = []
        d, _ = writer.node(node, "p")
        if index not in bit:
            lines = writer.lines + [f"d = op_union(d, {d});"]
            body.append(f"    // object {index} has no bit: always in\n"
                        + "".join(f"    {line}\n" for line in lines))
            continue
        lines = writer.lines + [f"d = op_union(d, {d});"]
        body.append(f"    if ((objects & {bit[index]}u) != 0u) {{\n"
                    + "".join(f"        {line}\n" for line in lines) + "    }\n")
    source = (
        "// Bit k of the result is set where the ray may reach the k-th object with a bit\n"
        "// (reference_cpu/culling.py, object_bits): always for one without a bounding\n"
        "// sphere, else where the ray meets its sphere (BOUNDj: centre, radius widened by 2\n"
        "// epsilon). Objects without a bit are always in.\n"
        "uint ray_objects(vec3 origin, vec3 direction)\n{\n"
        f"    uint objects = {always}u;\n"
        + "".join(tests) + "    return objects;\n}\n\n"
        "// The scene's distance for one march: the union of the objects its ray may reach\n"
        "// (the others count as infinitely far), in the order of scene_sdf.\n"
        "real march_sdf(vec3 p, uint objects)\n{\n    real d = INFINITY;\n"
        + "".join(body) + "    return d;\n}\n")
    return source, writer.used | {"op_union"}
