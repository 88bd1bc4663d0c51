"""Typed, validated fields for the scene's dataclasses.

Every scene class is a frozen dataclass deriving from `Record`. Its fields are declared with
`param(default, doc, check)`; on construction `Record` converts each value to its declared type
(``1`` -> ``1.0``, ``[0, 1, 0]`` -> ``(0.0, 1.0, 0.0)``) and runs its check. So a scene built in
Python and one read from a TOML file are validated by the same code, and a bad value is reported
with the name of the field that holds it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import typing
from typing import Any, Callable, Literal

from .errors import SceneError

Vec3 = tuple[float, float, float]
Color = tuple[float, float, float]
Int3 = tuple[int, int, int]

Check = Callable[[Any], str | None]


def param(default=dataclasses.MISSING, doc: str = "", check: Check | None = None, *,
          factory=dataclasses.MISSING, kw_only=dataclasses.MISSING):
    """A dataclass field carrying its documentation and a value check.

    ``check(value)`` returns None when the value is acceptable, else a short problem such as
    ``"must be positive"``.
    """
    return dataclasses.field(default=default, default_factory=factory, kw_only=kw_only,
                             metadata={"doc": doc, "check": check})


# ---------------------------------------------------------------------------------------------
# Checks: each returns None or a problem; `Record` adds the offending value to the message.

def positive(v) -> str | None:
    return None if v > 0 else "must be positive"


def nonnegative(v) -> str | None:
    return None if v >= 0 else "must be >= 0"


def unit_interval(v) -> str | None:
    return None if 0.0 <= v <= 1.0 else "must be between 0 and 1"


def color_range(v) -> str | None:
    return None if all(0.0 <= c <= 1.0 for c in v) else "components must be between 0 and 1"


def nonzero(v) -> str | None:
    return None if any(c != 0.0 for c in v) else "must not be the zero vector"


def all_positive(v) -> str | None:
    return None if all(c > 0 for c in v) else "components must be positive"


def nonnegative_vector(v) -> str | None:
    return None if all(c >= 0 for c in v) else "components must be >= 0"


def at_least(lo) -> Check:
    return lambda v: None if v >= lo else f"must be >= {lo}"


def between(lo, hi) -> Check:
    return lambda v: None if lo <= v <= hi else f"must be between {lo} and {hi}"


def between_open(lo, hi) -> Check:
    return lambda v: None if lo < v < hi else f"must be strictly between {lo} and {hi}"


# ---------------------------------------------------------------------------------------------

class Record:
    """Base of the scene's frozen dataclasses: converts and checks fields after ``__init__``.

    Subclasses may define ``check(self)`` for rules that involve several fields; it raises
    `SceneError` with the path of the field to blame.
    """

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            try:
                value = convert(field_types(type(self))[f.name], value)
                rule = f.metadata.get("check")
                problem = rule(value) if rule is not None and value is not None else None
            except SceneError as err:
                raise err.under(f.name) from None
            if problem:
                raise SceneError(f"{problem} (got {show(value)})", (f.name,))
            object.__setattr__(self, f.name, value)
        self.check()

    def check(self) -> None:
        """Cross-field rules; none by default."""


@functools.cache
def field_types(cls) -> dict[str, Any]:
    """The resolved type hint of each field of a dataclass."""
    return typing.get_type_hints(cls)


def show(value) -> str:
    """A value as a user would write it in a scene file (strings quoted and escaped)."""
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, tuple):
        return "[" + ", ".join(show(v) for v in value) + "]"
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return repr(value)
    return str(value)


def _number(value, kind: type):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"must be a number (got {show(value)})")
    if kind is int:
        if isinstance(value, float):
            raise SceneError(f"must be an integer (got {show(value)})")
        return int(value)
    value = float(value)
    if not math.isfinite(value):
        raise SceneError(f"must be a finite number (got {value})")
    return value


def convert(hint, value):
    """Convert ``value`` to the type ``hint`` names, or raise `SceneError` saying why not."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        (inner,) = [a for a in args if a is not type(None)]
        return convert(inner, value)
    if hint in (float, int):
        return _number(value, hint)
    if hint is bool:
        if not isinstance(value, bool):
            raise SceneError(f"must be true or false (got {show(value)})")
        return value
    if hint is str:
        if not isinstance(value, str):
            raise SceneError(f"must be a string (got {show(value)})")
        return value
    if origin is Literal:
        if value not in args:
            choices = ", ".join(repr(a) for a in args)
            raise SceneError(f"must be one of {choices} (got {show(value)})")
        return value
    if origin is tuple:
        if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
            raise SceneError(f"must be a list (got {show(value)})")
        items = tuple(value)
        if len(args) == 2 and args[1] is Ellipsis:
            kinds = [args[0]] * len(items)
        else:
            if len(items) != len(args):
                raise SceneError(f"must have {len(args)} components (got {len(items)})")
            kinds = list(args)
        out = []
        for i, (kind, item) in enumerate(zip(kinds, items)):
            try:
                out.append(convert(kind, item))
            except SceneError as err:
                raise err.under(i) from None
        return tuple(out)
    if origin is dict:
        if not isinstance(value, dict):
            raise SceneError(f"must be a table (got {show(value)})")
        out = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise SceneError(f"keys must be strings (got {show(key)})")
            try:
                out[key] = convert(args[1], item)
            except SceneError as err:
                raise err.under(key) from None
        return out
    if isinstance(hint, type):
        if not isinstance(value, hint):
            raise SceneError(f"must be a {hint.__name__} (got {type(value).__name__})")
        return value
    raise TypeError(f"unsupported field type {hint!r}")  # a bug in a scene class, not user input
