"""How deep a scene file nests, measured before anything recursive reads it.

A tree of objects can be written with nested inline tables (``child = { child = { ... } }``) or
with headers (``[[objects.children.children]]``). Python's TOML reader recurses once per inline
table or array, so a file nested a few hundred brackets deep would overflow its stack; headers
do not recurse there, but the scene reader and every engine after it would. So:

1. `parse_toml` counts the brackets of the text, outside strings and comments, before it lets
   `tomllib` read it; and
2. `deep_path` walks the parsed tables with a list, not recursion, and finds the first table
   nested deeper than `MAX_DEPTH` (the limit `scene_model.shapes` puts on a built tree).

Both report the path to the deep table. A level is counted as in the built tree: an object
table is one level, plus one for each shorthand key on it (``position``, ``rotation``,
``scale`` stand for transform nodes); the arrays that hold objects (``objects``, ``children``)
add none; any other table or array adds one.
"""

from __future__ import annotations

import re
import sys
import tomllib

from .errors import SceneError
from .shapes import MAX_DEPTH, TOO_DEEP

# An object needs at most two brackets per level (``children = [{ ... }]``), so a text nested
# deeper than this holds a table more than MAX_DEPTH levels deep. tomllib spends about three
# stack frames per bracket: 130 brackets take some 400 of Python's 1000.
MAX_BRACKETS = 2 * MAX_DEPTH + 2

# What the scanner stops at: the start of a string or comment, or a bracket.
_SPECIAL = re.compile(r'"""|\'\'\'|["\'#\[\]{}]')
# Each string form of TOML, matched from its opening quote. A multi-line string may end with
# up to two extra quotes, which belong to its content (TOML 1.0, "String").
_STRINGS = {
    '"""': re.compile(r'"""(?:\\.|[^\\])*?"""(?!")', re.S),
    "'''": re.compile(r"'''.*?'''(?!')", re.S),
    '"': re.compile(r'"(?:\\.|[^"\\\n])*"'),
    "'": re.compile(r"'[^'\n]*'"),
}
_CLOSE = {"[": "]", "{": "}"}
# A table header, ``[a.b]`` or ``[[a."b c"]]``, and the keys in it.
_KEY = r"""(?:[A-Za-z0-9_-]+|"(?:\\.|[^"\\\n])*"|'[^'\n]*')"""
_HEADER = re.compile(rf"\[\[?[ \t]*({_KEY}(?:[ \t]*\.[ \t]*{_KEY})*)[ \t]*\]")
_KEYS = re.compile(_KEY)


def too_deep_spans(text: str, limit: int = MAX_BRACKETS) -> list[tuple[int, int, str]]:
    """``(start, end, opener)`` of each bracketed group that opens deeper than ``limit``.

    Brackets inside strings and comments do not count. A group left open runs to the end of
    the text. Empty when the text nests at most ``limit`` deep. A table header with more than
    MAX_DEPTH keys (each key is at least one level) raises `SceneError` at once: headers make
    no brackets, but a file of deep headers grows with the square of its depth, and reading
    it would take seconds.
    """
    spans, depth, start, opener, at = [], 0, None, "", 0
    while match := _SPECIAL.search(text, at):
        token, at = match.group(), match.end()
        if token == "#":
            newline = text.find("\n", at)
            at = len(text) if newline < 0 else newline
        elif token in _STRINGS:
            string = _STRINGS[token].match(text, match.start())
            if string is None:
                break                      # an unterminated string: tomllib will say where
            at = string.end()
        elif token == "[" and depth == 0 and _starts_line(text, match.start()):
            _check_header(text, match.start())
            depth += 1
        elif token in "[{":
            depth += 1
            if depth == limit + 1:
                start, opener = match.start(), token
        else:
            if depth == limit + 1:
                spans.append((start, at, opener))
                start = None
            depth = max(depth - 1, 0)
    if start is not None:
        spans.append((start, len(text), opener))
    return spans


def _starts_line(text: str, at: int) -> bool:
    line_start = text.rfind("\n", 0, at) + 1
    return text[line_start:at].strip(" \t") == ""


def _check_header(text: str, at: int) -> None:
    header = _HEADER.match(text, at)
    if header is None:
        return                             # not a header tomllib can read: it will say so
    keys = _KEYS.findall(header.group(1))
    if len(keys) > MAX_DEPTH:
        line = text.count("\n", 0, at) + 1
        path = tuple(key.strip("\"'") for key in keys[:MAX_DEPTH + 1])
        raise SceneError(f"{TOO_DEEP} (the table header on line {line})", path)


def parse_toml(text: str, shorthand: tuple, source: str | None = None, at: tuple = ()) -> dict:
    """``tomllib.loads(text)``, once the text is known to nest shallowly enough to be read.

    A text nested too deep raises `SceneError` naming the path to the deep table. To find that
    path, each group nested too deep is replaced by an empty one, which still lies deeper than
    the limit; the shallow text is read and `deep_path` walks it. ``source`` is the file the
    text came from; ``at`` the field an override's text is read into (``v = ...``), which is
    then the path named.
    """
    try:
        spans = too_deep_spans(text)
    except SceneError as err:
        raise SceneError(err.problem, at + err.path, source) from None
    if not spans:
        return _loads(text, source, at)
    if at:
        raise SceneError(TOO_DEEP, at, source)
    shallow, end = [], 0
    for start, stop, opener in spans:
        shallow += [text[end:start], opener, _CLOSE[opener]]
        end = stop
    shallow.append(text[end:])
    try:
        path = deep_path(tomllib.loads("".join(shallow)), shorthand)
    except ValueError:                     # broken elsewhere too: name the line instead
        path = None
    if path is None:
        line = text.count("\n", 0, spans[0][0]) + 1
        raise SceneError(f"{TOO_DEEP} (brackets nested more than {MAX_BRACKETS} deep from "
                         f"line {line})", (), source)
    raise SceneError(TOO_DEEP, path, source)


def _loads(text: str, source, at) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        raise
    except ValueError:
        # The only other ValueError tomllib lets out: int() refuses more than 4300 digits.
        raise SceneError(f"has an integer of more than {sys.get_int_max_str_digits()} digits",
                         at, source) from None


def deep_path(data, shorthand: tuple) -> tuple | None:
    """The path to the first table or array of a parsed scene nested deeper than MAX_DEPTH
    levels, or None if there is none. Levels are counted as in the module's docstring, with
    ``shorthand`` the keys that stand for transform nodes."""
    stack = [(data, (), 0, "scene")]
    while stack:
        value, path, level, role = stack.pop()
        if isinstance(value, dict):
            if role == "object":
                level += 1 + sum(key in value for key in shorthand)
            elif role != "scene":
                level += 1
            if level > MAX_DEPTH:
                return path
            items = list(value.items())
        elif isinstance(value, list):
            level += 0 if role == "objects" else 1
            if level > MAX_DEPTH:
                return path
            items = list(enumerate(value))
        else:
            continue
        for key, item in reversed(items):      # reversed: the first child is walked first
            stack.append((item, path + (key,), level, _role(role, key)))
    return None


def _role(parent: str, key) -> str:
    """What a value is, from what holds it: an object, an array of objects, or other data."""
    if parent == "objects":
        return "object"
    if (parent, key) in (("scene", "objects"), ("object", "children")):
        return "objects"
    if (parent, key) == ("object", "child"):
        return "object"
    return "data"
