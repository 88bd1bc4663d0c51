"""The World: the state of every sphere and plane as plain arrays, and the step that advances it.

Everything the simulation knows is an attribute a student can print: ``world.position`` is an
(N, 3) array of centres, ``world.velocity`` their velocities, and so on. A step is the four
stages of integrators.py written out in `World.step`, followed by the continuous collision
tests (continuous.py for spheres, solid_sweeps.py for the other bodies), the push-out of
overlaps, and the removal of bodies that leave the bounds.
"""

from __future__ import annotations

import copy
from collections import Counter

import numpy as np

from physics.broadphase import NeighbourList
from physics.contacts import find_contacts, spread_coincident
from physics.colliders import Shape
from physics.convex import ConvexSolid
from physics.continuous import bounce_off_statics, stop_sphere_sweeps
from physics.errors import (PhysicsError, bounds_box, choice, column, finite, float_dtype, in_range,
                            positive, rows, vector3, whole_number)
from physics.events import EVENT_DTYPE, make_events
from physics.colliders import MAX_SHAPE_CONTACTS
from physics.impulses import SolverBodies
from physics.integrators import INTEGRATORS, integrate_velocities, parabola_start_velocity
from physics.point_solver import PointBodies, solve_points
from physics.quaternions import rotate_orientations, rotation_vector_between
from physics.solid_contacts import (PointContacts, contact_reach, find_solid_contacts,
                                    join_point_contacts, sphere_point_contacts, with_levers)
from physics.solid_sweeps import Sweep, lever, stop_solid_sweeps, sweep_solids
from physics.solids import (BOX, CAPSULE, CONVEX, KIND_NAMES, SPHERE, free_rotation,
                            principal_inertia, volume, world_inertia, world_inverse_inertia)
from physics.solvers import SOLVERS, contact_keys, separate_overlaps, warm_start
from scene_model.bodies import MAX_DT, MIN_DT
from scene_model.geometry import dot

SPAWN_OFFSET = 1e-3     # a sphere spawned on another's centre is moved this many radii away
# dt runs from MIN_DT to MAX_DT, the range the scene format declares (scene_model.bodies): a
# step shorter than a microsecond needs a million steps per simulated second; one longer than
# a tenth of a second skips through thin contacts (a ball falling from 1 m arrives at 4.4 m/s,
# 0.44 m a step). Outside the range the run would be endless or meaningless.
MAX_STEPS = 10 ** 9     # most steps one call may ask for: 1e9 steps are days of computing


class World:
    """Rigid spheres, boxes, capsules and convex solids among static planes and shapes under
    uniform gravity, stepped with a fixed dt.

    Parameters
    ----------
    gravity : (3,) array_like
        Acceleration of gravity (m/s^2).
    dt : float
        Time step (s), from MIN_DT to MAX_DT. Fixed: a step never depends on a frame rate.
    integrator : {"semi_implicit", "explicit", "verlet"}
        See integrators.py.
    solver : {"sequential", "simultaneous"}
        See solvers.py.
    dtype : {numpy.float64, numpy.float32, "float64", "float32"}
        Precision of every state array and of the arithmetic of a step.
    seed : int
        Seeds the random offset given to a sphere spawned on another's centre.
    bounds : ((3,), (3,)) array_like or None
        Corners (m) of the box outside which a body is removed (with a "left-bounds" event).
    iterations : int
        Most collision sweeps and resting-contact passes per step.
    restitution_threshold : float
        Contacts approaching slower than this (m/s) do not bounce, so resting contact rests.
    slop : float
        Surfaces closer than this (m) are in contact; overlaps up to it are left alone.
    push_out : float
        Fraction of a deeper overlap removed per step by moving the bodies (0 to 1).
    """

    def __init__(self, gravity=(0.0, -9.81, 0.0), dt=1 / 240, integrator="semi_implicit",
                 solver="sequential", dtype=np.float64, seed=0,
                 bounds=((-1e3, -1e3, -1e3), (1e3, 1e3, 1e3)), iterations=10,
                 restitution_threshold=0.01, slop=1e-4, push_out=0.2):
        self.dtype = float_dtype(dtype)
        self.gravity = vector3(gravity, "gravity").astype(self.dtype)
        self.dt = in_range(dt, "dt", MIN_DT, MAX_DT, "s")
        self.integrator = choice(integrator, "integrator", list(INTEGRATORS))
        self.solver = choice(solver, "solver", list(SOLVERS))
        self.seed = whole_number(seed, "seed", 0)
        self.bounds = bounds_box(bounds)
        self.iterations = whole_number(iterations, "iterations", 1)
        self.restitution_threshold = in_range(restitution_threshold, "restitution_threshold", 0)
        self.slop = in_range(slop, "slop", 0)
        self.push_out = in_range(push_out, "push_out", 0, 1)
        self.rng = np.random.default_rng(self.seed)
        self.steps = 0
        empty = lambda *shape: np.zeros((0,) + shape, self.dtype)  # noqa: E731
        self.position, self.velocity, self.angular_velocity = empty(3), empty(3), empty(3)
        self.orientation = empty(4)
        self.radius, self.mass, self.restitution, self.friction = empty(), empty(), empty(), empty()
        self.kind = np.zeros(0, np.int8)  # SPHERE, BOX, CAPSULE or CONVEX (solids.py)
        self.extent = empty(3)            # a box's half sizes, (0, l, 0) for a capsule
        self.gyration = empty(3)          # a convex body's principal I / m (m^2), else 0
        self.solid_of = np.zeros(0, np.int64)   # a convex body's row of `solids`, else -1
        self.solids: list[ConvexSolid] = []     # the convex bodies' shapes (convex.py)
        self.active = np.zeros(0, bool)
        self.plane_normal, self.plane_offset = empty(3), empty()
        self.plane_restitution, self.plane_friction = empty(), empty()
        self.shapes: list[Shape] = []     # static solids given by their SDF (colliders.py)
        self._events = []
        self._resting_impulses = None     # (keys, normal, tangent) of last step's contacts
        self._neighbours = NeighbourList()  # the broad phase's pairs, kept between steps
        self.work = Counter()             # what the last step did: see `World.step`

    # --- building -----------------------------------------------------------------------

    def add_sphere(self, position, velocity=(0.0, 0.0, 0.0), radius=0.1, mass=None,
                   density=None, restitution=0.5, friction=0.5,
                   angular_velocity=(0.0, 0.0, 0.0)) -> int:
        """Add one solid sphere and return its index.

        Parameters
        ----------
        position, velocity, angular_velocity : (3,) array_like
            Centre (m), velocity (m/s) and angular velocity (rad/s).
        radius : float
            Radius (m), > 0.
        mass, density : float, optional
            Mass (kg) or density (kg/m^3, mass = 4/3 pi r^3 density); give at most one.
            Neither: 1 kg.
        restitution : float
            Coefficient of restitution e in [0, 1]; a pair bounces with max(e_a, e_b).
        friction : float
            Coefficient of friction mu >= 0; a pair slides with sqrt(mu_a mu_b).
        """
        return int(self.add_spheres([vector3(position, "position")],
                                    [vector3(velocity, "velocity")], radius, mass, density,
                                    restitution, friction,
                                    [vector3(angular_velocity, "angular_velocity")])[0])

    def add_spheres(self, positions, velocities=None, radius=0.1, mass=None, density=None,
                    restitution=0.5, friction=0.5, angular_velocities=None) -> np.ndarray:
        """Add M spheres at once (positions (M, 3); the other values scalars or (M,) / (M, 3)).

        Returns their indices, (M,) int. A sphere whose centre is exactly that of another is
        moved by SPAWN_OFFSET radii in a random direction drawn from the world's seeded
        generator, so the pair separates the same way every run with the same seed (two equal
        centres have no direction between them to push along).
        """
        positions = rows(positions, "position")
        m = len(positions)
        velocities = np.zeros((m, 3)) if velocities is None else rows(velocities, "velocity", m)
        spins = (np.zeros((m, 3)) if angular_velocities is None
                 else rows(angular_velocities, "angular_velocity", m))
        radius = column(radius, "radius", m, positive)
        if mass is not None and density is not None:
            raise PhysicsError("give mass or density, not both")
        with np.errstate(over="ignore", under="ignore"):      # checked just below
            if density is not None:
                mass = 4 / 3 * np.pi * radius ** 3 * column(density, "density", m, positive)
            else:
                mass = column(1.0 if mass is None else mass, "mass", m, positive)
            inertia = 0.4 * mass * radius * radius
        # The solver divides by m and by I = 2/5 m r^2 in the world's precision: both, and
        # their inverses, must be finite there (a 1e200 m sphere is not, even in float64).
        with np.errstate(over="ignore", divide="ignore", under="ignore"):
            finite = np.isfinite(np.concatenate([mass, inertia, 1 / mass, 1 / inertia])
                                 .astype(self.dtype))
        if not finite.all():
            raise PhysicsError(f"mass {float(np.max(mass)):.3g} kg with radius "
                               f"{float(np.max(radius)):.3g} m is out of range for "
                               f"{np.dtype(self.dtype).name}: the mass, the moment of inertia "
                               "and their inverses must be finite")
        restitution = column(restitution, "restitution", m, lambda v, n: in_range(v, n, 0, 1))
        friction = column(friction, "friction", m, lambda v, n: in_range(v, n, 0))

        positions = spread_coincident(self.position, positions.astype(self.dtype),
                                      SPAWN_OFFSET * radius, self.rng)
        first = self.count
        grow = lambda old, new: np.concatenate([old, np.asarray(new, self.dtype)])  # noqa: E731
        self.position = grow(self.position, positions)
        self.velocity = grow(self.velocity, velocities)
        self.angular_velocity = grow(self.angular_velocity, spins)
        self.orientation = grow(self.orientation, np.tile([1.0, 0.0, 0.0, 0.0], (m, 1)))
        self.radius = grow(self.radius, radius)
        self.mass = grow(self.mass, mass)
        self.restitution = grow(self.restitution, restitution)
        self.friction = grow(self.friction, friction)
        self.active = np.concatenate([self.active, np.ones(m, bool)])
        self.kind = np.concatenate([self.kind, np.full(m, SPHERE, np.int8)])
        self.extent = grow(self.extent, np.zeros((m, 3)))
        self.gyration = grow(self.gyration, np.zeros((m, 3)))
        self.solid_of = np.concatenate([self.solid_of, np.full(m, -1, np.int64)])
        return np.arange(first, first + m)

    def add_box(self, position, half_size, orientation=(1.0, 0.0, 0.0, 0.0),
                velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), mass=None,
                density=None, restitution=0.5, friction=0.5) -> int:
        """Add one solid box and return its index among the bodies.

        Parameters
        ----------
        position : (3,) array_like
            Centre (m).
        half_size : (3,) array_like
            Half its extent along its own x, y, z (m), each > 0.
        orientation : (4,) array_like
            Unit quaternion (w, x, y, z) turning its own axes into the world's (normalised).
        mass, density : float, optional
            Mass (kg) or density (kg/m^3, mass = 8 a b c density); at most one. Neither: 1 kg.
        velocity, angular_velocity, restitution, friction
            As for `add_sphere`.
        """
        half = vector3(half_size, "half_size")
        for axis, value in zip("xyz", half):
            positive(value, f"half_size {axis}")
        return self._add_solid(BOX, position, float(np.sqrt(half @ half)), half, orientation,
                               velocity, angular_velocity, mass, density, restitution,
                               friction)

    def add_capsule(self, position, half_length, radius, orientation=(1.0, 0.0, 0.0, 0.0),
                    velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), mass=None,
                    density=None, restitution=0.5, friction=0.5) -> int:
        """Add one solid capsule, the points within ``radius`` of the segment from
        (0, -half_length, 0) to (0, half_length, 0) of its own frame, and return its index.

        Same parameters as `add_box` (mass from density: density times the volume of a
        cylinder and a sphere).
        """
        extent = np.array([0.0, positive(half_length, "half_length"), 0.0])
        return self._add_solid(CAPSULE, position, positive(radius, "radius"), extent,
                               orientation, velocity, angular_velocity, mass, density,
                               restitution, friction)

    def add_convex(self, position, solid: ConvexSolid, orientation=(1.0, 0.0, 0.0, 0.0),
                   velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), mass=None,
                   density=None, restitution=0.5, friction=0.5) -> int:
        """Add one body of any convex shape and return its index among the bodies.

        Parameters
        ----------
        position : (3,) array_like
            Its centre of mass (m).
        solid : physics.convex.ConvexSolid
            Its shape in its own frame (`physics.convex.convex_solid`): origin at the centre
            of mass, axes along the principal axes of inertia.
        orientation : (4,) array_like
            Unit quaternion turning its own (principal) axes into the world's.
        mass, density : float, optional
            Mass (kg) or density (kg/m^3, mass = density times ``solid.volume``); at most one.
        velocity, angular_velocity, restitution, friction
            As for `add_sphere`.
        """
        if not isinstance(solid, ConvexSolid):
            raise PhysicsError(f"a convex body's shape must be a physics.convex.ConvexSolid "
                               f"(got {type(solid).__name__})")
        self.solids.append(solid)
        try:
            index = self._add_solid(CONVEX, position, solid.radius, solid.extent, orientation,
                                    velocity, angular_velocity, mass, density, restitution,
                                    friction, solid)
        except PhysicsError:
            self.solids.pop()
            raise
        return index

    def _add_solid(self, kind, position, radius, extent, orientation, velocity,
                   angular_velocity, mass, density, restitution, friction, solid=None) -> int:
        position = vector3(position, "position")
        q = np.asarray(orientation, np.float64)
        if q.shape != (4,) or not np.all(np.isfinite(q)) or not q @ q > 0:
            raise PhysicsError(f"orientation must be a quaternion of four finite numbers, "
                               f"not all zero (got {orientation!r})")
        if mass is not None and density is not None:
            raise PhysicsError("give mass or density, not both")
        kinds, radii, extents = np.array([kind]), np.array([radius]), extent[None, :]
        gyration = np.zeros(3) if solid is None else np.asarray(solid.gyration, np.float64)
        with np.errstate(over="ignore", under="ignore"):
            if density is not None:
                size = (volume(kinds, radii, extents)[0] if solid is None else solid.volume)
                mass = float(size) * positive(density, "density")
            mass = positive(1.0 if mass is None else mass, "mass")
            moments = principal_inertia(kinds, np.array([mass]), radii, extents,
                                        gyration[None, :])[0]
        with np.errstate(over="ignore", divide="ignore", under="ignore"):
            ok = np.isfinite(np.concatenate([[mass, 1 / mass], moments, 1 / moments])
                             .astype(self.dtype)).all()
        if not ok:
            raise PhysicsError(f"mass {mass:.3g} kg of a {KIND_NAMES[kind]} of size "
                               f"{float(np.max(extents)) + radius:.3g} m is out of range for "
                               f"{np.dtype(self.dtype).name}: the mass, the moments of inertia "
                               "and their inverses must be finite")
        index = self.count
        grow = lambda old, new: np.concatenate([old, np.asarray(new, self.dtype)])  # noqa: E731
        self.position = grow(self.position, [position])
        self.velocity = grow(self.velocity, [vector3(velocity, "velocity")])
        self.angular_velocity = grow(self.angular_velocity,
                                     [vector3(angular_velocity, "angular_velocity")])
        self.orientation = grow(self.orientation, [q / np.sqrt(q @ q)])
        self.radius = grow(self.radius, [radius])
        self.mass = grow(self.mass, [mass])
        self.restitution = grow(self.restitution, [in_range(restitution, "restitution", 0, 1)])
        self.friction = grow(self.friction, [in_range(friction, "friction", 0)])
        self.active = np.concatenate([self.active, [True]])
        self.kind = np.concatenate([self.kind, np.array([kind], np.int8)])
        self.extent = grow(self.extent, [extent])
        self.gyration = grow(self.gyration, [gyration])
        row = -1 if solid is None else len(self.solids) - 1
        self.solid_of = np.concatenate([self.solid_of, np.array([row], np.int64)])
        return index

    def add_plane(self, normal, offset, restitution=0.0, friction=0.5) -> int:
        """Add the static plane ``normal/|normal| . x = offset`` (solid on the side away from
        ``normal``) and return its index.

        ``normal`` need not be unit length but must not be zero: it is normalised and
        ``offset`` is the plane's signed distance from the origin (m), as in the renderer and
        the scene format. So ``add_plane((0, 2, 0), 1)`` is the floor y = 1.
        """
        normal = vector3(normal, "normal")
        length = float(np.sqrt(normal @ normal))
        if length == 0:
            raise PhysicsError("normal must not be the zero vector")
        offset = finite(offset, "offset")
        grow = lambda old, new: np.concatenate([old, np.asarray(new, self.dtype)])  # noqa: E731
        self.plane_normal = grow(self.plane_normal, [normal / length])
        self.plane_offset = grow(self.plane_offset, [offset])
        self.plane_restitution = grow(self.plane_restitution,
                                      [in_range(restitution, "restitution", 0, 1)])
        self.plane_friction = grow(self.plane_friction, [in_range(friction, "friction", 0)])
        return len(self.plane_offset) - 1

    def add_shape(self, shape: Shape) -> int:
        """Add a static solid given by its signed distance (a `physics.colliders.Shape`: a box,
        a bowl, pegs, any SDF) and return its index among the shapes."""
        if not isinstance(shape, Shape):
            raise PhysicsError(f"a shape must be a physics.colliders.Shape (got "
                               f"{type(shape).__name__})")
        for name in ("restitution", "friction", "lipschitz"):
            finite(getattr(shape, name), f"{shape.name or 'shape'} {name}")
        in_range(shape.restitution, "restitution", 0, 1)
        in_range(shape.friction, "friction", 0)
        in_range(shape.lipschitz, "lipschitz", 1)
        self.shapes.append(shape)
        return len(self.shapes) - 1

    # --- derived state ------------------------------------------------------------------

    @property
    def count(self) -> int:
        """Number of spheres N (removed ones included: indices never change)."""
        return len(self.radius)

    @property
    def time(self) -> float:
        """Simulated time (s): steps x dt, so it does not accumulate rounding."""
        return self.steps * self.dt

    @property
    def inverse_mass(self) -> np.ndarray:
        """1/m (N,) in 1/kg."""
        return 1 / self.mass

    @property
    def inverse_inertia(self) -> np.ndarray:
        """1/I (N,) in 1/(kg m^2), with I = 2/5 m r^2 for a solid sphere (the sphere solver's;
        for any other body it means nothing: see `inverse_inertia_tensor`)."""
        return 1 / (0.4 * self.mass * self.radius * self.radius)

    @property
    def spheres(self) -> np.ndarray:
        """(N,) bool: the active bodies that are spheres, the ones the sphere code steps."""
        return self.active & (self.kind == SPHERE)

    @property
    def principal_inertia(self) -> np.ndarray:
        """Principal moments of inertia (N, 3) in kg m^2, about each body's own axes."""
        return principal_inertia(self.kind, self.mass, self.radius, self.extent, self.gyration)

    def inverse_inertia_tensor(self) -> np.ndarray:
        """World-frame I^-1 (N, 3, 3) in 1/(kg m^2), for the bodies' present orientations."""
        return world_inverse_inertia(self.orientation, self.principal_inertia)

    def angular_momentum(self) -> np.ndarray:
        """Total angular momentum about the origin of the active bodies, (3,) in kg m^2/s:
        sum of m x cross v + I_world w."""
        on = self.active
        spin = np.einsum("nij,nj->ni", world_inertia(self.orientation[on],
                                                     self.principal_inertia[on]),
                         self.angular_velocity[on])
        orbit = self.mass[on, None] * np.cross(self.position[on], self.velocity[on])
        return np.sum(orbit + spin, axis=0).astype(np.float64)

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy of the active bodies (J)."""
        v, w = self.velocity[self.active], self.angular_velocity[self.active]
        m, r = self.mass[self.active], self.radius[self.active]
        sphere = self.kind[self.active] == SPHERE
        if sphere.all():
            return float(np.sum(0.5 * m * np.sum(v * v, axis=1))
                         + np.sum(0.5 * (0.4 * m * r * r) * np.sum(w * w, axis=1)))
        # A box's or capsule's spin energy is w . I_world w / 2.
        solid = np.flatnonzero(self.active)[~sphere]
        inertia = world_inertia(self.orientation[solid], self.principal_inertia[solid])
        m, r, w_sphere = m[sphere], r[sphere], w[sphere]
        w = self.angular_velocity[solid]
        return float(np.sum(0.5 * self.mass[self.active] * np.sum(v * v, axis=1))
                     + np.sum(0.5 * (0.4 * m * r * r) * np.sum(w_sphere * w_sphere, axis=1))
                     + 0.5 * np.sum(w * np.einsum("nij,nj->ni", inertia, w)))

    def potential_energy(self) -> float:
        """Gravitational potential energy -sum m g.x of the active spheres (J), zero at x = 0."""
        x, m = self.position[self.active], self.mass[self.active]
        return float(-np.sum(m * (x @ self.gravity)))

    def energy(self) -> float:
        """Kinetic + rotational + potential energy (J)."""
        return self.kinetic_energy() + self.potential_energy()

    def momentum(self) -> np.ndarray:
        """Total linear momentum of the active spheres, (3,) in kg m/s."""
        return np.sum(self.mass[self.active, None] * self.velocity[self.active], axis=0)

    @property
    def events(self) -> np.ndarray:
        """Every contact event so far, a structured array of EVENT_DTYPE, in order."""
        if not self._events:
            return np.zeros(0, EVENT_DTYPE)
        return np.concatenate(self._events)

    def copy(self, dtype=None) -> "World":
        """An independent copy, optionally converted to another precision."""
        other = copy.deepcopy(self)
        if dtype is not None:
            other.dtype = float_dtype(dtype)
            for name in ("gravity", "position", "velocity", "angular_velocity", "orientation",
                         "radius", "mass", "restitution", "friction", "extent", "gyration",
                         "plane_normal",
                         "plane_offset", "plane_restitution", "plane_friction"):
                setattr(other, name, getattr(other, name).astype(other.dtype))
            if other._resting_impulses is not None:
                keys, normal, tangent = other._resting_impulses
                other._resting_impulses = (keys, normal.astype(other.dtype),
                                           tangent.astype(other.dtype))
        return other

    # --- stepping -----------------------------------------------------------------------

    def step(self, n: int = 1) -> None:
        """Advance the world by ``n`` steps of ``dt`` (0 to MAX_STEPS).

        Afterwards ``world.work`` (a collections.Counter) says what the last step did:
        ``"pairs examined"`` by the broad phase (contacts and swept test), ``"contacts"``,
        ``"collision sweeps"`` and ``"resting passes"`` (each at most ``iterations``),
        ``"solver levels"`` (sequential solver), ``"push-out passes"`` (one) and, with boxes
        or capsules, ``"sweep advances"`` (conservative-advancement evaluations of the swept
        test, solid_sweeps.py). Inside a
        crowd of overlapping spheres the broad phase pairs each sphere with a bounded number of
        neighbours (broadphase.py), so every one of these counts grows at most linearly with
        the number of spheres.
        """
        for _ in range(whole_number(n, "n", 0, MAX_STEPS)):
            self._step()

    def _step(self) -> None:
        h = self.dtype(self.dt)
        n = self.count
        scheme = INTEGRATORS[self.integrator]
        moving = self.active
        x_old, v_old = self.position, self.velocity
        solids = np.flatnonzero(self.kind != SPHERE)

        # 1. integrate velocities: v* = v_n + h g
        v = integrate_velocities(v_old, self.gravity, h, moving)

        # 2. find contacts at x_n. A sphere still approaching a plane it has not reached (gap
        # >= 0) is left to the continuous test below, which finds the moment it reaches the
        # plane: bouncing it here, a little above the plane, would use the wrong speed.
        work = Counter()
        shapes = [shape.at(self.time) for shape in self.shapes]   # kinematic ones placed now
        contacts = find_contacts(self, self.slop, work, shapes, self._neighbours)
        approach = -dot(contacts.normal, v_old[contacts.a] - contacts.surface_velocity)
        # (Only a still surface: the continuous test does not follow a moving one.)
        still = ~(contacts.surface_velocity != 0).any(axis=1)
        arriving = contacts.static & still & (contacts.gap >= 0) & (
            approach > self.restitution_threshold)
        # An arriving face of a shape is met on its tangent plane (bounce_off_statics).
        landing = contacts.select(arriving & (contacts.shape >= 0))
        contacts = contacts.select(~arriving)
        work["contacts"] = len(contacts)

        # 3. resolve contacts: impulses turn v* into v_{n+1}
        pad = lambda array: np.concatenate([array, np.zeros((1,) + array.shape[1:],  # noqa: E731
                                                            self.dtype)])
        motion = np.zeros((n + 1, 6), self.dtype, order="F")     # row n: the static world
        motion[:n, :3], motion[:n, 3:] = v, self.angular_velocity
        bodies = SolverBodies(motion, pad(self.inverse_mass), pad(self.inverse_inertia))
        # What this step's gravity added to each contact's normal velocity (static contacts
        # only: two falling spheres both gain h g, which cancels in their relative velocity).
        gravity_part = np.where(contacts.static, h * dot(contacts.normal, self.gravity), 0)
        keys = contact_keys(contacts, n, len(self.plane_offset), len(self.shapes))
        order = np.argsort(keys, kind="stable")
        # Each box's and capsule's contacts reach a few slops at most; the swept test after
        # step 4 finds what it meets beyond that (solid_contacts.contact_reach).
        reach = contact_reach(self) if len(solids) else None
        solid_contacts = (find_solid_contacts(self, shapes, MAX_SHAPE_CONTACTS, reach)
                          if len(solids) else ())
        if len(solid_contacts) == 0:
            warm = warm_start(keys, self._resting_impulses, self.dtype)
            collisions = SOLVERS[self.solver](bodies, contacts, gravity_part.astype(self.dtype),
                                              h, self.restitution_threshold, self.iterations,
                                              warm, counter=work)
            self._resting_impulses = (keys[order], warm[0][order], warm[1][order])
            solved = contacts
        else:
            # A body that is not a sphere touches something: every contact is solved at its
            # point (point_solver.py), the spheres' with them, in one order.
            solved, collisions = self._solve_at_points(
                bodies, sphere_point_contacts(contacts, self, keys), solid_contacts, h, work)
        v_new, spin = bodies.velocity[:n].copy(), bodies.spin[:n].copy()

        # 4. integrate positions (and orientations, with the same scheme)
        x_new = scheme.positions(x_old, v_old, v_new, h)
        turn = scheme.positions(np.zeros_like(spin), self.angular_velocity, spin, h)
        q_old = self.orientation
        self.orientation = rotate_orientations(self.orientation, turn)
        momentum = np.zeros_like(spin)
        if len(solids):
            # Free flight keeps the angular momentum L = I_world w, not w: a body that is not
            # a sphere turns with its L by the splitting of solids.free_rotation, whatever
            # the integrator, and its new w is L through its inertia where it now points.
            principal = self.principal_inertia[solids]
            momentum[solids] = np.einsum("nij,nj->ni", world_inertia(q_old[solids], principal),
                                         spin[solids])
            self.orientation[solids], spin[solids] = free_rotation(q_old[solids], principal,
                                                                   momentum[solids], h)

        # Continuous collision: bounce off planes and shapes reached during the step ...
        touching = np.zeros((n, len(self.plane_offset)), bool)
        plane, shape = contacts.plane >= 0, contacts.shape >= 0
        touching[contacts.a[plane], contacts.plane[plane]] = True
        acceleration = (v_new - v_old) / h
        start_velocity = parabola_start_velocity(scheme, v_old, v_new, h)
        bounced, end, end_velocity, end_acceleration, hits = bounce_off_statics(
            self, x_old, start_velocity, acceleration, spin, touching, h,
            landing=(landing.a, landing.shape, landing.normal,
                     dot(landing.normal, x_old[landing.a]) - landing.gap - landing.radius_a),
            resting=(contacts.a[shape], contacts.shape[shape], contacts.normal[shape]),
            shapes=shapes)
        x_new[bounced] = end[bounced]
        # ... and leave the velocity the integrator needs to carry on along the new parabola.
        v_new[bounced] = (end_velocity[bounced]
                          - (scheme.weight - 0.5) * h * end_acceleration[bounced])
        # ... and stop spheres at their first touch with another.
        stop_sphere_sweeps(x_old, x_new, self.radius, self.spheres, self.slop, work,
                           self._neighbours)
        # ... and sweep the boxes and capsules (solid_sweeps.py).
        solid_hits = []
        if len(solids):
            solid_hits = self._sweep_solids(shapes, x_old, q_old, x_new, v_new, spin, momentum,
                                            reach, h, work)

        # One push-out pass a step, never more: it removes ``push_out`` of each overlap.
        separate_overlaps(x_new, solved, bodies.inverse_mass, self.slop, self.push_out)
        work["push-out passes"] += 1
        self.work = work

        self.position, self.velocity, self.angular_velocity = x_new, v_new, spin
        self.steps += 1
        self._record(solved, collisions, hits, solid_hits)
        self._remove_out_of_bounds()

    def _sweep_solids(self, shapes, x_old, q_old, x_new, v_new, spin, momentum, reach, h,
                      work) -> list:
        """The swept test of the boxes and capsules (solid_sweeps.py): updates ``x_new``,
        ``v_new``, ``spin`` and the orientations in place and returns the events.

        Over the step a body's centre goes from x_n to x_{n+1} on the parabola of gravity
        alone, x(t) = x_n + t u + t^2 g / 2 with u = (x_{n+1} - x_n) / h - h g / 2: the
        solver's impulses change its velocity at the start of the step, and only gravity
        acts during it. (The sphere test of continuous.py spreads the impulses over the step
        as an acceleration; a box's impact impulses are large, and spread out they would
        meet a wall at the wrong speed.) A body is swept against the planes and shapes when
        it could move a point of it farther than its contact reach:
        L (h max(|u|, |u + h g|) + |r| l) > reach, with L the shapes' largest Lipschitz bound,
        r its turn over the step and l its `lever`. Then every body that moved is swept
        against the others, where one of the two is not a sphere.
        """
        solids = np.flatnonzero(self.active & (self.kind != SPHERE))
        acceleration = np.broadcast_to(self.gravity, x_new.shape)
        u = (x_new - x_old) / h - (0.5 * h) * acceleration
        turn = rotation_vector_between(q_old[solids], self.orientation[solids])
        end = u[solids] + h * acceleration[solids]
        speed = np.maximum(np.sqrt(dot(u[solids], u[solids])), np.sqrt(dot(end, end)))
        lipschitz = max([1.0] + [shape.lipschitz for shape in shapes])
        moves = lipschitz * (h * speed + np.sqrt(dot(turn, turn)) * lever(self)[solids])
        fast = moves > reach[solids]
        displacement = x_new - x_old
        if not fast.any() and not np.any(np.sqrt(dot(displacement, displacement))[self.active]
                                         > reach[self.active]):
            return []               # nothing moves farther than its contacts reach: at rest
        rows = solids[fast]
        events = []
        # When (s into the step), where and how turned each body first met a plane or shape;
        # and how each would have ended the step had it met none.
        impact = (np.full(self.count, np.inf, self.dtype), x_new.copy(),
                  self.orientation.copy())
        unswept = (x_new.copy(), self.orientation.copy(), v_new.copy(), spin.copy())
        if len(rows) and len(self.plane_offset) + len(shapes):
            sweep = Sweep(body=rows, start=x_old[rows], velocity=u[rows],
                          acceleration=acceleration[rows], orientation=q_old[rows],
                          turn=turn[fast], end_orientation=self.orientation[rows],
                          end_spin=spin[rows], momentum=momentum[rows],
                          duration=np.full(len(rows), h, self.dtype))
            moved, events = sweep_solids(self, shapes, sweep, reach, h, work)
            changed, position, velocity, end_acceleration, orientation, new_spin = moved[:6]
            body = rows[changed]                    # (changed: rows of the sweep)
            for where, value in zip(impact, moved[6:]):
                where[body] = value
            x_new[body] = position
            self.orientation[body] = orientation
            spin[body] = new_spin
            # The velocity the integrator needs to carry on along the new parabola.
            v_new[body] = (velocity - (INTEGRATORS[self.integrator].weight - 0.5) * h
                           * end_acceleration)
        _, undone = stop_solid_sweeps(self, x_old, q_old, x_new, self.orientation, reach,
                                      impact, unswept[:2], work)
        # A body that met a surface through another it rode on goes on as if it had not.
        v_new[undone], spin[undone] = unswept[2][undone], unswept[3][undone]
        kept = []
        for kind, body, other, speed, impulse in events:
            keep = ~undone[body]
            kept.append((kind[keep], body[keep], other[keep], speed[keep], impulse[keep]))
        return kept

    def _solve_at_points(self, bodies, sphere_contacts, solid_contacts, h, work):
        """Solve every contact at its point (point_solver.py); ``bodies`` gets the result.

        Returns the contacts solved (physics.solid_contacts.PointContacts) and the collisions.
        """
        n = self.count
        if self.solver != "sequential":
            raise PhysicsError(f"boxes and capsules need the sequential solver (this world "
                               f"has solver {self.solver!r})")
        every = with_levers(join_point_contacts(sphere_contacts, solid_contacts),
                            self.position)
        # I^-1 is 1/I times the identity for a sphere; only a box's or capsule's turns with it.
        tensors = np.zeros((n + 1, 3, 3), self.dtype)
        tensors[:n] = self.inverse_inertia[:, None, None] * np.eye(3, dtype=self.dtype)
        solid = np.flatnonzero(self.kind != SPHERE)
        tensors[solid] = world_inverse_inertia(self.orientation[solid],
                                               self.principal_inertia[solid])
        points = PointBodies(bodies.velocity, bodies.spin, bodies.inverse_mass, tensors)
        gravity_part = np.where(every.static, h * dot(every.normal, self.gravity), 0)
        warm = warm_start(every.key, self._resting_impulses, self.dtype)
        collisions = solve_points(points, every, gravity_part.astype(self.dtype), h,
                                  self.restitution_threshold, self.iterations, warm,
                                  counter=work, gravity=self.gravity)
        self._resting_impulses = (every.key, warm[0], warm[1])
        work["contacts"] = len(every)
        return every, collisions

    def _record(self, contacts, collisions, hits, solid_hits=()) -> None:
        # Point contacts hold their kinds and others as arrays; sphere contacts derive them.
        at_points = isinstance(contacts, PointContacts)
        kinds = contacts.kind if at_points else contacts.kind()
        others = contacts.other if at_points else contacts.other()
        if collisions:      # every sweep's, in order, as one block of events
            index, approach, impulse = (np.concatenate(part) for part in zip(*collisions))
            self._add_events(kinds[index], contacts.a[index], others[index], approach, impulse)
        planes = len(self.plane_offset)
        for body, static, approach, impulse in hits:
            self._add_events(np.where(static < planes, "sphere-plane", "sphere-shape"), body,
                             np.where(static < planes, static, static - planes), approach,
                             impulse)
        for kind, body, other, approach, impulse in solid_hits:
            self._add_events(kind, body, other, approach, impulse)

    def _add_events(self, kind, body, other, speed, impulse) -> None:
        self._events.append(make_events(self.steps, self.time, kind, body, other, speed,
                                        impulse))

    def _remove_out_of_bounds(self) -> None:
        if self.bounds is None:
            return
        low, high = self.bounds
        outside = self.active & np.any((self.position < low) | (self.position > high), axis=1)
        if outside.any():
            body = np.flatnonzero(outside)
            self.active = self.active & ~outside
            speed = np.sqrt(np.sum(self.velocity[body] ** 2, axis=1))
            self.velocity[body] = 0
            self.angular_velocity[body] = 0
            self._add_events("left-bounds", body, np.full(len(body), -1), speed,
                             np.zeros(len(body)))
