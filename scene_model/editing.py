"""What a scene editor does, as pure functions on a `Scene`, and an undo history of scenes.

A scene is immutable, so every edit returns a new one and a window's buttons stay thin: each
action here is tested without a window. Two kinds of address are used:

* a **node path** is a tuple of child indices into the SDF tree: ``(i,)`` is
  ``scene.objects[i]``, ``(i, j)`` its j-th child (`scene_model.shapes.children`), and so on;
* a **field path** is what ``marchlab render --set`` takes, ``"objects[2].radius"``
  (``"objects.2.radius"`` and a tuple ``("objects", 2, "radius")`` are accepted too). It
  reads the scene as its file shows it: an object's outer translate, rotate and scale are
  its ``position``, ``rotation`` and ``scale`` keys (`scene_model.scenefile.SHORTHAND`).

Choices an editor has to make, made once here:

* Every CSG operator holds a tuple of children (none is binary); a transform (translate,
  rotate, scale, repeat) holds exactly one. So a shape inside transforms is duplicated,
  deleted or moved together with them, its **branch**, as a scene file writes a shape and
  its ``position`` as one object.
* Deleting the last child of a node deletes that node too, up to the top level: an operator
  needs a child. Deleting the first child of a subtraction makes the next one the shape cut.
* A duplicate is moved `DUPLICATE_OFFSET` (0.5 m along +x), so it can be seen beside the
  original: its translate is shifted, or it gets one (the file shows ``position``).
* A node added to a scene that lacks a material it uses named "default" brings
  ``Material()`` under that name, so "Add sphere" works in every scene.
"""

from __future__ import annotations

import dataclasses
import difflib
import numbers
import re
from typing import Any

from .bodies import Body
from .mesh_objects import ProceduralMesh, mesh_kinds
from .errors import SceneError, format_path
from .fields import Record, field_types
from .scene import Light, Material, Scene
from .scenefile import SHORTHAND, parse_field_path
from .shapes import (Box, Node, Primitive, Repeat, Rotate, Scale, Sphere, Translate, children,
                     node_kinds, primitives)

DUPLICATE_OFFSET = (0.5, 0.0, 0.0)      # m: where a duplicate goes, relative to its original
HISTORY_LIMIT = 200                     # undo steps kept

NodePath = tuple[int, ...]


# --- Node paths ----------------------------------------------------------------------------

def node_at(scene: Scene, path: NodePath) -> Node:
    """The node at ``path``; a path that leads nowhere raises `SceneError` saying where."""
    path = _node_path(path)
    node, kids, here = None, scene.objects, ()
    for index in path:
        if node is None:
            at, problem = ("objects", index), f"no such object (there are {len(kids)})"
        elif not kids:
            raise SceneError(f"a {node.kind} is a primitive and has no children", here)
        elif hasattr(node, "child"):
            at, problem = here + ("child",), f"no child {index} (a {node.kind} has one, index 0)"
        else:
            at, problem = here + ("children", index), f"no such child (there are {len(kids)})"
        if not 0 <= index < len(kids):
            raise SceneError(problem, at)
        node, kids, here = kids[index], children(kids[index]), at
    return node


def _node_path(path) -> NodePath:
    if isinstance(path, (str, bytes)) or not hasattr(path, "__iter__"):
        raise SceneError(f"a node path is a tuple of indices such as (2, 0) (got {path!r})")
    path = tuple(path)
    if not path or not all(isinstance(i, numbers.Integral) and not isinstance(i, bool)
                           for i in path):
        raise SceneError(f"a node path is a non-empty tuple of indices such as (2, 0) "
                         f"(got {path!r})")
    return tuple(int(i) for i in path)


def _location(scene: Scene, path: NodePath) -> tuple:
    """The node's field path in the dataclasses: ``(2, 0)`` -> ``("objects", 2, "child")``."""
    where, node = ("objects", path[0]), scene.objects[path[0]]
    for index in path[1:]:
        where += ("child",) if hasattr(node, "child") else ("children", index)
        node = children(node)[index]
    return where


def _kids(scene: Scene, parent: tuple) -> tuple[Node, ...]:
    """The children of the node at ``parent``; the top level (``()``) holds the objects."""
    return scene.objects if not parent else children(node_at(scene, parent))


def _set_kids(scene: Scene, parent: tuple, kids: tuple[Node, ...]) -> Scene:
    """``scene`` with the children of the node at ``parent`` (or its objects) replaced."""
    if not parent:
        return dataclasses.replace(scene, objects=kids)
    node = node_at(scene, parent)
    change = {"children": kids} if hasattr(node, "children") else {"child": kids[0]}
    try:
        node = dataclasses.replace(node, **change)
    except SceneError as err:                   # e.g. nested deeper than MAX_DEPTH
        raise err.under(*_location(scene, parent)) from None
    return replace_node(scene, parent, node)


def replace_node(scene: Scene, path: NodePath, node: Node) -> Scene:
    """``scene`` with the node at ``path`` replaced by ``node``."""
    path = _node_path(path)
    node_at(scene, path)
    if not isinstance(node, Node):
        raise SceneError(f"must be a node (got {type(node).__name__})", _location(scene, path))
    kids = list(_kids(scene, path[:-1]))
    kids[path[-1]] = node
    return _set_kids(scene, path[:-1], tuple(kids))


def _check_holds_children(scene: Scene, parent: tuple) -> None:
    if not parent:
        return
    node = node_at(scene, parent)
    if hasattr(node, "children"):
        return
    if hasattr(node, "child"):
        problem = (f"a {node.kind} holds exactly one child; add the shape to a union or "
                   f"another operator instead")
    else:
        problem = f"a {node.kind} is a primitive and holds no children"
    raise SceneError(problem, _location(scene, parent))


def _branch(scene: Scene, path: NodePath) -> NodePath:
    """``path`` raised through the transforms above it: the node with its translate etc."""
    while len(path) > 1 and hasattr(node_at(scene, path[:-1]), "child"):
        path = path[:-1]
    return path


def _removable(scene: Scene, path: NodePath, stop: tuple | None = None) -> NodePath:
    """What goes when the node at ``path`` goes: ``path`` raised while its parent (never
    ``stop``) has no other child, since no operator or transform may be left empty."""
    while len(path) > 1 and path[:-1] != stop and len(_kids(scene, path[:-1])) == 1:
        path = path[:-1]
    return path


# --- Adding, duplicating, deleting, moving nodes ----------------------------------------------

def add_object(scene: Scene, node: Node, parent: NodePath | None = None
               ) -> tuple[Scene, NodePath]:
    """``node`` appended at the top level, or as the last child of the operator at ``parent``.

    Returns the new scene and the new node's path. A transform or primitive ``parent``
    cannot take another child: `SceneError` says so.
    """
    parent = () if parent is None else _node_path(parent)
    if not isinstance(node, Node):
        raise SceneError(f"must be a node (got {type(node).__name__})")
    _check_holds_children(scene, parent)
    if ("default" not in scene.materials
            and any(p.material == "default" for p in primitives((node,)))):
        scene = dataclasses.replace(scene, materials={**scene.materials, "default": Material()})
    kids = _kids(scene, parent) + (node,)
    return _set_kids(scene, parent, kids), parent + (len(kids) - 1,)


def duplicate(scene: Scene, path: NodePath) -> tuple[Scene, NodePath]:
    """A copy of the node's branch right after it, moved by `DUPLICATE_OFFSET`.

    Returns the new scene and the path of the copy of the node at ``path`` (one level deeper
    than the original's where the copy was given a translate of its own).
    """
    path = _node_path(path)
    node_at(scene, path)
    branch = _branch(scene, path)
    original = node_at(scene, branch)
    try:
        if type(original) is Translate:
            offset = tuple(a + b for a, b in zip(original.offset, DUPLICATE_OFFSET))
            copy, inside = dataclasses.replace(original, offset=offset), ()
        else:
            copy, inside = Translate(original, DUPLICATE_OFFSET), (0,)
    except SceneError as err:
        raise err.under(*_location(scene, branch)) from None
    kids = list(_kids(scene, branch[:-1]))
    kids.insert(branch[-1] + 1, copy)
    new_branch = branch[:-1] + (branch[-1] + 1,)
    return _set_kids(scene, branch[:-1], tuple(kids)), new_branch + inside + path[len(branch):]


def delete(scene: Scene, path: NodePath) -> Scene:
    """``scene`` without the node at ``path``, the transforms above it, and every ancestor
    that it leaves without children."""
    path = _node_path(path)
    node_at(scene, path)
    return _remove(scene, _removable(scene, path))


def _remove(scene: Scene, path: NodePath) -> Scene:
    kids = list(_kids(scene, path[:-1]))
    del kids[path[-1]]
    return _set_kids(scene, path[:-1], tuple(kids))


def reparent(scene: Scene, path: NodePath, new_parent: NodePath | None
             ) -> tuple[Scene, NodePath]:
    """The node's branch moved to the end of ``new_parent``'s children (None: the top level).

    The node keeps its own transforms, not those of its old ancestors, so it may move in the
    picture. Ancestors left empty are deleted, as by `delete`. Returns the new scene and the
    node's new path.
    """
    path = _node_path(path)
    node_at(scene, path)
    target = () if new_parent is None else _node_path(new_parent)
    _check_holds_children(scene, target)
    branch = _branch(scene, path)
    if target[:len(branch)] == branch:
        raise SceneError("cannot move a node into itself or its own descendant",
                         _location(scene, path))
    moved = node_at(scene, branch)
    gone = _removable(scene, branch, stop=target)
    if gone[:-1] == target:                     # already under target: move it to the end
        kids = list(_kids(scene, target))
        del kids[gone[-1]]
    else:
        scene = _remove(scene, gone)
        # Deleting ``gone`` shifts its later siblings, and their subtrees, one place left.
        k = len(gone) - 1
        if len(target) > k and target[:k] == gone[:k] and target[k] > gone[k]:
            target = target[:k] + (target[k] - 1,) + target[k + 1:]
        kids = list(_kids(scene, target))
    kids.append(moved)
    return (_set_kids(scene, target, tuple(kids)),
            target + (len(kids) - 1,) + path[len(branch):])


# A small, visible example of each node kind, for an "Add" menu. A cube and a sphere over one
# of its corners show every operator's effect: joined, the corner rounded, a bite taken out.
def default_node(kind: str) -> Node:
    """A new node of ``kind`` (any key of `node_kinds`): a primitive of the class's default
    size with material "default"; an operator of a unit cube and a sphere over its corner;
    a transform of a unit cube."""
    kinds = node_kinds()
    if kind not in kinds:
        raise SceneError(f"unknown node type {kind!r} (one of: {', '.join(sorted(kinds))})")
    cls = kinds[kind]
    if issubclass(cls, Primitive):
        return cls()
    if "children" in {f.name for f in dataclasses.fields(cls)}:
        return cls(children=(Box(), Translate(Sphere(0.6), (0.4, 0.4, 0.4))))
    settings = {Translate: {"offset": (0.0, 0.5, 0.0)}, Rotate: {"degrees": (0.0, 45.0, 0.0)},
                Scale: {"factor": 0.5},
                Repeat: {"period": (1.5, 0.0, 1.5), "count": (1, 0, 1)}}.get(cls, {})
    return cls(child=Box(), **settings)


# --- Fields by path (as marchlab render --set) ----------------------------------------------

def field_steps(path) -> tuple:
    """``"objects[2].radius"`` or ``"objects.2.radius"`` -> ``("objects", 2, "radius")``."""
    if isinstance(path, tuple) and path:
        return path
    text = re.sub(r"\.(\d+)(?=[.\[]|$)", r"[\1]", str(path).strip())
    steps = parse_field_path(text)
    if not steps:
        raise SceneError(f"{path!r} is not a field path (e.g. render.epsilon or "
                         f"lights[0].position)")
    return steps


def get_field(scene: Scene, path) -> Any:
    """The value at a field path, as the model holds it (tuples, records); None where the
    path runs through something absent (an object without ``position``, no ``[physics]``)."""
    value, steps = scene, field_steps(path)
    for depth, step in enumerate(steps):
        if value is None:
            return None
        at = steps[:depth]
        if isinstance(value, Node):
            chain, value = _shorthand(value)
            if step in SHORTHAND:
                value = chain.get(step)
                continue
        if isinstance(value, tuple):
            value = value[_index(value, step, at)]
        elif isinstance(value, dict):
            if str(step) not in value:
                raise SceneError(f"no such entry (defined: {', '.join(value)})",
                                 at + (str(step),))
            value = value[str(step)]
        elif isinstance(value, Record):
            value = getattr(value, _field_name(value, step, at, reading=True))
        else:
            raise SceneError("is not a table", at)
    return value


def set_field(scene: Scene, path, value) -> Scene:
    """``scene`` with the field at ``path`` set to ``value``, validated by the records.

    A bad value raises `SceneError` naming the field, as the same value in a scene file
    would. As with ``--set``, a missing table on the way is created (``physics.dt`` in a
    scene without ``[physics]``, ``materials.new.color``), an object's ``position``,
    ``rotation`` or ``scale`` gives it that transform, and None removes it. The walk
    rebuilds only the records on the path, so it costs a fraction of a millisecond.
    """
    steps = field_steps(path)
    return _set(scene, Scene, steps, value, (), scene)


def _set(here, hint, steps: tuple, value, at: tuple, scene: Scene):
    """``here`` (the value at field path ``at``, declared as ``hint``) with ``steps`` below
    it set to ``value``."""
    step, rest = steps[0], steps[1:]
    if here is None:
        here = _new_record(hint, at)
    if isinstance(here, Node):
        chain, core = _shorthand(here)
        if step in SHORTHAND:
            chain[step] = _set(chain.get(step), None, rest, value, at + (step,),
                               scene) if rest else value
        else:
            core = _set_in_record(core, step, rest, value, at, scene)
        return _wrap(core, chain, at)
    if isinstance(here, Record):
        return _set_in_record(here, step, rest, value, at, scene)
    if isinstance(here, tuple):
        index = _index(here, step, at)
        item_hint = _item_hint(hint, index)
        item = _set(here[index], item_hint, rest, value, at + (index,), scene) if rest else value
        return here[:index] + (item,) + here[index + 1:]
    if isinstance(here, dict):
        key, item_hint = str(step), _item_hint(hint, 1)
        item = _set(here.get(key), item_hint, rest, value, at + (key,), scene) if rest else value
        return {**here, key: item}
    raise SceneError("is not a table", at)


def _set_in_record(record: Record, step, rest: tuple, value, at: tuple, scene: Scene):
    name = _field_name(record, step, at, reading=False)
    hint = field_types(type(record))[name]
    new = _set(getattr(record, name), hint, rest, value, at + (name,), scene) if rest else value
    if (name == "material" and isinstance(record, (Primitive, Body)) and isinstance(new, str)
            and new not in scene.materials):
        known = ", ".join(sorted(scene.materials)) or "none"
        raise SceneError(f"unknown material {new!r} (defined: {known})", at + (name,))
    try:
        return dataclasses.replace(record, **{name: new})
    except SceneError as err:
        raise err.under(*at) from None


def _field_name(record: Record, step, at: tuple, reading: bool) -> str:
    """``step`` if it names a field of ``record``, else a `SceneError` like the file reader's."""
    names = [f.name for f in dataclasses.fields(record)]
    if step in names:
        return step
    kind = getattr(record, "kind", "")
    if step == "type" and kind:
        if reading:
            return "kind"
        raise SceneError("cannot be set: replace the whole entry with one of the new type",
                         at + (step,))
    if not isinstance(step, str):
        raise SceneError("is a table, not an array", at)
    allowed = names + (list(SHORTHAND) if isinstance(record, Node) else [])
    close = difflib.get_close_matches(step, sorted(allowed), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise SceneError(f"unknown key{hint}", at + (step,))


def _index(items: tuple, step, at: tuple) -> int:
    if not isinstance(step, int):
        raise SceneError(f"is an array: give an index such as {format_path(at + (0,))}", at)
    if not 0 <= step < len(items):
        raise SceneError(f"no such entry (there are {len(items)})", at + (step,))
    return step


def _item_hint(hint, index: int):
    """The declared type of item ``index`` of a tuple or dict hint (None when unknown)."""
    args = getattr(hint, "__args__", ())
    if len(args) == 2 and args[1] is Ellipsis:
        return args[0]
    return args[index] if index < len(args) else None


def _new_record(hint, at: tuple) -> Record:
    """A record of its defaults, for a table missing on a field path (as ``--set`` makes)."""
    for kind in getattr(hint, "__args__", (hint,)):
        if isinstance(kind, type) and dataclasses.is_dataclass(kind):
            return kind()
    raise SceneError("is not set: set the whole value first", at)


def _shorthand(node: Node) -> tuple[dict, Node]:
    """``({"position": offset, ...}, core)``: the transforms a scene file writes as keys of
    the object's table (in the order `scene_model.scenefile` reads them), and what they hold."""
    chain = {}
    for key, (cls, field) in SHORTHAND.items():
        if type(node) is cls:
            chain[key] = getattr(node, field)
            node = node.child
    return chain, node


def _wrap(core: Node, chain: dict, at: tuple) -> Node:
    """``core`` wrapped in the transforms of ``chain`` (a None value: no such transform)."""
    node = core
    for key in reversed(SHORTHAND):
        if chain.get(key) is not None:
            cls, field = SHORTHAND[key]
            try:
                node = cls(child=node, **{field: chain[key]})
            except SceneError as err:
                raise SceneError(err.problem, at + (key,) + err.path[1:]) from None
    return node


def node_field_path(scene: Scene, path: NodePath, field: str) -> str:
    """The field path of a field of the node at ``path``, for `set_field` and `get_field`:
    ``(2, 0), "radius"`` -> ``"objects[2].radius"``, ``(2,), "offset"`` ->
    ``"objects[2].position"`` when objects[2] is a sphere inside a translate."""
    path = _node_path(path)
    node = node_at(scene, path)
    steps, node = ["objects", path[0]], scene.objects[path[0]]
    above = len(_shorthand(node)[0])            # transforms written as keys of this table
    for index in path[1:]:
        if above:
            above -= 1
        else:
            steps += ["child"] if hasattr(node, "child") else ["children", index]
            above = len(_shorthand(children(node)[index])[0])
        node = children(node)[index]
    if field not in {f.name for f in dataclasses.fields(node)}:
        raise SceneError(f"a {node.kind} has no field {field!r}", _location(scene, path))
    if above:                                   # a transform the file writes as a key
        key = next(k for k, (cls, _) in SHORTHAND.items() if type(node) is cls)
        if field != SHORTHAND[key][1]:
            raise SceneError(f"the {field} of a {node.kind} is a node: select it to edit it",
                             _location(scene, path))
        return format_path(steps + [key])
    return format_path(steps + [field])


# --- Mesh nodes (scenes of triangle meshes) --------------------------------------------------

def addable_mesh_kinds() -> list[str]:
    """The mesh node types an editor can add with their defaults: the procedural ones (an
    OBJ model needs a file, a group children)."""
    return [kind for kind, cls in mesh_kinds().items() if issubclass(cls, ProceduralMesh)]


def add_mesh(scene: Scene, kind: str) -> tuple[Scene, int]:
    """A top-level mesh node of procedural ``kind`` with its defaults, at the origin, in the
    material "default" (or the scene's first, where it has none so named), appended;
    returns the new scene and the node's index."""
    kinds = addable_mesh_kinds()
    if kind not in kinds:
        raise SceneError(f"unknown mesh type {kind!r} to add (one of: {', '.join(kinds)})")
    material = "default" if "default" in scene.materials or not scene.materials \
        else next(iter(scene.materials))
    node = mesh_kinds()[kind](material=material)
    return dataclasses.replace(scene, meshes=scene.meshes + (node,)), len(scene.meshes)


def duplicate_mesh(scene: Scene, index: int) -> tuple[Scene, int]:
    """A copy of top-level mesh node ``index`` (its children too) right after it, moved by
    `DUPLICATE_OFFSET`; returns the new scene and the copy's index."""
    node = scene.meshes[_index(scene.meshes, index, ("meshes",))]
    copy = dataclasses.replace(node, position=tuple(
        a + b for a, b in zip(node.position, DUPLICATE_OFFSET)))
    meshes = scene.meshes[:index + 1] + (copy,) + scene.meshes[index + 1:]
    return dataclasses.replace(scene, meshes=meshes), index + 1


def delete_mesh(scene: Scene, index: int) -> Scene:
    """``scene`` without top-level mesh node ``index``. The last one stays: without meshes
    the scene would no longer be one of triangle meshes."""
    _index(scene.meshes, index, ("meshes",))
    if len(scene.meshes) == 1:
        raise SceneError("a scene of triangle meshes keeps at least one mesh", ("meshes",))
    return dataclasses.replace(scene, meshes=scene.meshes[:index] + scene.meshes[index + 1:])


# --- Lights and materials --------------------------------------------------------------------

def _light_kinds() -> dict[str, type]:
    return {cls.kind: cls for cls in Light.__subclasses__()}


def add_light(scene: Scene, kind: str = "point") -> tuple[Scene, int]:
    """A light of ``kind`` ("point", "directional" or "spot") with its defaults, appended;
    returns the new scene and the light's index."""
    kinds = _light_kinds()
    if kind not in kinds:
        raise SceneError(f"unknown light type {kind!r} (one of: {', '.join(sorted(kinds))})")
    return dataclasses.replace(scene, lights=scene.lights + (kinds[kind](),)), len(scene.lights)


def delete_light(scene: Scene, index: int) -> Scene:
    """``scene`` without light ``index``; a scene may have no lights (ambient light only)."""
    _index(scene.lights, index, ("lights",))
    return dataclasses.replace(scene, lights=scene.lights[:index] + scene.lights[index + 1:])


def add_material(scene: Scene, name: str | None = None, material: Material | None = None
                 ) -> tuple[Scene, str]:
    """``material`` (default: ``Material()``) added as ``name`` (default: the first free
    "material_1", "material_2", ...); returns the new scene and the name."""
    if name is None:
        number = 1
        while f"material_{number}" in scene.materials:
            number += 1
        name = f"material_{number}"
    elif not isinstance(name, str) or not name:
        raise SceneError(f"a material's name must be a non-empty string (got {name!r})",
                         ("materials",))
    elif name in scene.materials:
        raise SceneError("a material of this name already exists", ("materials", name))
    materials = {**scene.materials, name: Material() if material is None else material}
    return dataclasses.replace(scene, materials=materials), name


def delete_material(scene: Scene, name: str) -> Scene:
    """``scene`` without material ``name``, which nothing may still use."""
    if name not in scene.materials:
        known = ", ".join(sorted(scene.materials)) or "none"
        raise SceneError(f"no such material (defined: {known})", ("materials", name))
    users = [format_path(_location(scene, path)) for path, prim in _primitive_paths(scene)
             if prim.material == name]
    users += [f"bodies[{i}]" for i, body in enumerate(scene.bodies) if body.material == name]
    if users:
        more = f" and {len(users) - 3} more" if len(users) > 3 else ""
        raise SceneError(f"is still used by {', '.join(users[:3])}{more}; give them another "
                         f"material first", ("materials", name))
    return dataclasses.replace(scene, materials={k: v for k, v in scene.materials.items()
                                                 if k != name})


# --- Object ids (what a click picks) -----------------------------------------------------------

def _primitive_paths(scene: Scene, nodes=None, prefix: tuple = ()):
    """``(path, primitive)`` for every primitive, in object-id (depth-first) order."""
    for index, node in enumerate(scene.objects if nodes is None else nodes):
        if isinstance(node, Primitive):
            yield prefix + (index,), node
        else:
            yield from _primitive_paths(scene, children(node), prefix + (index,))


def _count(nodes) -> int:
    return sum(1 for _ in primitives(nodes))


def primitive_ids(scene: Scene, path: NodePath) -> tuple[int, ...]:
    """The object ids of the primitives under the node at ``path`` (all of its outline).

    A primitive's id is its depth-first index over the scene's objects, as every renderer
    numbers them (`scene_model.scene.scene_objects`).
    """
    path = _node_path(path)
    node = node_at(scene, path)
    first = _count(scene.objects[:path[0]])
    parent = scene.objects[path[0]]
    for index in path[1:]:
        first += _count(children(parent)[:index])
        parent = children(parent)[index]
    return tuple(range(first, first + _count((node,))))


def primitive_path(scene: Scene, object_id: int):
    """The node path of the primitive with ``object_id``; ``("body", k)`` for the sphere of
    body k (ids after the objects' primitives); None for any other id (-1 is a miss)."""
    remaining, nodes, path = int(object_id), scene.objects, ()
    if remaining < 0:
        return None
    while True:
        for index, node in enumerate(nodes):
            count = _count((node,))
            if remaining < count:
                path += (index,)
                if isinstance(node, Primitive):
                    return path
                nodes = children(node)
                break
            remaining -= count
        else:                                   # past every object's primitives
            return ("body", remaining) if remaining < len(scene.bodies) else None


def object_path(scene: Scene, object_id: int):
    """What a click on a pixel of ``object_id`` selects: the path ``(i,)`` of the top-level
    object holding that primitive, ``("body", k)`` for body k, or None (a miss, -1)."""
    path = primitive_path(scene, object_id)
    return path if path is None or path[0] == "body" else path[:1]


# --- Undo and redo ---------------------------------------------------------------------------

class History:
    """Undo and redo over scenes: scenes are immutable, so each step keeps a whole one (they
    share every record an edit did not touch).

    ``push(scene, label, coalesce=key)`` records an edit. Consecutive pushes with the same
    ``coalesce`` key (one slider drag) make one step, until `seal`, `undo` or `redo`. A push
    after an undo drops the steps that could have been redone. At most ``limit`` steps are
    kept; the oldest go first.
    """

    def __init__(self, scene: Scene, limit: int = HISTORY_LIMIT):
        self._steps = [(scene, "", None)]       # (scene, label, coalesce key); [0] the start
        self._at = 0
        self._open = False                      # may the next push merge into step _at?
        self.limit = limit

    @property
    def scene(self) -> Scene:
        return self._steps[self._at][0]

    def push(self, scene: Scene, label: str, coalesce=None) -> None:
        """Record ``scene`` as the result of the edit ``label``; a no-op edit is not a step."""
        if scene == self.scene:
            return
        del self._steps[self._at + 1:]
        key = self._steps[self._at][2]
        if coalesce is not None and self._open and self._at > 0 and key == coalesce:
            self._steps[self._at] = (scene, label, coalesce)
        else:
            self._steps.append((scene, label, coalesce))
            self._at += 1
            if len(self._steps) > self.limit + 1:
                del self._steps[0]
                self._at -= 1
        self._open = True

    def seal(self) -> None:
        """End the current step: the next push starts a new one even with the same key
        (call it when a drag ends)."""
        self._open = False

    def undo(self) -> Scene:
        """Step back and return the scene there (the current one if there is nothing to undo)."""
        if self.can_undo:
            self._at -= 1
        self._open = False
        return self.scene

    def redo(self) -> Scene:
        """Step forward again and return the scene there (the current one if none)."""
        if self.can_redo:
            self._at += 1
        self._open = False
        return self.scene

    @property
    def can_undo(self) -> bool:
        return self._at > 0

    @property
    def can_redo(self) -> bool:
        return self._at < len(self._steps) - 1

    @property
    def undo_labels(self) -> tuple[str, ...]:
        """Labels of the steps `undo` would take back, the next one first."""
        return tuple(label for _, label, _ in reversed(self._steps[1:self._at + 1]))

    @property
    def redo_labels(self) -> tuple[str, ...]:
        """Labels of the steps `redo` would make again, the next one first."""
        return tuple(label for _, label, _ in self._steps[self._at + 1:])
