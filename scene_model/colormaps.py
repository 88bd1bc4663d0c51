"""The colour ramp used to draw step counts (shading mode ``steps`` and the steps AOV)."""

from __future__ import annotations

import numpy as np

# A dark-to-bright ramp in the spirit of matplotlib's "inferno": dark violet for few steps,
# orange, then pale yellow for rays that used (nearly) all of max_steps.
HEAT_STOPS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
HEAT_COLORS = np.array([
    [0.00, 0.00, 0.02],
    [0.34, 0.06, 0.43],
    [0.73, 0.21, 0.33],
    [0.98, 0.55, 0.04],
    [0.99, 1.00, 0.64],
])


def heat(x: np.ndarray) -> np.ndarray:
    """Colours (..., 3) for values ``x`` (...) in [0, 1], by linear interpolation of the stops."""
    x = np.clip(x, 0, 1)
    return np.stack([np.interp(x, HEAT_STOPS, HEAT_COLORS[:, c]) for c in range(3)], axis=-1)
