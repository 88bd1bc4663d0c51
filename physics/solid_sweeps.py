"""Continuous collision of boxes and capsules: each body swept over its step, met at its time of
impact.

The contacts of a box or capsule are found at the start of a step, and only within its reach,
a few slops (solid_contacts.contact_reach: Box2D v3's speculative distance). A box thrown at
200 m/s with dt = 1/60 s moves 3.3 m a step: whatever it meets farther away than its reach
is found here, after the positions are integrated, by sweeping it over the step.

**The sweep** (`Sweep`). Over one step the centre goes from x_n to x_{n+1} on the parabola
of gravity, x(t) = x_n + t u + t^2 A / 2 with A = g (the solver's impulses change the
velocity at the start of the step; World._sweep_solids), and the orientation turns at a
constant rate from q_n to q_{n+1} (a slerp: q(t) = exp((t / h) r) q_n, r the rotation vector
between them, as Box2D v3's b2Sweep interpolates the angle). The slerp is not the free
rotation of solids.free_rotation, but has the same ends. A point of the body at most l from
its centre (a box's corner, a capsule's segment end) then moves at most::

    |x'(t)| + |w| l <= max(|u|, |u + h A|) + (|r| / h) l,

(|x'(t)|^2 is a convex quadratic in t, largest at an end of the step), and toward a plane of
normal n at most max(-n.u, -n.(u + h A), 0) + (|r| / h) l: the bound on the approach speed
of conservative advancement (Mirtich, "Impulse-based dynamic simulation of rigid body
systems", PhD thesis, UC Berkeley 1996; Catto, "Continuous collision", GDC 2013, which
writes it |v.n| + |w| r_max).

**Conservative advancement** (`advance`). With gap(t) a lower bound of the distance between
the body and what it may meet, and V the bound above, nothing can touch before
t + (gap(t) - target) / V. Stepping t by that much until the gap is within a tolerance of the
target never passes through anything, however thin or fast: the body stops 0.5 to 1 slop
from the surface (Box2D v3's b2TimeOfImpact, src/distance.c, stops at the linear slop, give
or take a quarter of it). The gap is the one the contacts use::

    against a plane   the 8 corners, the capsule's 2 end spheres           exact
                      a convex body's surface samples (convex.py)          sampled
    against a shape   its SDF at the 26 surface samples of a box, the
                      5 along a capsule's segment, a convex body's
                      samples (solid_contacts.py)                          sampled
    against a body    sphere-box (the box's SDF), sphere-capsule and
                      capsule-capsule (nearest points of segments),
                      capsule-box (the ternary search, less its error),
                      box-box (the largest of the 15 separating-axis
                      gaps, a lower bound of the distance)                 exact or a lower bound
                      a convex body: each one's samples in the other's
                      SDF                                                  sampled

Points that already are contacts of the solver at the start (gap within the body's reach)
are left to it, so a box sliding on a floor is not stopped by the floor it slides on, unless
they end the step deeper than they started (less a slop): the solver's restitution bounces
one contact of a body and leaves its others alone, and can drive a box into the floor it
rests on. Those are swept to where they would sink that slop. A convex body's contacts are
its patch (convex_contacts.py), not its samples: a sample that turning brings onto a surface
(a rolling cylinder's next bottom line), on a body not closing in on it faster than it turns,
counts as such a contact too, and is looked at `TURN_LOOKS` - 1 times within the step, so that
a corner turned through a thin wall is met. Swept as impacts, those samples grazed the surface
every few steps, and each landing in mid-step lifted a rolling cylinder.

**At a plane or shape** (`sweep_statics`) the body is met at its time of impact t*: it is
moved there, its contacts there are solved with restitution (point_solver.solve_points: the
approach speed is the speed it arrives with, not one slowed by a speculative contact), and it
spends the rest of the step moving with its new velocity and spin, along a new parabola (with
the acceleration along the normal removed if it has landed: it would fall back through the
surface before the step ends), as a sphere does in continuous.py. Up to `SWEEP_PASSES`
impacts a step; a body that would meet a further one is stopped at that time of impact (as
Box2D v3 stops a fast body, solver.c, b2SolveContinuous), so it never passes through.

**Between two bodies** (`stop_solid_sweeps`) both move: each is swept on the straight line
from its start to its end of step, turning at a constant rate (Box2D v3's b2Sweep, for
bullets against other bodies), and both are stopped at their first touch; the solver bounces
them at the start of the next step, up to one step late, as stop_sphere_sweeps does for two
spheres. Two bodies in contact are the solver's, unless one met a plane or shape and they end
the step deeper in each other than they started (a box riding on another that lands): then
the one that met the surface first is stopped there and the other swept against it.

What it does not catch: against a shape only the samples are swept, so a feature of the shape
that fits between two samples (an edge or a peg narrower than half a box's side, meeting a
face between its samples; a capsule's samples are 2 l / 4 apart) can pass into the body, as
it can rest in it (docs/physics.md). A body gliding past a shape's surface closer than its
motion in a step over `colliders.MAX_ADVANCE` (and the passes) is stopped where the
advancement gave up: it loses the rest of that step, but does not pass through. A body that
bounced off a surface is swept against the other bodies on the line from its start to its
end of step, not along its bent path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.box_contacts import largest_separation
from physics.broadphase import CROWD_WINDOW, find_pairs
from physics.colliders import MAX_ADVANCE, MAX_SHAPE_CONTACTS, shape_normals
from physics.point_solver import PASSES_PER_ITERATION, PointBodies, solve_points
from physics.quaternions import rotate_orientations, rotation_matrices, rotation_vector_between
from physics.solid_contacts import (sampled_gap, segment_nearest_box, speculative_distance,
                                    static_contacts, support_points)
from physics.solids import (BOX, CAPSULE, CONVEX, SPHERE, box_distance, bounding_radius,
                            capsule_ends, free_rotation, segment_closest, segments_closest,
                            world_inertia, world_inverse_inertia)
from scene_model.geometry import dot

TARGET_SLOPS = 0.5       # a sweep stops the surfaces this many slops apart ...
TOLERANCE_SLOPS = 0.5    # ... or up to this many more
SWEEP_PASSES = 3         # impacts met and resolved per body and step; at the next it stops
TURN_LOOKS = 8           # a turning convex body's settled points are looked at 7 times a step


def lever(world) -> np.ndarray:
    """How far (m) a point that decides a body's gap can be from its centre, (N,): a box's
    corner, a capsule's segment end, a convex body's farthest point; 0 for a sphere (its gap
    does not turn with it)."""
    corner = np.sqrt(dot(world.extent, world.extent))
    return np.select([world.kind == BOX, world.kind == CAPSULE, world.kind == CONVEX],
                     [corner, world.extent[:, 1], world.radius], 0).astype(world.dtype)


def advance(gap, rate, duration, target, tolerance, counter=None, start_gap=None):
    """Conservative advancement: the first time (K,) in [0, duration] at which each of K gaps
    comes within ``tolerance`` of ``target`` (m), +inf where none does.

    Each step moves t by (gap - target) / rate, the least time the gap needs to reach the
    target, so it never steps past a touch. A row that has not converged after MAX_ADVANCE
    steps (a path grazing a surface) counts as a hit where it got to: no nearer than its last
    gap, and not through.

    Parameters
    ----------
    gap : callable
        ``gap(rows, t)`` for rows (M,) int and times t (M,) returns the gaps (M,) (m) of
        those rows then: never more than the true distance.
    rate : (K,)
        A bound on how fast each gap can shrink (m per unit of t); 0: it never shrinks.
    duration : (K,)
        The end of each row's time.
    target : float or (K,)
        The gap to stop at (m).
    tolerance : float
        How far above the target the gap may stop (m).
    counter : collections.Counter, optional
        Gets the rows evaluated added to ``"sweep advances"``.
    start_gap : (K,), optional
        The gaps at t = 0, if known (saves one evaluation).
    """
    time = np.full(len(rate), np.inf, rate.dtype)
    t = np.zeros(len(rate), rate.dtype)
    target = np.broadcast_to(np.asarray(target, rate.dtype), rate.shape)
    rows = np.flatnonzero(rate > 0)
    for attempt in range(MAX_ADVANCE):
        if len(rows) == 0:
            break
        if attempt == 0 and start_gap is not None:
            g = start_gap[rows]
        else:
            if counter is not None:
                counter["sweep advances"] += len(rows)
            g = gap(rows, t[rows])
        aim = target[rows]
        hit = (g <= aim + tolerance) | (attempt == MAX_ADVANCE - 1)
        time[rows[hit]] = t[rows[hit]]
        later = t[rows] + np.maximum(g - aim, 0) / rate[rows]
        going = ~hit & (later <= duration[rows])
        t[rows[going]] = later[going]
        rows = rows[going]
    return time


# --- against the planes and shapes ------------------------------------------------------

@dataclass
class Sweep:
    """How K bodies move over the rest of a step. Arrays of length K.

    body : (K,) int; start, velocity, acceleration : (K, 3) the parabola
    x(t) = start + t velocity + t^2 acceleration / 2 (m, m/s, m/s^2); orientation : (K, 4) at
    the start; turn : (K, 3) the rotation vector (rad) turned by the end, at a constant rate;
    end_orientation : (K, 4) and end_spin : (K, 3) where it points and how it spins then;
    momentum : (K, 3) its angular momentum (kg m^2/s); duration : (K,) s.
    """
    body: np.ndarray
    start: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    orientation: np.ndarray
    turn: np.ndarray
    end_orientation: np.ndarray
    end_spin: np.ndarray
    momentum: np.ndarray
    duration: np.ndarray

    def select(self, rows) -> "Sweep":
        return Sweep(**{name: value[rows] for name, value in vars(self).items()})

    def pose(self, world, rows, t):
        """Full (N, 3) positions and (N, 4) orientations with rows ``rows`` placed at times
        t (M,) along their sweeps (the other bodies where the world has them)."""
        position, orientation = world.position.copy(), world.orientation.copy()
        body, t = self.body[rows], t[:, None]
        position[body] = (self.start[rows] + t * self.velocity[rows]
                          + (0.5 * t * t) * self.acceleration[rows])
        duration = self.duration[rows, None]
        fraction = np.where(duration > 0, t / np.where(duration > 0, duration, 1), 1)
        orientation[body] = rotate_orientations(self.orientation[rows],
                                                fraction * self.turn[rows])
        return position, orientation

    def speed(self):
        """max(|u|, |u + A tau|) (K,): the fastest the centre moves (m/s)."""
        end = self.velocity + self.duration[:, None] * self.acceleration
        return np.maximum(np.sqrt(dot(self.velocity, self.velocity)), np.sqrt(dot(end, end)))

    def spin(self):
        """|r| / tau (K,): the constant rate of turning (rad/s)."""
        some = self.duration > 0
        return np.sqrt(dot(self.turn, self.turn)) / np.where(some, self.duration, 1) * some


def sweep_statics(world, shapes, sweep: Sweep, reach, counter):
    """The first time of impact (K,) of each swept body with a plane or shape (+inf: none),
    and which (K,): plane p, or P + q for shape q.

    A point of a body (a corner, a sample) whose gap at the start is at most ``reach`` (N,)
    of its body is a contact of the solver's, and is left to it if it ends the step no
    deeper than it started (less a slop): a box sliding on the floor is not stopped by the
    floor. One that ends deeper (the solver's restitution, which bounces one contact and
    leaves the others alone, can drive a box into the floor it rests on) is swept too, to
    the moment it would sink a slop deeper than it started.
    """
    k, planes = len(sweep.body), len(world.plane_offset)
    dtype = world.dtype
    target, tolerance = TARGET_SLOPS * world.slop, TOLERANCE_SLOPS * world.slop
    row_of = np.full(world.count, -1)
    row_of[sweep.body] = np.arange(k)
    levers = lever(world)[sweep.body]
    spin_reach = sweep.spin() * levers
    everything = np.arange(k)
    times = np.full((k, planes + len(shapes)), np.inf, dtype)

    def gaps(which, distance, rows, t):
        """The gaps (M,) of the points ``which`` of bodies ``rows`` at times t, each point's
        row and feature (M,), and the points (M, 3)."""
        body, point, radius, feature = support_points(world, sweep.body[rows], which,
                                                      sweep.pose(world, rows, t))
        return (distance(point) - radius).astype(dtype), row_of[body], feature, point

    end_velocity = sweep.velocity + sweep.duration[:, None] * sweep.acceleration
    turning = np.where(world.kind[sweep.body] == CONVEX, spin_reach * sweep.duration, 0)

    def rolled_onto(start, row, points, normal):
        """Which points (M,) of convex bodies turning brings to the surface this step: within
        the turn's reach of it, on a body whose centre closes in on it along the surface's
        normal there (``normal(points (M, 3))``) by no more than the turn's reach (or a
        contact's). The patch holds those up (a rolling cylinder's next bottom line, a
        rocking prism's next face, convex_contacts.py): they are met only if they sink into
        it. A body thrown at the surface faster than it turns has its points met as they
        come within half a slop of it."""
        body = sweep.body[row]
        candidates = np.flatnonzero((turning[row] > 0) & (start <= reach[body] + turning[row]))
        rolled = np.zeros(len(start), bool)
        if len(candidates):
            m = normal(points[candidates])
            closing = np.maximum(np.maximum(-dot(sweep.velocity[row[candidates]], m),
                                            -dot(end_velocity[row[candidates]], m)), 0)
            rolled[candidates] = closing * sweep.duration[row[candidates]] <= np.maximum(
                reach[body[candidates]], turning[row[candidates]])
        return rolled

    def gap_of(which, distance, normal):
        """A gap function for `advance` (target 0), and its values at the start (K,): the
        least of each body's points' gaps less the gap each may come down to (``aim``):
        half a slop, or a slop deeper than it started for a contact that sinks.
        ``normal(points (M, 3))`` gives the surface's unit normals there."""
        start, row, feature, points = gaps(which, distance, everything, np.zeros(k, dtype))
        end = gaps(which, distance, everything, sweep.duration)[0]
        contact = (start <= reach[sweep.body[row]]) | rolled_onto(start, row, points, normal)
        aim_here = np.where(contact, np.minimum(start, 0) - world.slop, target)
        settled = contact & (end >= aim_here)      # a contact that does not sink: the solver's
        if np.any(settled & (turning[row] > 0)):
            # A convex body's point that turns may pass through a thin wall between the
            # step's ends (a spinning prism's corner): looked at TURN_LOOKS times in between,
            # one found a slop inside is not settled. A wall thinner than the turn's reach
            # over TURN_LOOKS can still be missed (docs/physics.md).
            for look in range(1, TURN_LOOKS):
                inside = gaps(which, distance, everything,
                              sweep.duration * (look / TURN_LOOKS))[0] < aim_here
                settled &= ~(inside & (turning[row] > 0))
        aim = np.full((k, feature.max() + 1 if len(feature) else 0), np.inf, dtype)
        aim[row, feature] = np.where(settled, -np.inf, aim_here)

        def gap(rows, t):
            each, row, feature, _ = gaps(which, distance, rows, t)
            least = np.full(k, np.inf, dtype)
            np.minimum.at(least, row, each - aim[row, feature])
            return least[rows]
        least = np.full(k, np.inf, dtype)
        np.minimum.at(least, row, start - aim[row, feature])
        return gap, least

    for p, (normal, offset) in enumerate(zip(world.plane_normal, world.plane_offset)):
        closing = np.maximum(np.maximum(-sweep.velocity @ normal, -end_velocity @ normal), 0)
        gap, start_gap = gap_of("corners", lambda x: x @ normal - offset,
                                lambda points: np.tile(normal, (len(points), 1)))
        times[:, p] = advance(gap, (closing + spin_reach).astype(dtype), sweep.duration,
                              0, tolerance, counter, start_gap)
    for q, shape in enumerate(shapes):
        rate = shape.lipschitz * (sweep.speed() + spin_reach)
        gap, start_gap = gap_of("surface", lambda x: np.asarray(shape.distance(x), dtype),
                                lambda points: shape_normals(shape, points))
        times[:, planes + q] = advance(gap, rate.astype(dtype), sweep.duration, 0, tolerance,
                                       counter, start_gap)
    if times.shape[1] == 0:
        return np.full(k, np.inf, dtype), np.zeros(k, np.int64)
    static = np.argmin(times, axis=1)
    return times[everything, static], static


def resolve_impacts(world, shapes, sweep: Sweep, t, h, counter):
    """Move the swept bodies to their times of impact t (K,), solve their contacts with the
    planes and shapes there (with restitution), and return (the sweeps of the rest of the
    step, the events as (kinds, bodies, others, approach speeds, impulses))."""
    n, k, dtype = world.count, len(sweep.body), world.dtype
    body = sweep.body
    position, orientation = sweep.pose(world, np.arange(k), t)
    velocity = np.zeros((n + 1, 3), dtype)
    spin = np.zeros((n + 1, 3), dtype)
    inverse_inertia = np.zeros((n + 1, 3, 3), dtype)
    velocity[body] = sweep.velocity + t[:, None] * sweep.acceleration
    inverse_inertia[body] = world_inverse_inertia(orientation[body],
                                                  world.principal_inertia[body])
    spin[body] = np.einsum("kij,kj->ki", inverse_inertia[body], sweep.momentum)
    inverse_mass = np.concatenate([world.inverse_mass, np.zeros(1, dtype)]).astype(dtype)
    margin = np.full(n, speculative_distance(world), dtype)
    contacts = static_contacts(world, shapes, body, margin, (position, orientation),
                               MAX_SHAPE_CONTACTS)
    bodies = PointBodies(velocity, spin, inverse_mass, inverse_inertia)
    warm = (np.zeros(len(contacts), dtype), np.zeros((len(contacts), 3), dtype))
    # An impact's contacts (nine on a box's face) settle their restitution in about twice
    # the world's passes (10 left a box thrown at a wall at e = 1 leaving 1.3e-6 slower, and
    # spinning): that stage gets PASSES_PER_ITERATION times as many, and stops once settled.
    collisions = solve_points(bodies, contacts, np.zeros(len(contacts), dtype), h,
                              world.restitution_threshold, world.iterations, warm,
                              counter=counter, gravity=world.gravity,
                              restitution_passes=PASSES_PER_ITERATION * world.iterations)
    events = [(contacts.kind[i], contacts.a[i], contacts.other[i], speed, impulse)
              for i, speed, impulse in collisions]

    # Landed: the centre would fall back through the surface of its nearest contact before
    # the step ends. The surface then holds it against the acceleration into it.
    left = sweep.duration - t
    acceleration = sweep.acceleration.copy()
    nearest = np.full(n, np.inf, dtype)
    np.minimum.at(nearest, contacts.a, contacts.gap)
    first = np.flatnonzero(contacts.gap == nearest[contacts.a])
    first = first[np.unique(contacts.a[first], return_index=True)[1]]
    row_of = np.full(n, -1)
    row_of[body] = np.arange(k)
    rows, normal = row_of[contacts.a[first]], contacts.normal[first]
    u_n = dot(bodies.velocity[body[rows]], normal)
    a_n = dot(acceleration[rows], normal)
    landed = u_n * left[rows] + 0.5 * a_n * left[rows] ** 2 <= 0
    acceleration[rows] -= (landed * np.minimum(a_n, 0))[:, None] * normal

    principal = world.principal_inertia[body]
    momentum = np.einsum("kij,kj->ki", world_inertia(orientation[body], principal),
                         bodies.spin[body])
    end_orientation, end_spin = free_rotation(orientation[body], principal, momentum, left)
    rest = Sweep(body=body, start=position[body], velocity=bodies.velocity[body],
                 acceleration=acceleration, orientation=orientation[body],
                 turn=rotation_vector_between(orientation[body], end_orientation),
                 end_orientation=end_orientation, end_spin=end_spin, momentum=momentum,
                 duration=left)
    return rest, events


def sweep_solids(world, shapes, sweep: Sweep, reach, h, counter):
    """Follow swept boxes and capsules through the step, meeting planes and shapes at their
    times of impact (module docstring).

    Returns (rows (M,) of ``sweep`` whose motion changed, their end positions (M, 3),
    velocities at the end of their parabolas (M, 3), accelerations (M, 3), orientations
    (M, 4), spins (M, 3), and the first time of impact (M,) in s, position (M, 3) and
    orientation (M, 4) then), and the events (see `resolve_impacts`).
    """
    k = len(sweep.body)
    current = sweep.select(np.arange(k))           # a copy, changed row by row below
    changed = np.zeros(k, bool)
    first = np.full(k, np.inf, world.dtype)
    met = (sweep.start.copy(), sweep.orientation.copy())     # where each first met one
    live = np.arange(k)
    skip = reach
    events = []
    stop = np.full(k, np.nan, world.dtype)
    for attempt in range(SWEEP_PASSES + 1):
        if len(live) == 0:
            break
        part = current.select(live)
        time, _ = sweep_statics(world, shapes, part, skip, counter)
        hit = np.isfinite(time)
        if attempt == SWEEP_PASSES:
            stop[live[hit]] = time[hit]
            break
        if not hit.any():
            break
        rest, found = resolve_impacts(world, shapes, part.select(hit), time[hit], h, counter)
        events += found
        rows = live[hit]
        if attempt == 0:
            first[rows] = time[hit]
            met[0][rows], met[1][rows] = rest.start, rest.orientation
        for name, value in vars(rest).items():
            getattr(current, name)[rows] = value
        changed[rows] = True
        live = rows
        # After an impact the body's contacts are those within the speculative distance.
        skip = np.full(world.count, speculative_distance(world), world.dtype)
    rows = np.flatnonzero(changed | np.isfinite(stop))
    done = current.select(rows)
    t = np.where(np.isfinite(stop[rows]), stop[rows], done.duration)
    position, orientation = done.pose(world, np.arange(len(rows)), t)
    stopped = np.isfinite(stop[rows])
    orientation = np.where(stopped[:, None], orientation[done.body], done.end_orientation)
    spin = np.where(stopped[:, None],
                    np.einsum("kij,kj->ki", world_inverse_inertia(
                        orientation, world.principal_inertia[done.body]), done.momentum),
                    done.end_spin)
    velocity = done.velocity + t[:, None] * done.acceleration
    return (rows, position[done.body], velocity, done.acceleration, orientation, spin,
            first[rows], met[0][rows], met[1][rows]), events


# --- between two bodies -----------------------------------------------------------------

def pair_gaps(world, a, b, position_a, orientation_a, position_b, orientation_b):
    """Lower bounds (K,) of the distance (m) between bodies a (K,) and b (K,) placed at the
    given positions (K, 3) and orientations (K, 4); not both spheres (module docstring).
    A pair with a convex body has the least gap of either's samples in the other's SDF:
    sampled, so no lower bound between samples, as a box's against a shape."""
    kind_a, kind_b = world.kind[a], world.kind[b]
    gap = np.zeros(len(a), world.dtype)
    convex = (kind_a == CONVEX) | (kind_b == CONVEX)
    for row in np.flatnonzero(convex):
        gap[row] = sampled_gap(world, a[row], b[row], position_a[row], orientation_a[row],
                               position_b[row], orientation_b[row])
    if convex.all():
        return gap
    rest = np.flatnonzero(~convex)
    gap[rest] = _analytic_pair_gaps(world, a[rest], b[rest], position_a[rest],
                                    orientation_a[rest], position_b[rest], orientation_b[rest])
    return gap


def _analytic_pair_gaps(world, a, b, position_a, orientation_a, position_b, orientation_b):
    """`pair_gaps` of pairs of spheres, boxes and capsules."""
    kind_a, kind_b = world.kind[a], world.kind[b]
    gap = np.zeros(len(a), world.dtype)
    # Put the sphere, then the capsule, first: a pair is (lower kind, higher kind) in
    # (SPHERE, CAPSULE, BOX) order.
    rank = np.array([0, 2, 1])
    swap = rank[kind_a] > rank[kind_b]
    first, second = np.where(swap, b, a), np.where(swap, a, b)
    x1 = np.where(swap[:, None], position_b, position_a)
    x2 = np.where(swap[:, None], position_a, position_b)
    q1 = np.where(swap[:, None], orientation_b, orientation_a)
    q2 = np.where(swap[:, None], orientation_a, orientation_b)
    kinds = np.stack([world.kind[first], world.kind[second]], axis=1)
    radius, extent = world.radius, world.extent
    for pair in ((SPHERE, BOX), (SPHERE, CAPSULE), (CAPSULE, CAPSULE)):
        rows = np.flatnonzero(np.all(kinds == pair, axis=1))
        if len(rows) == 0:
            continue
        i, j = first[rows], second[rows]
        if pair == (SPHERE, BOX):
            rotation = rotation_matrices(q2[rows])
            local = np.einsum("kji,kj->ki", rotation, x1[rows] - x2[rows])
            gap[rows] = box_distance(local, extent[j])[0] - radius[i]
            continue
        p2, e2 = capsule_ends(x2[rows], q2[rows], extent[j])
        if pair == (SPHERE, CAPSULE):
            nearest = p2 + segment_closest(p2, e2, x1[rows])[:, None] * (e2 - p2)
            apart = x1[rows] - nearest
        else:
            p1, e1 = capsule_ends(x1[rows], q1[rows], extent[i])
            s, t = segments_closest(p1, e1, p2, e2)
            apart = (p1 + s[:, None] * (e1 - p1)) - (p2 + t[:, None] * (e2 - p2))
        gap[rows] = np.sqrt(dot(apart, apart)) - radius[i] - radius[j]
    boxes = np.flatnonzero(np.all(kinds == (BOX, BOX), axis=1))
    if len(boxes):
        i, j = first[boxes], second[boxes]
        gap[boxes] = largest_separation(x1[boxes], rotation_matrices(q1[boxes]), extent[i],
                                        x2[boxes], rotation_matrices(q2[boxes]), extent[j])
    for row in np.flatnonzero(np.all(kinds == (CAPSULE, BOX), axis=1)):
        i, j = first[row], second[row]
        rotation = rotation_matrices(q2[row:row + 1])[0]
        start, end = capsule_ends(x1[row:row + 1], q1[row:row + 1], extent[i:i + 1])
        t, error = segment_nearest_box(start, end, x2[row], rotation, extent[j])
        nearest = start + t * (end - start) - x2[row]
        gap[row] = box_distance(nearest @ rotation, extent[j:j + 1])[0][0] - error - radius[i]
    return gap


def stop_solid_sweeps(world, start, start_orientation, end, end_orientation, reach,
                      impact=None, unswept=None, counter=None):
    """Stop bodies at their first touch with another, where one of the two is a box or a
    capsule (two spheres: continuous.stop_sphere_sweeps).

    Parameters
    ----------
    world : World
        For the bodies' kinds, sizes and which are active.
    start, end : (N, 3)
        Centres at the start and end of the step (m); ``end`` is updated in place.
    start_orientation, end_orientation : (N, 4)
        Orientations then; ``end_orientation`` is updated in place.
    reach : (N,)
        Each body's contact reach at the start (m): a pair closer than the sum of the two is
        the solver's.
    impact : ((N,), (N, 3), (N, 4)), optional
        When (s into the step) each body first met a plane or shape in `sweep_solids`
        (+inf for none), and its position and orientation then.
    unswept : ((N, 3), (N, 4)), optional
        Where each body would have ended, and how turned, had it not met them.
    counter : collections.Counter, optional
        Gets ``"pairs examined"`` (the broad phase) and ``"sweep advances"`` added.

    Returns
    -------
    stopped, reverted : (N,) bool
        The bodies that were stopped, and those of them whose meeting with a plane or shape
        is undone (their velocity and spin should be the unswept ones again).

    Each body moves on the straight line from start to end, turning at a constant rate; the
    gap of a pair shrinks at most |d_a - d_b| + |r_a| l_a + |r_b| l_b per unit of that line
    (d the displacements, r the rotation vectors, l the `lever`), and `advance` finds where
    it first comes within a slop.

    A pair in contact at the start is the solver's, unless one of the two met a plane or
    shape during the step (and so changed its velocity after the solver) and they end deeper
    in each other than they started: a box riding on another that lands at 36 m/s. Then the
    one that met the surface first (the leader) is stopped where it met it, with its new
    velocity, as Box2D v3 stops a fast body; the other is swept from its start against it
    there, never sinking deeper into it than it started, and if it met the surface too
    (through the leader) that meeting is undone: it keeps its velocity, and stops no later
    than that meeting. The solver resolves the two at the start of the next step.
    """
    n = world.count
    stopped, reverted = np.zeros(n, bool), np.zeros(n, bool)
    alive = np.flatnonzero(world.active)
    if len(alive) < 2 or np.all(world.kind[alive] == SPHERE):
        return stopped, reverted
    if impact is None:
        impact = (np.full(n, np.inf, world.dtype), end, end_orientation)
    impact, met, met_orientation = impact
    impacted = np.isfinite(impact)
    original, original_orientation = (end, end_orientation) if unswept is None else unswept
    dtype = world.dtype
    d = end - start
    turn = rotation_vector_between(start_orientation, end_orientation)
    levers = lever(world)
    length = np.sqrt(dot(d, d))
    spin = np.sqrt(dot(turn, turn)) * levers
    if not np.any(length[alive] + spin[alive] > reach[alive]):
        return stopped, reverted           # no pair can close more than its contacts reach
    bound = bounding_radius(world.kind, world.radius, world.extent)
    further = original - start
    span = np.maximum(length, np.sqrt(dot(further, further)))
    i, j = find_pairs(start[alive], bound[alive] + span[alive], CROWD_WINDOW, counter)
    a, b = alive[i], alive[j]
    relative = d[a] - d[b]
    rate = np.sqrt(dot(relative, relative)) + spin[a] + spin[b]
    # A pair that cannot close by more than its contacts reach is the solver's (two boxes
    # falling side by side move a lot, but not toward each other).
    keep = ((world.kind[a] != SPHERE) | (world.kind[b] != SPHERE)) & (
        (rate > reach[a] + reach[b]) | impacted[a] | impacted[b])
    a, b = a[keep], b[keep]
    if len(a) == 0:
        return stopped, reverted
    # Each pair's two motions: from (x, q), by s (dx, r) for s in [0, 1].
    x_a, q_a, dx_a, r_a = start[a], start_orientation[a], d[a], turn[a]
    x_b, q_b, dx_b, r_b = start[b], start_orientation[b], d[b], turn[b]

    def gap(rows, s):
        s = s[:, None]
        return pair_gaps(world, a[rows], b[rows],
                         x_a[rows] + s * dx_a[rows], rotate_orientations(q_a[rows],
                                                                       s * r_a[rows]),
                         x_b[rows] + s * dx_b[rows], rotate_orientations(q_b[rows],
                                                                       s * r_b[rows]))

    zero = np.zeros(len(a), dtype)
    start_gap = gap(np.arange(len(a)), zero)
    touching = start_gap <= reach[a] + reach[b]
    follow = np.flatnonzero(touching & (impacted[a] | impacted[b]))
    if len(follow):
        end_gap = gap(follow, np.ones(len(follow), dtype))
        follow = follow[end_gap < np.minimum(start_gap[follow], 0) - world.slop]
    # The leader met the surface first: held where it met it. The follower goes from its
    # start to where it would have ended had it not met the surface.
    hold_a = np.zeros(len(a), bool)
    hold_a[follow] = impact[a[follow]] <= impact[b[follow]]
    hold_b = np.zeros(len(a), bool)
    hold_b[follow] = ~hold_a[follow]
    undo, leader = np.zeros(n, bool), np.zeros(n, bool)
    for hold, x, q, dx, r, body, other, other_dx, other_r in (
            (hold_a, x_a, q_a, dx_a, r_a, a, b, dx_b, r_b),
            (hold_b, x_b, q_b, dx_b, r_b, b, a, dx_a, r_a)):
        leader[body[hold]] = True
        x[hold], q[hold] = met[body[hold]], met_orientation[body[hold]]
        dx[hold], r[hold] = 0, 0
        undone = other[hold & impacted[other]]
        undo[undone] = True
        rows = hold & impacted[other]
        other_dx[rows] = original[undone] - start[undone]
        other_r[rows] = rotation_vector_between(start_orientation[undone],
                                                original_orientation[undone])
    start_gap[follow] = gap(follow, zero[follow])
    moving = np.sqrt(dot(dx_a - dx_b, dx_a - dx_b))
    rate = (moving + np.sqrt(dot(r_a, r_a)) * levers[a]
            + np.sqrt(dot(r_b, r_b)) * levers[b]).astype(dtype)
    rate = np.where(touching & ~(hold_a | hold_b), 0, rate)
    target, tolerance = TARGET_SLOPS * world.slop, TOLERANCE_SLOPS * world.slop
    target = np.where(start_gap > target + tolerance, target,
                      np.minimum(start_gap, 0) - world.slop).astype(dtype)
    time = advance(gap, rate, np.ones(len(a), dtype), target, tolerance, counter, start_gap)
    # An undone follower stops at its meeting with the surface at the latest.
    first = np.where(undo, impact / world.dt, np.inf).astype(dtype)
    hit = np.isfinite(time)
    np.minimum.at(first, a[hit & ~hold_a], time[hit & ~hold_a])
    np.minimum.at(first, b[hit & ~hold_b], time[hit & ~hold_b])
    stopped = np.isfinite(first)
    reverted = undo
    # Along the line it was swept on: the unswept one for an undone follower.
    target_end = np.where(undo[:, None], original, end)
    target_turn = rotation_vector_between(start_orientation,
                                          np.where(undo[:, None], original_orientation,
                                                   end_orientation))
    s = first[stopped][:, None]
    end[stopped] = start[stopped] + s * (target_end[stopped] - start[stopped])
    end_orientation[stopped] = rotate_orientations(start_orientation[stopped],
                                                   s * target_turn[stopped])
    end[leader], end_orientation[leader] = met[leader], met_orientation[leader]
    return stopped | leader, reverted
