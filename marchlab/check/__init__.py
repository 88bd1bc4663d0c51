"""Self-checks for the lessons' exercises.

A student writes, say, ``sdf_torus`` in a notebook and calls ``marchlab.check.sdf_torus(fn)``:
the check compares it with marchlab's own function on random inputs and prints what is wrong
(or that it passed). Graphics exercises live in `graphics` (which gathers one module per
lesson topic: `sdf`, `operators`, `marching`, `shading`, `shadows`, `glass`; they are judged by
`judge`), the rasterisation lesson's in `raster` (edge functions, perspective-correct
interpolation, barycentric coordinates), physics ones in `physics` (gathering `impulses`,
`integration`, `invariants`; judged by `physics_judge`).
"""

from .graphics import *   # noqa: F401,F403
from .physics import *    # noqa: F401,F403
from .raster import *     # noqa: F401,F403
from .result import CheckResult   # noqa: F401
