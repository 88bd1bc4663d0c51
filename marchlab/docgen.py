"""Generate the field reference of docs/scene-format.md from the scene's dataclasses.

The tables are written between two marker lines; everything else in the file is prose a person
writes. Run ``python -m marchlab.docgen`` after changing a field; a test fails while the file is
out of date, so the reference cannot drift from the code.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import typing
from pathlib import Path

from scene_model.bodies import Body, PhysicsSettings
from scene_model.motion import Motion
from scene_model.keyframes import Keyframes, Orbit
from scene_model.fields import field_types, show
from scene_model.scene import (Background, Camera, Checker, Fog, Light, Material, RenderSettings,
                               Scene, Texture)
from scene_model.shapes import node_kinds
from scene_model.mesh_objects import mesh_kinds

BEGIN = "<!-- BEGIN GENERATED FIELD REFERENCE (python -m marchlab.docgen) -->"
END = "<!-- END GENERATED FIELD REFERENCE -->"
DOC = Path(__file__).resolve().parent.parent / "docs" / "scene-format.md"


def type_name(hint) -> str:
    """A field's type as a scene-file author thinks of it."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is bool:
        return "boolean"
    if hint is float:
        return "number"
    if hint is int:
        return "integer"
    if hint is str:
        return "string"
    if origin is typing.Literal:
        return " \\| ".join(f'`"{a}"`' for a in args)
    if origin is tuple and args and args[-1] is Ellipsis:
        return f"array of {type_name(args[0])}"
    if origin is tuple:
        return f"[{', '.join(type_name(a) for a in args)}]"
    if origin is dict:
        return f"table of {type_name(args[1])}"
    if type(None) in args:
        (inner,) = [a for a in args if a is not type(None)]
        return f"{type_name(inner)} (optional)"
    if isinstance(hint, type):
        return f"{hint.__name__} table"
    return str(hint)


def default_text(f: dataclasses.Field) -> str:
    if f.default is not dataclasses.MISSING:
        if f.default is None:
            return "absent"
        if isinstance(f.default, bool):
            return f"`{'true' if f.default else 'false'}`"
        strings = isinstance(f.default, str) or (isinstance(f.default, tuple) and f.default
                                                 and all(isinstance(v, str) for v in f.default))
        return f"`{json.dumps(f.default) if strings else show(f.default)}`"
    if f.default_factory is not dataclasses.MISSING:
        return "see below"
    return "required"


def allowed_text(f: dataclasses.Field) -> str:
    """The values a field's check allows, as the check itself states them."""
    check = f.metadata.get("check")
    return getattr(check, "allowed", "").replace("|", "\\|")


def table(cls) -> list[str]:
    hints = field_types(cls)
    lines = ["| field | type | default | allowed | meaning |", "| --- | --- | --- | --- | --- |"]
    for f in dataclasses.fields(cls):
        meaning = f.metadata.get("doc", "").replace("|", "\\|")
        lines.append(f"| `{f.name}` | {type_name(hints[f.name])} | {default_text(f)} | "
                     f"{allowed_text(f)} | {meaning} |")
    return lines


def section(title: str, cls) -> list[str]:
    doc = " ".join((cls.__doc__ or "").split())
    return [f"### {title}", "", doc, ""] + table(cls) + [""]


def reference() -> str:
    """The generated part of docs/scene-format.md."""
    out = [BEGIN, "", "## Field reference", ""]
    out += section("Top level", Scene)
    out += section("`[camera]`", Camera)
    out += section("`[render]`", RenderSettings)
    out += section("`[render.fog]`", Fog)
    for cls in Background.__subclasses__():
        out += section(f'`[render.background]` with `type = "{cls.kind}"`', cls)
    out += section("`[materials.NAME]`", Material)
    out += section("`[materials.NAME.checker]`", Checker)
    out += section("`[materials.NAME.texture]`", Texture)
    for cls in Light.__subclasses__():
        out += section(f'`[[lights]]` with `type = "{cls.kind}"`', cls)
    out += ["### `[[objects]]`", "",
            "Every object table has a `type`. Any object may also carry the shorthand keys "
            "`position` (array of 3 numbers), `rotation` (Euler angles in degrees) and `scale` "
            "(a positive number); see *The SDF tree* above.", ""]
    for kind, cls in node_kinds().items():
        out += section(f'`type = "{kind}"`', cls)
    out += ["### `[[meshes]]`", "",
            "Triangle meshes, drawn by the raster backends (numpy-raster, raster, embree). "
            "Every mesh table has a `type`; each places itself in its parent's frame by "
            "`position`, `rotation` and `scale` and holds its own `children` "
            "(docs/rasterisation.md, *The transform hierarchy*).", ""]
    for kind, cls in mesh_kinds().items():
        out += section(f'`type = "{kind}"`', cls)
    out += section("`[physics]`", PhysicsSettings)
    out += section("`[[bodies]]`", Body)
    out += section("`[[motions]]`", Motion)
    out += section("`[[keyframes]]`", Keyframes)
    out += section("`[orbit]`", Orbit)
    out.append(END)
    return "\n".join(out) + "\n"


def updated(text: str) -> str:
    """``text`` with the generated section replaced by the current reference."""
    start, stop = text.index(BEGIN), text.index(END) + len(END) + 1
    return text[:start] + reference() + text[stop:]


def main() -> int:
    text = DOC.read_text()
    new = updated(text)
    if new != text:
        DOC.write_text(new)
        print(f"updated {DOC}")
    else:
        print(f"{DOC} is up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main())
