"""Rigid-body physics with a fixed time step: the CPU truth the GPU step is checked against.

`World` holds spheres, boxes, capsules and convex solids, planes and static SDF shapes as
arrays and steps them (world.py); `simulate` records a run as a `Trajectory`. One concept per
module: integrators, contacts (with broadphase, crowds and colliders), impulses, solvers,
continuous; solids, solid_contacts, solid_sweeps and point_solver for the bodies that are not
spheres; convex and convex_contacts for those of any convex SDF (`convex_solid`).
"""

from physics.colliders import Shape
from physics.convex import ConvexSolid, convex_solid
from physics.errors import PhysicsError
from physics.integrators import INTEGRATORS
from physics.solvers import SOLVERS
from physics.state import load_state, save_state
from physics.trajectory import Trajectory, simulate
from physics.events import EVENT_DTYPE
from physics.world import World

__all__ = ["ConvexSolid", "EVENT_DTYPE", "INTEGRATORS", "PhysicsError", "SOLVERS", "Shape",
           "Trajectory", "World", "convex_solid", "load_state", "save_state", "simulate"]
