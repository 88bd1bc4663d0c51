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
import numbers
import re
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
    ``"must be positive"``. The checks below (`Range`, `Rule`, `Each`) also carry
    ``allowed``, what they accept in a few characters, which the field reference prints.
    """
    return dataclasses.field(default=default, default_factory=factory, kw_only=kw_only,
                             metadata={"doc": doc, "check": check})


# ---------------------------------------------------------------------------------------------
# Limits. A scene is measured in metres; these bounds keep every number a renderer derives from
# it finite. A float32 backend squares coordinates and sizes (1e12 at most, far below float32's
# 3.4e38), and at 1e6 m its spacing is already 6 cm, so nothing larger can be drawn faithfully.
# docs/scene-format.md ("Limits") gives the reasons to users.

MAX_COORDINATE = 1e6          # m: |x| of every position, look_at, offset, capsule end
MIN_SIZE, MAX_SIZE = 1e-6, 1e6   # m: radii, half sizes, heights, blend widths, periods, scales
MAX_SPEED = 1e6               # m/s and rad/s: body velocities
MAX_DEGREES = 360.0           # rotation angles, each way


# ---------------------------------------------------------------------------------------------
# Checks: each returns None or a problem; `Record` adds the offending value to the message.
# A check also says what it allows (``check.allowed``), for the field reference in the docs, so
# the rule, its error message and its documentation are written once, here.

def number_text(x) -> str:
    """A bound as a person writes it: 1e-06 -> ``1e-6``, 1000000.0 -> ``1e6``, 0.1 -> ``0.1``."""
    if isinstance(x, int):
        return str(x)
    return re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", f"{x:g}")


class Rule:
    """A check made of a test and the problem it reports: ``Rule(test, problem, allowed)``."""

    def __init__(self, test: Callable[[Any], bool], problem: str, allowed: str):
        self.test, self.problem, self.allowed = test, problem, allowed

    def __call__(self, value) -> str | None:
        return None if self.test(value) else self.problem


class Range:
    """A number from ``lo`` to ``hi``, either end excluded with ``lo_open`` / ``hi_open``.

    The message names the bound a value broke ("must be >= 1e-6", "must be <= 1e6"), except
    that a quantity declared ``positive`` tells a value of 0 or less that it "must be
    positive": there the sign, not the size, is the mistake.
    """

    def __init__(self, lo, hi, *, lo_open: bool = False, hi_open: bool = False,
                 positive: bool = False, allowed: str | None = None):
        self.lo, self.hi, self.lo_open, self.hi_open = lo, hi, lo_open, hi_open
        self.positive = positive or (lo == 0 and lo_open)
        self.allowed = allowed or (f"{'(' if lo_open else '['}{number_text(lo)}, "
                                   f"{number_text(hi)}{')' if hi_open else ']'}")

    def __call__(self, v) -> str | None:
        if self.positive and v <= 0:
            return "must be positive"
        if v < self.lo or (self.lo_open and v == self.lo):
            return f"must be {'>' if self.lo_open else '>='} {number_text(self.lo)}"
        if v > self.hi or (self.hi_open and v == self.hi):
            return f"must be {'<' if self.hi_open else '<='} {number_text(self.hi)}"
        return None


class Each:
    """Applies a number check to every component of a vector; the error names the component
    (``camera.position[1]``)."""

    def __init__(self, check):
        self.check = check
        self.allowed = f"each in {check.allowed}"

    def __call__(self, vector) -> None:
        for index, component in enumerate(vector):
            problem = self.check(component)
            if problem:
                raise SceneError(f"{problem} (got {show(component)})", (index,))
        return None


class AllOf:
    """The first problem any of ``checks`` finds, in order."""

    def __init__(self, *checks, allowed: str | None = None):
        self.checks = checks
        self.allowed = allowed or ", ".join(c.allowed for c in checks)

    def __call__(self, value) -> str | None:
        for check in self.checks:
            problem = check(value)
            if problem:
                return problem
        return None


def length(v) -> float:
    return math.hypot(*v)


# The checks many fields share. Those in upper case are named so because a field of the same
# name (``position``) declared earlier in a class body would hide a lower-case one there.
unit_interval = Rule(lambda v: 0.0 <= v <= 1.0, "must be between 0 and 1", "[0, 1]")
color_range = Rule(lambda v: all(0.0 <= c <= 1.0 for c in v),
                   "components must be between 0 and 1", "each in [0, 1]")
SIZE = Range(MIN_SIZE, MAX_SIZE, positive=True)          # a length of a solid
SIZES = Each(SIZE)
COORDINATE = Range(-MAX_COORDINATE, MAX_COORDINATE)
POINT = Each(COORDINATE)                                 # a position
nonzero = Rule(lambda v: any(c != 0.0 for c in v), "must not be the zero vector", "not 0")
DIRECTION = AllOf(nonzero, Rule(lambda v: MIN_SIZE <= length(v) <= MAX_SIZE,
                                f"length must be between {number_text(MIN_SIZE)} and "
                                f"{number_text(MAX_SIZE)}", ""),
                  allowed=f"length in {SIZE.allowed}")


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
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, tuple):
        return "[" + ", ".join(show(v) for v in value) + "]"
    if isinstance(value, int) and value.bit_length() > 100:
        return f"an integer of {digit_count(value)} digits"     # str() refuses 4300 digits
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return repr(value)
    if isinstance(value, (int, float, list, dict)):
        return str(value)
    return repr(value)                          # numpy and other types say what they are


def digit_count(n: int) -> int:
    """The number of decimal digits of ``n``, without writing it out."""
    n = abs(n)
    digits = int((n.bit_length() - 1) * math.log10(2)) + 1
    return digits + 1 if n >= 10 ** digits else digits


def _number(value, kind: type):
    # numbers.Real takes NumPy's scalars too (np.float32(0.5)); bool is an int in Python but
    # never a number in a scene file.
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SceneError(f"must be a number (got {show(value)})")
    if kind is int:
        if not isinstance(value, numbers.Integral):
            raise SceneError(f"must be an integer (got {show(value)})")
        return int(value)
    try:
        value = float(value)
    except OverflowError:                       # an int beyond float's 1.8e308
        raise SceneError(f"is too large (got {show(value)})") from None
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
