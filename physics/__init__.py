"""Rigid-sphere physics with a fixed time step: the CPU ground truth the GPU step is checked against.

`World` holds spheres and planes as arrays and steps them (world.py); `simulate` records a run
as a `Trajectory`. One concept per module: integrators, contacts (with broadphase and crowds),
impulses, solvers, continuous.
"""

from physics.errors import PhysicsError
from physics.integrators import INTEGRATORS
from physics.solvers import SOLVERS
from physics.trajectory import Trajectory, simulate
from physics.events import EVENT_DTYPE
from physics.world import World

__all__ = ["EVENT_DTYPE", "INTEGRATORS", "PhysicsError", "SOLVERS", "Trajectory", "World",
           "simulate"]
