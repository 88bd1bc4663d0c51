"""The graphics self-checks, gathered from one module per lesson topic.

`marchlab.check` exports every name listed here, so a lesson calls
``marchlab.check.sdf_torus(sdf_torus)`` whichever module holds the check:

- `marchlab.check.sdf`: the primitives' signed distance functions (lesson 01);
- `marchlab.check.marching`: how many steps the march takes to a floor, ``steps_to_floor``
  (lesson 01);
- `marchlab.check.operators`: CSG, smooth blends and transforms (lesson 02);
- `marchlab.check.shading`: ``reflect``, Lambert, Phong, Blinn-Phong, attenuation (lessons 03
  and 05);
- `marchlab.check.shadows`: hard and soft shadow rays (lesson 04);
- `marchlab.check.glass`: Snell's law in vector form, the critical angle, Schlick's Fresnel
  approximation and Beer-Lambert absorption (lesson 08).

How each check judges a student's function, and the tolerance ``TOLERANCE`` it allows, is in
`marchlab.check.judge`.
"""

from . import glass, marching, operators, sdf, shading, shadows
from .glass import *      # noqa: F401,F403
from .judge import TOLERANCE
from .marching import *    # noqa: F401,F403
from .operators import *   # noqa: F401,F403
from .result import CheckResult
from .sdf import *         # noqa: F401,F403
from .shading import *     # noqa: F401,F403
from .shadows import *     # noqa: F401,F403

__all__ = ["CheckResult", "TOLERANCE", *sdf.__all__, *operators.__all__, *shading.__all__,
           *marching.__all__, *shadows.__all__, *glass.__all__]
