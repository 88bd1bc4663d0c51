"""Errors a user can cause, each printed by the CLI as one line and exit code 2.

A `SceneError` knows *where* the problem is: the file, and the field path inside it
(``objects[2].radius``), so the message can point at the exact line a user must fix.
"""

from __future__ import annotations

import json
import re


class MarchlabError(Exception):
    """An error caused by the user's input (not a bug): shown as one line, no traceback."""


class SceneError(MarchlabError):
    """A bad value or structure in a scene, located by file and field path.

    Parameters
    ----------
    problem : str
        What is wrong, e.g. ``"must be positive (got -1.0)"``.
    path : tuple of str or int
        Field names and list indices from the scene root, e.g. ``("objects", 2, "radius")``.
    source : str or None
        The file the scene came from, if any.
    """

    def __init__(self, problem: str, path: tuple = (), source: str | None = None):
        self.problem = problem
        self.path = tuple(path)
        self.source = source
        super().__init__(str(self))

    def under(self, *prefix) -> "SceneError":
        """The same error seen from a parent table: ``prefix`` is prepended to the path."""
        return SceneError(self.problem, tuple(prefix) + self.path, self.source)

    def in_file(self, source: str) -> "SceneError":
        return SceneError(self.problem, self.path, source)

    def __str__(self) -> str:
        parts = [p for p in (self.source, format_path(self.path)) if p]
        return ": ".join(parts + [self.problem])


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def format_path(path) -> str:
    """``("objects", 2, "radius")`` -> ``"objects[2].radius"``.

    A key that TOML would have to quote is quoted and escaped (``materials."two\\nlines"``),
    so the path, and the one-line message holding it, stays on one line. A path longer than
    ``LONG_PATH`` steps (only a tree nested too deep has one) keeps its first and last steps
    around an ellipsis: ``objects[0].children[0] ... children[0].child``.
    """
    path = tuple(path)
    if len(path) > LONG_PATH:
        start = len(path) - LONG_PATH // 4
        start -= isinstance(path[start], int)          # begin the tail at a key, not an index
        return f"{format_path(path[:LONG_PATH // 2])} ... {format_path(path[start:])}"
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            key = part if _BARE_KEY.fullmatch(part) else json.dumps(part)
            text += f".{key}" if text else key
    return text


LONG_PATH = 16
