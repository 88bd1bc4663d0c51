"""Rigid-sphere physics with a fixed time step: the CPU truth the GPU step is checked against.

`World` holds spheres, planes and static SDF shapes as arrays and steps them (world.py);
`simulate` records a run as a `Trajectory`. One concept per module: integrators, contacts
(with broadphase, crowds and colliders), impulses, solvers, continuous.
"""

from physics.colliders import Shape
from physics.errors import PhysicsError
from physics.integrators import INTEGRATORS
from physics.solvers import SOLVERS
from physics.state import load_state, save_state
from physics.trajectory import Trajectory, simulate
from physics.events import EVENT_DTYPE
from physics.world import World

__all__ = ["EVENT_DTYPE", "INTEGRATORS", "PhysicsError", "SOLVERS", "Shape", "Trajectory",
           "World", "load_state", "save_state", "simulate"]
