"""The verdict every exercise check returns (graphics and physics alike)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class CheckResult:
    """The verdict of one check; true when the student's function passed.

    Attributes
    ----------
    name : str
        The function checked.
    passed : bool
    message : str
        The paragraph the check printed.
    samples : int
        How many inputs were compared.
    max_error : float
        Largest error |got - expected| / (1 + |expected|) over the samples compared (nan if
        none could be compared).
    """
    name: str
    passed: bool
    message: str
    samples: int = 0
    max_error: float = math.nan

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        return self.message

    def __repr__(self) -> str:
        return f"CheckResult({self.name!r}, passed={self.passed})"
