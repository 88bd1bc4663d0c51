"""Contact events: what hit what, when, how fast; one row of a structured array each.

The GPU step records the same fields, so two runs can be lined up step by step.
"""

from __future__ import annotations

import numpy as np

EVENT_DTYPE = np.dtype([("step", np.int64), ("time", np.float64), ("kind", "U15"),
                        ("body", np.int64), ("other", np.int64), ("speed", np.float64),
                        ("impulse", np.float64)])
"""A contact event: at ``step`` (time s), ``body`` hit ``other`` (a body for "sphere-sphere", a
plane for "sphere-plane", a shape for "sphere-shape", -1 for "left-bounds") approaching at
``speed`` (m/s), receiving the normal ``impulse`` (N s)."""


def make_events(step, time, kind, body, other, speed, impulse) -> np.ndarray:
    """Events of one kind at one step, for bodies (K,) and what they hit (K,)."""
    events = np.zeros(len(body), EVENT_DTYPE)
    events["step"], events["time"], events["kind"] = step, time, kind
    events["body"], events["other"] = body, other
    events["speed"], events["impulse"] = speed, impulse
    return events
