"""``marchlab view --script FILE``: input actions replayed on a live view, one per frame.

A script is a TOML file with a list of ``[[action]]`` tables, each naming one verb::

    [[action]]
    drag = "left"            # or "right" / "middle": orbit, pan (a left drag on a light's
    from = [320, 240]        # marker moves the light, on a body throws it; with shift = true
    to = [400, 240]          # it moves the selected object); view pixels from the top left
    frames = 8               # spread over this many frames (default 1)

    [[action]]
    scroll = 2               # wheel clicks, positive toward the pivot
    [[action]]
    keys = "WD"              # fly with these keys held (W A S D Q E), for `seconds`
    seconds = 0.5
    [[action]]
    set = "render.epsilon"   # any scene field, as `marchlab render --set`
    value = 0.01
    [[action]]
    click = [320, 240]       # select the object under this pixel
    [[action]]
    overlay = "steps"        # color, steps, depth, normal, object_id
    [[action]]
    add = "sphere"           # any kind of node; `delete = true` deletes the selection
    [[action]]
    physics = "play"         # play, pause, step, reset, kick
    [[action]]
    wait = 10                # frames
    [[action]]
    screenshot = "shot.png"  # the 3D view alone, at full resolution
    [[action]]
    save = "edited.toml"     # the scene, as File > Save as
    [[action]]
    turntable = "spin.gif"   # one turn about the pivot, recorded (.gif or .mp4); the
    frames = 72              # script goes on once it is written

Tests drive the window with scripts, and a teacher records a lesson's moves with one. A
script that cannot be read is refused before the window opens, in one line naming the file,
the action and the problem.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

from scene_model.errors import MarchlabError
from scene_model.shapes import node_kinds

from .camera_control import BUTTONS, FLY_KEYS
from .recording import recording_problem
from .view import OVERLAYS

PHYSICS = ("play", "pause", "step", "reset", "kick")
# Each verb and the other keys its table may hold.
VERBS = {"drag": ("from", "to", "frames", "shift"), "scroll": (), "keys": ("seconds", "shift"),
         "set": ("value",), "click": (), "overlay": (), "add": (), "delete": (),
         "undo": (), "redo": (), "physics": (), "wait": (), "screenshot": (), "save": (),
         "turntable": ("frames",)}
MAX_FRAMES = 10_000


@dataclasses.dataclass(frozen=True)
class Action:
    """One frame's input: ``verb`` and its ``arguments``."""
    verb: str
    arguments: dict


def read_script(path) -> list[Action]:
    """The actions of a script file, each drag spread into one action per frame."""
    name = str(path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as err:
        raise MarchlabError(f"{name}: cannot read the script: {err.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise MarchlabError(f"{name}: not a TOML script: {err}") from None
    unknown = set(data) - {"action"}
    if unknown:
        raise MarchlabError(f"{name}: unknown table {sorted(unknown)[0]!r} (a script holds "
                            "[[action]] tables only)")
    tables = data.get("action", [])
    if not isinstance(tables, list):
        raise MarchlabError(f"{name}: 'action' must be a list of [[action]] tables")
    actions = []
    for number, table in enumerate(tables, 1):
        try:
            actions += _parse(table)
        except MarchlabError as err:
            raise MarchlabError(f"{name}: action {number}: {err}") from None
    return actions


def _parse(table: dict) -> list[Action]:
    verbs = [key for key in table if key in VERBS]
    if len(verbs) != 1:
        named = f" ({', '.join(verbs)})" if verbs else ""
        raise MarchlabError(f"names {len(verbs)} verbs{named}: an action names exactly one of "
                            f"{', '.join(VERBS)}")
    verb = verbs[0]
    extra = set(table) - {verb} - set(VERBS[verb])
    if extra:
        raise MarchlabError(f"{verb}: unknown key {sorted(extra)[0]!r}"
                            + (f" (allowed: {', '.join(VERBS[verb])})" if VERBS[verb] else ""))
    value = table[verb]
    if verb == "drag":
        if value not in BUTTONS:
            raise MarchlabError(f"drag: button {value!r} is not one of {', '.join(BUTTONS)}")
        start, end = (_pixel(table.get(key), f"drag: {key}") for key in ("from", "to"))
        frames = _count(table.get("frames", 1), "drag: frames", low=1)
        points = [tuple(a + (b - a) * k / frames for a, b in zip(start, end))
                  for k in range(frames + 1)]
        shift = table.get("shift", False)
        if not isinstance(shift, bool):
            raise MarchlabError(f"drag: shift: write true or false (got {shift!r})")
        return [Action("drag", {"button": value, "from": p, "to": q, "first": k == 0,
                                "shift": shift,
                                "last": k == frames - 1})
                for k, (p, q) in enumerate(zip(points, points[1:]))]
    if verb == "scroll":
        return [Action(verb, {"clicks": _number(value, "scroll")})]
    if verb == "keys":
        if not isinstance(value, str) or not value or set(value.upper()) - set(FLY_KEYS):
            raise MarchlabError(f"keys: {value!r} is not a string of {''.join(FLY_KEYS)}")
        seconds = _number(table.get("seconds", 0.1), "keys: seconds")
        if not 0 < seconds <= 60:
            raise MarchlabError(f"keys: seconds must be in (0, 60] (got {seconds})")
        return [Action(verb, {"keys": value.upper(), "seconds": seconds,
                              "fast": bool(table.get("shift", False))})]
    if verb == "set":
        if not isinstance(value, str) or "value" not in table:
            raise MarchlabError("set: needs a field path (set = \"render.epsilon\") and a value")
        return [Action(verb, {"path": value, "value": table["value"]})]
    if verb == "click":
        return [Action(verb, {"at": _pixel(value, "click")})]
    if verb == "overlay" and value not in OVERLAYS:
        raise MarchlabError(f"overlay: {value!r} is not one of {', '.join(OVERLAYS)}")
    if verb == "add" and value not in node_kinds():
        raise MarchlabError(f"add: {value!r} is not a kind of node ({', '.join(node_kinds())})")
    if verb == "physics" and value not in PHYSICS:
        raise MarchlabError(f"physics: {value!r} is not one of {', '.join(PHYSICS)}")
    if verb == "wait":
        return [Action("wait", {})] * _count(value, "wait", low=0)
    if verb in ("screenshot", "save"):
        if not isinstance(value, str) or not value.strip():
            raise MarchlabError(f"{verb}: needs a file name")
        if verb == "save" and not value.lower().endswith(".toml"):
            raise MarchlabError(f"save: {value!r}: a scene file must end in .toml")
        if verb == "screenshot" and not value.lower().endswith(".png"):
            raise MarchlabError(f"screenshot: {value!r}: a screenshot is a .png")
    if verb == "turntable":
        if not isinstance(value, str) or not value.strip():
            raise MarchlabError("turntable: needs a file name")
        if (problem := recording_problem(value)) is not None:
            raise MarchlabError(f"turntable: {problem}")
        return [Action(verb, {"path": value,
                              "frames": _count(table.get("frames", 72), "turntable: frames",
                                               low=2)})]
    if verb in ("delete", "undo", "redo") and value is not True:
        raise MarchlabError(f"{verb}: write {verb} = true")
    return [Action(verb, {"value": value})]


def _number(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise MarchlabError(f"{what}: expected a number (got {value!r})")
    return float(value)


def _count(value, what: str, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= MAX_FRAMES:
        raise MarchlabError(f"{what}: expected a whole number from {low} to {MAX_FRAMES} "
                            f"(got {value!r})")
    return value


def _pixel(value, what: str) -> tuple[float, float]:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        raise MarchlabError(f"{what}: expected [x, y] in view pixels (got {value!r})")
    return float(value[0]), float(value[1])


def perform(action: Action, viewer, gl) -> None:
    """Do ``action`` on ``viewer``; ``gl`` answers what needs the GPU: ``object_id_at(x, y)``,
    ``screenshot(path)`` and ``turntable(path, frames)`` (the window's)."""
    a = action.arguments
    if action.verb == "drag":
        (x0, y0), (x1, y1) = a["from"], a["to"]
        if a["first"] and a["button"] == "left":
            viewer.press(x0, y0, shift=a["shift"])
        if a["button"] == "left" and viewer.holding is not None:
            viewer.move_to(x1, y1)
            if a["last"]:
                viewer.let_go()
        else:
            viewer.drag(a["button"], x1 - x0, y1 - y0)
    elif action.verb == "scroll":
        viewer.scroll(a["clicks"])
    elif action.verb == "keys":
        viewer.fly(set(a["keys"]), a["seconds"], a["fast"])
    elif action.verb == "set":
        if not viewer.set_field(a["path"], a["value"]):
            raise MarchlabError(f"script: set {a['path']}: {viewer.status}")
    elif action.verb == "click":
        viewer.pick(gl.object_id_at(*a["at"]))
    elif action.verb == "overlay":
        viewer.overlay = a["value"]
    elif action.verb == "add":
        viewer.add_object(a["value"])
    elif action.verb == "delete":
        viewer.delete_selected()
    elif action.verb in ("undo", "redo"):
        getattr(viewer, action.verb)()
    elif action.verb == "physics":
        _physics(viewer, a["value"])
    elif action.verb == "screenshot":
        gl.screenshot(a["value"])
    elif action.verb == "save":
        viewer.save(a["value"])
    elif action.verb == "turntable":
        gl.turntable(a["path"], a["frames"])


def _physics(viewer, command: str) -> None:
    playback = viewer.playback
    if playback is None:
        raise MarchlabError(f"script: physics {command}: the scene has no bodies")
    if command == "kick":
        playback.kick(1.0)
    else:
        getattr(playback, command)()
