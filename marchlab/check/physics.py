"""The physics self-checks, gathered from one module per lesson topic.

`marchlab.check` exports every name listed here, so a lesson calls
``marchlab.check.collision_impulse(collision_impulse)`` whichever module holds the check:

- `marchlab.check.impulses`: restitution, a bounce off a wall, Coulomb friction, the
  effective masses of a contact (lessons 05 and 06);
- `marchlab.check.integration`: bounce heights and impact times measured in the simulator
  and the three integrators' position steps (lesson 06);
- `marchlab.check.invariants`: kinetic energy and momentum (lesson 07).

The student's functions have the signatures of the lessons' exercises; where ``physics`` has
a function of the same name (``friction_impulse``, ``semi_implicit_euler``,
``effective_masses``) the signature is the same, for one contact instead of K. How each check
judges a function is in `marchlab.check.physics_judge`.
"""

from . import impulses, integration, invariants
from .impulses import *      # noqa: F401,F403
from .integration import *   # noqa: F401,F403
from .invariants import *    # noqa: F401,F403

__all__ = [*impulses.__all__, *integration.__all__, *invariants.__all__]
