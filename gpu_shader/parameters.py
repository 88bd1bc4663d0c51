"""The parameter block: every number a frame may change, as rows of four in one array.

A generated program reads its parameters from an array ``P`` of 4-vectors (a uniform buffer
in GLSL). The program text depends only on the scene's structure; the values in the block
are the scene's numbers. So moving an object, changing a colour or turning the camera writes
new values into the block and never recompiles.

Named rows (the camera, the render settings, each light) get a ``#define`` so the generated
code reads ``EPSILON`` rather than ``P[4].x``; rows of the SDF tree are referred to by index,
with a comment saying what they hold.
"""

from __future__ import annotations

import numpy as np


class ParameterBlock:
    """Rows of 4 values, allocated in order while a program is generated."""

    def __init__(self):
        self.rows: list[tuple[float, float, float, float]] = []
        self.names: list[tuple[str, str]] = []        # (#define name, expression)

    def row(self, values) -> int:
        """Append one row (up to 4 values, padded with zeros) and return its index."""
        values = [float(v) for v in values]
        if len(values) > 4:
            raise ValueError(f"a parameter row holds 4 values, got {len(values)}")
        self.rows.append(tuple(values + [0.0] * (4 - len(values))))
        return len(self.rows) - 1

    def named(self, fields: dict[str, tuple[str, object]]) -> int:
        """One row whose parts get names: ``{"EPSILON": ("x", 1e-3), ...}``.

        Each value is a number (one component) or a 3-vector (``"xyz"``).
        """
        values, names = [], []
        for name, (swizzle, value) in fields.items():
            part = np.ravel(np.asarray(value, dtype=np.float64)).tolist()
            if swizzle != "xyzw"[len(values):len(values) + len(part)]:
                raise ValueError(f"{name}: {len(part)} values cannot sit at .{swizzle}")
            values.extend(part)
            names.append((name, swizzle))
        index = self.row(values)
        self.names.extend((name, f"P[{index}].{swizzle}") for name, swizzle in names)
        return index

    def defines(self) -> str:
        """``#define NAME P[i].x`` lines for the named rows."""
        width = max((len(n) for n, _ in self.names), default=0)
        return "".join(f"#define {n:<{width}} {e}\n" for n, e in self.names)

    def values(self, dtype=np.float32) -> np.ndarray:
        """The block as an (N, 4) array in ``dtype``: what the program's ``P`` holds.

        Values are rounded from float64 once, as the NumPy reference rounds its parameters.
        """
        rows = self.rows or [(0.0, 0.0, 0.0, 0.0)]
        return np.asarray(rows, dtype=np.float64).astype(dtype)
