"""Scenes to and from TOML files (read with `tomllib`, written with `tomlkit`).

The file mirrors the dataclasses of `scene_model.scene` one table per record (``[physics]`` and
``[[bodies]]`` included), with a ``type`` key where a field can hold several classes (objects,
lights, background). One shorthand keeps files short: any object table may carry ``position``,
``rotation`` and ``scale``, which mean ``translate(rotate(scale(node)))``. Saving writes that
shorthand wherever it applies, so ``load_scene(p) == scene`` after ``save_scene(scene, p)``.

Every error names the file and the path of the field inside it (``objects[2].radius``).
Image files that a scene file names (an environment's, a texture's) are read relative to its
folder.
"""

from __future__ import annotations

import dataclasses
import difflib
import os
import re
import tomllib
import typing
from importlib import resources
from pathlib import Path
from typing import Any

import tomlkit

from .errors import SceneError
from .fields import field_types
from .files import write_atomically
from .nesting import deep_path, parse_toml
from .scene import Background, Light, Scene
from .mesh_objects import MeshObject, mesh_kinds, relative_to
from .mesh_world import check_obj_files
from .shapes import TOO_DEEP, Node, Rotate, Scale, Translate, node_kinds

# Shorthand keys on an object table, outermost first, and the transform each one stands for.
SHORTHAND = {"position": (Translate, "offset"), "rotation": (Rotate, "degrees"),
             "scale": (Scale, "factor")}

POLYMORPHIC = {Node: node_kinds, MeshObject: mesh_kinds, Light: lambda: _kinds(Light),
               Background: lambda: _kinds(Background)}


def _kinds(base) -> dict[str, type]:
    return {cls.kind: cls for cls in base.__subclasses__()}


# --- Reading ---------------------------------------------------------------------------------

def bundled_scene_names(meshes: bool | None = None) -> list[str]:
    """Names of the scenes shipped in scene_model/scenes/: all of them, or with ``meshes``
    True only the scenes of triangle meshes, with False only the others (the SDF scenes)."""
    folder = resources.files("scene_model") / "scenes"
    names = sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))
    if meshes is None:
        return names
    return [name for name in names if bool(load_scene(name).meshes) == meshes]


def scene_path(name_or_path: str | os.PathLike) -> Path:
    """The file of a bundled scene's name, or the path itself if it names a file."""
    path = Path(name_or_path)
    try:
        if path.is_file():
            return path
        if path.is_dir():
            raise SceneError("is a folder, not a scene file", (), str(name_or_path))
        bundled = resources.files("scene_model") / "scenes" / f"{name_or_path}.toml"
        found = path.suffix == "" and bundled.is_file()
    except OSError as err:          # a name the system refuses to look up (too long, ...)
        raise SceneError(f"cannot look it up: {err.strerror}", (), str(name_or_path)) from None
    if found:
        return Path(str(bundled))
    names = ", ".join(bundled_scene_names())
    raise SceneError(f"no such file or bundled scene (bundled: {names})", (),
                     str(name_or_path))


def load_scene(name_or_path: str | os.PathLike, overrides: list[str] = ()) -> Scene:
    """Read a scene from a bundled name (``"classroom"``) or a TOML file path.

    ``overrides`` are ``"field.path=value"`` strings applied before validation, as by the CLI's
    ``--set render.max_steps=64``.
    """
    path = scene_path(name_or_path)
    source = str(name_or_path)          # as the user wrote it: a bundled name or a path
    try:
        data = parse_toml(path.read_bytes().decode("utf-8"), tuple(SHORTHAND), source)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"TOML syntax error: {err}", (), source) from None
    except UnicodeDecodeError as err:
        raise SceneError(f"not UTF-8 text, as TOML requires (byte {err.object[err.start]:#04x} "
                         f"at offset {err.start})", (), source) from None
    except OSError as err:
        raise SceneError(f"cannot read: {err.strerror}", (), source) from None
    if not data:        # saved before anything was written: not a wish for the defaults
        raise SceneError("holds no scene (the file is empty, or comments only): write at least "
                         "a [camera] table or one [[objects]]", (), source)
    try:
        for assignment in overrides:
            apply_override(data, assignment)
        scene = with_files_from(scene_from_dict(data), path.parent)
        check_obj_files(scene.meshes)
    except SceneError as err:
        raise err.in_file(source) from None
    return scene


def with_files_from(scene: Scene, folder) -> Scene:
    """``scene`` with the files it names (an environment's images, the materials' textures,
    the meshes' OBJ files) read relative to ``folder``, the folder of the scene file, as a
    scene file means them."""
    background = scene.render.background.relative_to(folder)
    materials = {name: m if m.texture is None else dataclasses.replace(
                     m, texture=m.texture.relative_to(folder))
                 for name, m in scene.materials.items()}
    meshes = tuple(relative_to(node, folder) for node in scene.meshes)
    if (background == scene.render.background and materials == scene.materials
            and meshes == scene.meshes):
        return scene
    return dataclasses.replace(scene, materials=materials, meshes=meshes,
                               render=dataclasses.replace(scene.render, background=background))


def scene_from_dict(data: dict) -> Scene:
    """Build and validate a `Scene` from the dictionary a TOML file parses to."""
    too_deep = deep_path(data, tuple(SHORTHAND))       # before anything below recurses
    if too_deep is not None:
        raise SceneError(TOO_DEEP, too_deep)
    materials = data.get("materials", {"default": None})
    return _record(Scene, data, (), frozenset(materials) if isinstance(materials, dict) else None)


def _record(cls, table: Any, path: tuple, materials) -> Any:
    """Build the record ``cls`` from a TOML table, converting nested tables first."""
    if not isinstance(table, dict):
        raise SceneError(f"must be a table (got {type(table).__name__})", path)
    hints = field_types(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    allowed = names | ({"type"} if _base(cls) else set())
    if issubclass(cls, Node):
        allowed |= set(SHORTHAND)
    for key in table:
        if key not in allowed:
            close = difflib.get_close_matches(key, sorted(allowed), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise SceneError(f"unknown key{hint}", path + (key,))
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name in table:
            kwargs[f.name] = _value(hints[f.name], table[f.name], path + (f.name,), materials)
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise SceneError(f"missing key {f.name!r}", path)
    if "material" in names and materials is not None:          # a primitive, body or mesh
        # An OBJ model's material may be absent (its own MTL colours it).
        name = kwargs.get("material", next(f.default for f in dataclasses.fields(cls)
                                           if f.name == "material"))
        if isinstance(name, str) and name not in materials:
            known = ", ".join(sorted(materials)) or "none"
            problem = (f"unknown material {name!r}" if "material" in table else
                       "no material given, and no material named 'default' is defined")
            raise SceneError(f"{problem} (defined: {known})", path + ("material",))
    try:
        record = cls(**kwargs)
    except SceneError as err:
        raise err.under(*path) from None
    if issubclass(cls, Node):
        record = _expand_shorthand(record, table, path)
    return record


def _value(hint, value, path: tuple, materials):
    """Convert nested tables and arrays of tables; leave scalars to the record's own checks."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint in POLYMORPHIC:
        return _record(_pick(hint, value, path), value, path, materials)
    if _is_record(hint):
        return _record(hint, value, path, materials)
    if origin is tuple and args[-1] is Ellipsis and isinstance(value, list):
        return tuple(_value(args[0], v, path + (i,), materials) for i, v in enumerate(value))
    if origin is dict and isinstance(value, dict):
        return {k: _value(args[1], v, path + (k,), materials) for k, v in value.items()}
    if type(None) in args:
        (inner,) = [a for a in args if a is not type(None)]
        return _value(inner, value, path, materials)
    return value


def _is_record(hint) -> bool:
    return isinstance(hint, type) and dataclasses.is_dataclass(hint)


def _base(cls):
    return next((b for b in POLYMORPHIC if issubclass(cls, b)), None)


def _pick(base, table, path) -> type:
    """The concrete class a table's ``type`` key names."""
    if not isinstance(table, dict):
        raise SceneError(f"must be a table (got {type(table).__name__})", path)
    kinds = POLYMORPHIC[base]()
    if "type" not in table:
        raise SceneError(f"missing key 'type' (one of: {', '.join(sorted(kinds))})", path)
    kind = table["type"]
    if not isinstance(kind, str):
        raise SceneError(f"must be a string (got {type(kind).__name__})", path + ("type",))
    if kind not in kinds:
        close = difflib.get_close_matches(str(kind), sorted(kinds), n=1)
        hint = f"did you mean {close[0]!r}?" if close else f"one of: {', '.join(sorted(kinds))}"
        raise SceneError(f"unknown type {kind!r} ({hint})", path + ("type",))
    return kinds[kind]


def _expand_shorthand(node: Node, table: dict, path: tuple) -> Node:
    """Wrap ``node`` in the transforms its shorthand keys ask for (innermost: scale)."""
    for key in reversed(SHORTHAND):
        if key in table:
            cls, _ = SHORTHAND[key]
            try:
                node = cls(node, table[key])
            except SceneError as err:
                raise SceneError(err.problem, path + (key,) + err.path[1:]) from None
    return node


# --- Overrides (--set) -------------------------------------------------------------------------

_PATH = re.compile(r"[A-Za-z_][\w-]*(?:\.[A-Za-z_][\w-]*|\[\d+\])*")
_STEP = re.compile(r"[A-Za-z_][\w-]*|\[(\d+)\]")


def parse_field_path(text: str) -> tuple:
    """``"objects[2].radius"`` -> ``("objects", 2, "radius")``, or None if it is not a path."""
    if not _PATH.fullmatch(text):
        return None
    return tuple(int(m.group(1)) if m.group(1) else m.group(0) for m in _STEP.finditer(text))


def apply_override(data: dict, assignment: str) -> None:
    """Apply ``"render.max_steps=64"`` or ``"objects[2].radius=0.5"`` to a parsed scene file.

    The value is read as TOML (``[1, 2, 3]``, ``true``, ``"text"``); a bare word that is not
    TOML is taken as a string, so ``render.shading=toon`` works. Missing tables on the way are
    created (``render.fog.density=0.1``); the scene's own checks then judge the result.
    """
    key, sep, text = assignment.partition("=")
    path = parse_field_path(key.strip())
    if not sep or path is None:
        raise SceneError(f"--set {assignment!r}: expected FIELD.PATH=VALUE, "
                         "e.g. render.max_steps=64 or objects[0].radius=0.5")
    try:
        value = parse_toml(f"v = {text.strip()}", tuple(SHORTHAND), at=path)["v"]
    except tomllib.TOMLDecodeError:
        value = text.strip()
    target = data
    for depth, step in enumerate(path):
        here = path[:depth + 1]
        if isinstance(step, int):
            if not isinstance(target, list):
                raise SceneError("is not an array", path[:depth])
            if step >= len(target):
                raise SceneError(f"no such entry (there are {len(target)})", here)
        elif not isinstance(target, dict):
            raise SceneError("is not a table", path[:depth])
        if here == path:
            target[step] = value
        elif isinstance(step, str):
            target = target.setdefault(step, {})
        else:
            target = target[step]


# --- Writing ---------------------------------------------------------------------------------

def scene_to_dict(scene: Scene) -> dict:
    """The dictionary a scene is saved as (the inverse of `scene_from_dict`)."""
    return _table(scene)


def _table(record) -> dict:
    if isinstance(record, Node):
        return _node_table(record)
    if isinstance(record, MeshObject):
        return _mesh_table(record)
    out = {"type": record.kind} if _base(type(record)) else {}
    for f in dataclasses.fields(record):
        value = _plain(getattr(record, f.name))
        if value is not None:
            out[f.name] = value
    return out


def _plain(value):
    if dataclasses.is_dataclass(value):
        return _table(value)
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _node_table(node: Node) -> dict:
    """A node's table, with an outer translate/rotate/scale chain written as shorthand."""
    shorthand = {}
    for key, (cls, field) in SHORTHAND.items():
        if type(node) is cls:
            shorthand[key] = _plain(getattr(node, field))
            node = node.child
    out = {"type": node.kind}
    for f in dataclasses.fields(node):
        value = _plain(getattr(node, f.name))
        if value is not None:
            out[f.name] = value
    out.update(shorthand)
    return out


def _mesh_table(node: MeshObject) -> dict:
    """A mesh node's table as a person writes it: its type and parameters, then where it is
    (only what differs from no move, no turn, scale 1), then its children."""
    out = {"type": node.kind}
    placement = {"position": (0.0,) * 3, "rotation": (0.0,) * 3, "scale": (1.0,) * 3}
    for f in dataclasses.fields(node):
        value = getattr(node, f.name)
        if f.name not in placement and f.name != "children" and value is not None:
            out[f.name] = _plain(value)
    for name, still in placement.items():
        if getattr(node, name) != still:
            out[name] = _plain(getattr(node, name))
    if node.children:
        out["children"] = _plain(node.children)
    return out


def save_scene(scene: Scene, path: str | os.PathLike) -> None:
    """Write ``scene`` as TOML; the file appears whole or not at all."""
    write_atomically(path, scene_to_toml(scene).encode())


def scene_to_toml(scene: Scene) -> str:
    """The TOML text of a scene, top level in reading order: description, camera, ... objects."""
    data = scene_to_dict(scene)
    doc = tomlkit.document()
    doc.add(tomlkit.comment("marchlab scene (docs/scene-format.md describes every field)"))
    lists = ("bodies", "motions", "keyframes", "meshes") + (("objects",) if data.get("meshes")
                                                           else ())
    for key in ("description", "camera", "render", "physics", "materials", "lights", "objects",
                "meshes", "motions", "bodies", "orbit", "keyframes"):
        # A scene without bodies, motions or keyframes is saved without ``bodies = []``, as it
        # was before they existed.
        if key in data and data[key] is not None and not (key in lists and not data[key]):
            doc.add(key, data[key])
    return tomlkit.dumps(doc)

