"""The error a user gets for a bad physics argument: one line that names the argument.

`PhysicsError` is a `ValueError`, so ``except ValueError`` catches it too; the command line
prints it as a one-line message (``radius must be positive (got -1.0)``) with no traceback.
"""

from __future__ import annotations

import numpy as np


class PhysicsError(ValueError):
    """A bad value given to the physics module (not a bug in it)."""


def vector3(value, name: str) -> np.ndarray:
    """``value`` as a finite float64 (3,) array, or a PhysicsError naming ``name``."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise PhysicsError(f"{name} must be three numbers (got {value!r})") from None
    if array.shape != (3,):
        raise PhysicsError(f"{name} must be three numbers (got {value!r})")
    if not np.all(np.isfinite(array)):
        raise PhysicsError(f"{name} must be finite (got {value!r})")
    return array


def positive(value, name: str) -> float:
    """``value`` as a finite float > 0, or a PhysicsError naming ``name``."""
    number = finite(value, name)
    if number <= 0:
        raise PhysicsError(f"{name} must be positive (got {value!r})")
    return number


def in_range(value, name: str, low: float, high: float = np.inf, unit: str = "") -> float:
    """``value`` as a finite float in [low, high], or a PhysicsError naming ``name`` (and the
    ``unit`` of the bounds, if given)."""
    number = finite(value, name)
    if not low <= number <= high:
        where = f"at least {low}" if high == np.inf else f"between {low:g} and {high:g}"
        raise PhysicsError(f"{name} must be {where}{' ' + unit if unit else ''} "
                           f"(got {value!r})")
    return number


def finite(value, name: str) -> float:
    """``value`` as a finite float, or a PhysicsError naming ``name``."""
    if isinstance(value, (bool, np.bool_)):
        raise PhysicsError(f"{name} must be a number (got {value!r})")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise PhysicsError(f"{name} must be a number (got {value!r})") from None
    if not np.isfinite(number):
        raise PhysicsError(f"{name} must be finite (got {value!r})")
    return number


def whole_number(value, name: str, low: int, high: int | None = None) -> int:
    """``value`` as an int in [low, high] (bools and floats refused), or a PhysicsError naming
    it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
            or value < low:
        raise PhysicsError(f"{name} must be a whole number of at least {low} (got {value!r})")
    if high is not None and value > high:
        raise PhysicsError(f"{name} must be at most {high:,} (got {value!r})")
    return int(value)


def choice(value, name: str, options) -> str:
    """``value`` if it is one of ``options``, or a PhysicsError listing them."""
    if value not in options:
        raise PhysicsError(f"{name} must be one of {', '.join(map(repr, options))} "
                           f"(got {value!r})")
    return value


def float_dtype(dtype):
    """numpy.float64 or numpy.float32 for a name or type, or a PhysicsError."""
    for name, value in (("float64", np.float64), ("float32", np.float32)):
        if dtype in (name, value) or (isinstance(dtype, np.dtype) and dtype == value):
            return value
    raise PhysicsError(f"dtype must be float64 or float32 (got {dtype!r})")


def bounds_box(bounds):
    """(low, high) corners as float64 (3,) arrays with low < high, or None."""
    if bounds is None:
        return None
    try:
        low, high = bounds
    except (TypeError, ValueError):
        raise PhysicsError(f"bounds must be two corners (low, high) or None (got {bounds!r})") \
            from None
    low, high = vector3(low, "bounds low corner"), vector3(high, "bounds high corner")
    if np.any(low >= high):
        raise PhysicsError(f"bounds: every coordinate of low must be below high (got {bounds!r})")
    return low, high


def rows(values, name, m=None):
    """``values`` as a finite float64 (M, 3) array (a single (3,) row repeated M times)."""
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise PhysicsError(f"{name} must be three numbers per sphere (got {values!r})") from None
    if array.ndim == 1 and m is not None:
        array = np.broadcast_to(array, (m,) + array.shape)
    if array.ndim != 2 or array.shape[1] != 3 or (m is not None and len(array) != m):
        raise PhysicsError(f"{name} must be three numbers per sphere (got shape {array.shape})")
    if not np.all(np.isfinite(array)):
        raise PhysicsError(f"{name} must be finite")
    return array.copy()


def column(values, name, m, check):
    """``values`` as a float64 (m,) array, one number repeated or one per row, each checked."""
    if isinstance(values, (bool, np.bool_)):
        raise PhysicsError(f"{name} must be a number (got {values!r})")
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise PhysicsError(f"{name} must be a number or one number per sphere (got {values!r})") \
            from None
    if array.ndim == 0:
        return np.full(m, check(float(array), name))
    if array.shape != (m,):
        raise PhysicsError(f"{name} must be one number or one per sphere (got shape {array.shape})")
    return np.array([check(value, name) for value in array.tolist()])
