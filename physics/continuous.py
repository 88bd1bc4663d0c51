"""Continuous collision: a fast sphere cannot pass through a wall or another sphere in one step.

Contacts are found at the start of a step, so a ball falling at 200 m/s with dt = 1/60 s,
3.3 m per step, could start above the floor and end below it without ever being seen touching
it. After the positions are integrated, each motion over the step is therefore checked for a
first time of impact (Ericson, Real-Time Collision Detection, 2005, ch. 5.5, "Dynamic
intersection tests").

Against a plane the test is exact. Over one step each integrator puts a body on the parabola
x(t) = x_n + t u + t^2 A / 2 (integrators.py), so the gap to a plane is the quadratic

    s(t) = s0 + u_n t + A_n t^2 / 2,        u_n = n.u, A_n = n.A,

whose first root (s0 >= 0) is t = 2 s0 / (-u_n + sqrt(u_n^2 - 2 A_n s0)): the usual root
formula with numerator and denominator multiplied by the conjugate, so it needs no division
by A_n and loses no digits when A_n is small. The body is stopped there, given the collision impulse
(restitution, friction, spin; impulses.py) and sent along the new parabola for the rest of the
step. Bounces of a single ball are then exact for every integrator and every dt: at e = 1
the apex never drifts, and the bounce happens at the floor, not above or below it.

Against any other shape (a box, a bowl, pegs: colliders.py) the time of impact is found by
conservative advancement along the same parabola, stepping by the SDF's distance over the
largest speed, so it never steps through a wall; the ball gets the same impulse there, with
the shape's normal.

Between two spheres both move, so the test uses their straight paths over the step:
|p + t d|^2 = R^2 with p, d the differences of the start points and displacements and R the
sum of the radii. Both spheres are stopped at the first touch; the solver resolves the
collision at the start of the next step, so it can happen up to one step late.
"""

from __future__ import annotations

import numpy as np

from physics.broadphase import CROWD_WINDOW, find_pairs
from physics.colliders import SAME_SURFACE, first_shape_hit, parabola, surface_near
from physics.contacts import sphere_plane_gaps
from physics.impulses import collision_impulse, cross, effective_masses

SKIN_SLOPS = 4      # the skin of a touching shape, in slops (see bounce_off_statics)
from scene_model.geometry import dot


def first_plane_hit(gap, speed, acceleration, duration):
    """First time (s) in (0, duration] at which a gap s(t) = gap + speed t + acceleration t^2/2
    reaches 0; +inf where it does not. All arguments (K,) arrays (m, m/s, m/s^2), gap >= 0."""
    discriminant = speed * speed - 2 * acceleration * gap
    denominator = -speed + np.sqrt(np.maximum(discriminant, 0))
    hit = (discriminant >= 0) & (denominator > 0)
    time = np.where(hit, 2 * gap / np.where(hit, denominator, 1), np.inf)
    return np.where(time <= duration, time, np.inf)


def bounce_off_statics(world, start, u, acceleration, spin, skip, h, landing=None,
                       resting=None, shapes=None, passes=3):
    """Follow each body's parabola over the step, bouncing off planes and shapes it would reach.

    Parameters
    ----------
    world : World
        For the planes, shapes, radii, masses and coefficients.
    start : (N, 3)
        Positions at the start of the step (m).
    u, acceleration : (N, 3)
        The parabola x(t) = start + t u + t^2 acceleration / 2 of each body (m/s, m/s^2).
    spin : (N, 3)
        Angular velocities after the solver (rad/s); updated in place at each bounce.
    skip : (N, P) bool
        Body-plane pairs already handled by the contact solver (touching at the start).
    h : float
        Step (s).
    landing : tuple of 4 arrays, optional
        Faces of shapes that bodies are arriving at (contacts with a gap >= 0, approaching,
        which the solver left alone), as (body (K,), shape (K,), unit normals (K, 3),
        offsets (K,)): each is met exactly on its tangent plane ``n . x = offset``, as a
        plane would be.
    resting : tuple of 3 arrays, optional
        The solver's contacts with shapes, as (body (C,), shape (C,), unit normals (C, 3)).
        A shape is not skipped because a ball touches it: a ball rolling on the floor of a
        box must still meet its wall. Instead the ball is
        advanced from its path lifted off each face it rests on by a skin of `SKIN_SLOPS`
        slops, so those faces are out of reach and the others are where they were (exactly,
        for faces at right angles). A face met that is one of these (velocity Verlet carries
        the solver's impulse as an acceleration over the step, so its parabola may dip into
        the face before turning) is not a new impact.
    shapes : list of Shape, optional
        The world's shapes where they are at the start of the step (`Shape.at`; default
        ``world.shapes``). A moving shape is met there, and gives the ball its surface's
        velocity: the continuous test does not follow it through the step.
    passes : int
        Most bounces per body per step (a ball driven into a corner meets two or three walls).

    Returns
    -------
    bounced : (N,) bool
        Bodies that hit a plane or shape; only their rows of the results below are meaningful.
    position, velocity_at_end, acceleration : (N, 3)
        Where each bounced body ends the step, its parabola velocity there and its acceleration.
    hits : list of (body, static, approach speed, normal impulse) arrays
        ``static`` < P is a plane, P + q is shape q.

    Planes are met at their exact time of impact (`first_plane_hit`), shapes by conservative
    advancement (`colliders.first_shape_hit`) refined on the tangent plane of the face met.
    """
    n = world.count
    planes = len(world.plane_offset)
    dtype = start.dtype
    bounced = np.zeros(n, bool)
    # Copied column by column (impulses.columns): the plane tests' (N, P, 3) products run
    # fastest so.
    position, velocity, acceleration = (np.array(part, order="F")
                                        for part in (start, u, acceleration))
    elapsed = np.zeros(n, dtype)
    skip = skip.copy()
    none = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3), dtype))
    landing = (*none, np.zeros(0, dtype)) if landing is None else landing
    resting = none if resting is None else resting
    hits = []
    shapes = world.shapes if shapes is None else shapes
    if planes + len(shapes) == 0:
        passes = 0
    for _ in range(passes):
        remaining = h - elapsed
        shape_time, face_normal = _shape_times(world, shapes, position, velocity,
                                               acceleration, remaining, landing, resting)
        time = np.concatenate([_plane_times(world, position, velocity, acceleration,
                                            remaining, skip), shape_time], axis=1)
        time = np.where(world.spheres[:, None], time, np.inf)     # boxes: no sweep
        static = np.argmin(time, axis=1)
        body = np.flatnonzero(np.isfinite(time[np.arange(n), static]))
        if len(body) == 0:
            break
        static = static[body]
        t = time[body, static][:, None]
        # Move to the moment of impact, on the parabola.
        position[body] += t * velocity[body] + (0.5 * t * t) * acceleration[body]
        velocity[body] += t * acceleration[body]
        elapsed[body] += t[:, 0]
        n_s, e_s, mu_s, v_s = _surface(world, shapes, static, position[body])
        # A shape's face has the normal found where it was met (the gradient at the centre
        # gives the nearest face, which may be another one the ball already touches).
        on_shape = static >= planes
        met_shape = on_shape.any()          # (most steps of most scenes: planes only)
        if met_shape:
            n_s[on_shape] = face_normal[body[on_shape], static[on_shape] - planes]
        approach, j = _impact(world, body, n_s, e_s, mu_s, v_s, velocity, spin)
        hits.append((body, static, approach, j))
        # If the ball would fall back through the surface before the step ends, it has landed:
        # it keeps no normal velocity and the surface holds it against any acceleration into it.
        left = (h - elapsed[body])
        u_n = dot(velocity[body] - v_s, n_s)              # relative to a moving surface
        a_n = dot(acceleration[body], n_s)
        landed = u_n * left + 0.5 * a_n * left * left <= 0
        velocity[body] -= (landed * u_n)[:, None] * n_s
        acceleration[body] -= (landed * np.minimum(a_n, 0))[:, None] * n_s
        bounced[body] = True
        # The ball now touches what it met: a plane is skipped, a shape's face rests.
        skip[body[~on_shape], static[~on_shape]] = True
        if met_shape:
            met = np.zeros((n, len(shapes)), bool)
            met[body[on_shape], static[on_shape] - planes] = True
            keep = ~met[landing[0], landing[1]]
            landing = tuple(part[keep] for part in landing)
            resting = (np.concatenate([resting[0], body[on_shape]]),
                       np.concatenate([resting[1], static[on_shape] - planes]),
                       np.concatenate([resting[2], n_s[on_shape]]))
    left = (h - elapsed)[:, None]
    end = position + left * velocity + (0.5 * left * left) * acceleration
    return bounced, end, velocity + left * acceleration, acceleration, hits


def _plane_times(world, position, velocity, acceleration, remaining, skip):
    """(N, P): each body's first time of impact with each plane, +inf for none or skipped."""
    normal, offset = world.plane_normal, world.plane_offset
    gap = sphere_plane_gaps(position, world.radius, normal, offset)
    # n.u and n.A of every body and plane in one product, (2, N, P)
    speed, accel = dot(np.stack([velocity, acceleration])[:, :, None, :], normal)
    return np.where(skip | (gap < 0), np.inf,
                    first_plane_hit(np.maximum(gap, 0), speed, accel, remaining[:, None]))


def _shape_times(world, shapes, position, velocity, acceleration, remaining, landing,
                 resting):
    """When and where each body first meets each shape in the time left.

    Returns (N, Q) times (s; +inf for none) and (N, Q, 3) the unit normals of the faces met.

    The path of a body resting on faces of the shape (``resting``) is lifted off each by the
    skin (see `bounce_off_statics`); a face met on the lifted path is met on the real one
    when the gap along the face's normal, less the lift, reaches 0: the time is moved back
    on the face's tangent plane to that moment. A body is advanced only if its gap now is at
    most the farthest it can travel in the time left (its speed bound times that time).
    ``landing`` faces are met on their tangent plane, exactly.
    """
    n = len(position)
    dtype = position.dtype
    touch = 0.5 * world.slop
    skin = SKIN_SLOPS * world.slop
    times = np.full((n, len(shapes)), np.inf, dtype)
    normals = np.zeros((n, len(shapes), 3), dtype)
    if not shapes:                      # nothing to meet (nor faces of one to land on)
        return times, normals
    end_velocity = velocity + remaining[:, None] * acceleration
    travel = remaining * np.maximum(np.sqrt(dot(velocity, velocity)),
                                    np.sqrt(dot(end_velocity, end_velocity)))
    for q, shape in enumerate(shapes):
        mine = resting[1] == q
        lift = np.zeros((n, 3), dtype)
        np.add.at(lift, resting[0][mine], skin * resting[2][mine])
        rows = np.flatnonzero(world.spheres)
        lifted = position[rows] + lift[rows]
        gap = np.asarray(shape.distance(lifted), dtype) - world.radius[rows]
        reach = gap <= shape.lipschitz * travel[rows] + touch
        rows, lifted = rows[reach], lifted[reach]
        time = first_shape_hit(shape, lifted, velocity[rows], acceleration[rows],
                               world.radius[rows], remaining[rows], touch)
        hit = np.isfinite(time)
        rows, time, lifted = rows[hit], time[hit], lifted[hit]
        if len(rows) == 0:
            continue
        p = parabola(lifted, velocity[rows], acceleration[rows], time)
        depth, normal = surface_near(shape, p, np.asarray(shape.distance(p), dtype))
        # Met again: a face the ball rests on (the solver's), not a new impact.
        again = np.any((rows[:, None] == resting[0][mine][None, :])
                       & (normal @ resting[2][mine].T > SAME_SURFACE), axis=1)
        # gap(t) ~ gap_hit + (t - t_hit) v.n on the tangent plane: back to where it was 0.
        gap_hit = depth - dot(lift[rows], normal) - world.radius[rows]
        closing = dot(velocity[rows] + time[:, None] * acceleration[rows], normal)
        back = (gap_hit < 0) & (closing < 0)
        time = np.where(back, np.maximum(time - gap_hit / np.where(back, closing, 1), 0), time)
        times[rows, q] = np.where(again, np.inf, time)
        normals[rows, q] = normal
    body, q, normal, offset = landing
    gap = dot(position[body], normal) - offset - world.radius[body]
    time = first_plane_hit(np.maximum(gap, 0), dot(velocity[body], normal),
                           dot(acceleration[body], normal), remaining[body])
    for row in np.flatnonzero(np.isfinite(time)):          # a few rows: arriving faces
        if time[row] < times[body[row], q[row]]:
            times[body[row], q[row]] = time[row]
            normals[body[row], q[row]] = normal[row]
    return times, normals


def _surface(world, shapes, static, position):
    """Normal (K, 3), restitution (K,), friction (K,) and surface velocity (K, 3) of the
    static thing each body meets: plane ``static`` < P, else shape ``static`` - P at the
    body's position (its normal is left 0: `_shape_times` found it)."""
    planes = len(world.plane_offset)
    k = len(static)
    normal = np.zeros((k, 3), position.dtype)
    restitution = np.zeros(k, position.dtype)
    friction = np.zeros(k, position.dtype)
    velocity = np.zeros((k, 3), position.dtype)
    plane = static < planes
    normal[plane] = world.plane_normal[static[plane]]
    restitution[plane] = world.plane_restitution[static[plane]]
    friction[plane] = world.plane_friction[static[plane]]
    for q in (np.unique(static[~plane] - planes) if shapes else ()):
        rows = np.flatnonzero(static == planes + q)
        restitution[rows], friction[rows] = shapes[q].coefficients(position[rows])
        velocity[rows] = shapes[q].surface_velocity(position[rows])
    return normal, restitution, friction, velocity


def _impact(world, body, normal, restitution, friction, surface, velocity, spin):
    """Apply the collision impulse of ``body`` against a static surface of unit ``normal``
    (K, 3), coefficients ``restitution``, ``friction`` (K,) and velocity ``surface`` (K, 3)
    to velocity and spin (in place).

    A contact approaching slower than the restitution threshold still gets an inelastic
    impulse: here the ball is at the wall, so something must stop it going through.
    """
    static = np.zeros(len(body), velocity.dtype)
    inverse_mass, inverse_inertia = world.inverse_mass[body], world.inverse_inertia[body]
    radius = world.radius[body]
    v_rel = velocity[body] - cross(radius[:, None] * spin[body], normal) - surface
    approach = -dot(v_rel, normal)
    restitution = np.maximum(world.restitution[body], restitution)
    restitution = np.where(approach > world.restitution_threshold, restitution, 0)
    friction = np.sqrt(world.friction[body] * friction)
    k_normal, k_tangent = effective_masses(inverse_mass, static, inverse_inertia, static,
                                           radius, static)
    impulse, j, approach = collision_impulse(v_rel, normal, static, restitution, friction,
                                             k_normal, k_tangent, 0)
    velocity[body] += impulse * inverse_mass[:, None]
    spin[body] -= (radius * inverse_inertia)[:, None] * cross(normal, impulse)
    return approach, j


def stop_sphere_sweeps(start, end, radius, active, slop, counter=None, neighbours=None):
    """Stop spheres whose straight paths start -> end would make them pass into each other.

    Parameters
    ----------
    start, end : (N, 3)
        Positions at the start and end of the step (m); ``end`` is updated in place.
    radius : (N,)
    active : (N,) bool
    slop : float
        Pairs that start closer than this are the contact solver's (m).
    counter : collections.Counter, optional
        Counts the candidate pairs (`broadphase.find_pairs`); in a crowd, as there, each
        sphere is tested only against its nearest neighbours.
    neighbours : broadphase.NeighbourList, optional
        Kept from step to step: the same pairs as `find_pairs`, with less work.

    Returns
    -------
    (N,) bool
        The bodies that were stopped.
    """
    alive = np.flatnonzero(active)
    stopped = np.zeros(len(start), bool)
    if len(alive) < 2:
        return stopped
    d = end - start
    length = np.sqrt(dot(d, d))
    i, j = find_pairs(start[alive] + 0.5 * d[alive], radius[alive] + 0.5 * length[alive],
                      CROWD_WINDOW, counter, neighbours, alive)
    a, b = alive[i], alive[j]
    p, q = start[a] - start[b], d[a] - d[b]
    reach = radius[a] + radius[b]
    # |p + t q|^2 = R^2  <=>  (q.q) t^2 + 2 (p.q) t + (p.p - R^2) = 0; the first root, written
    # as c / (-b + sqrt(b^2 - a c)) so that it is accurate when q is small.
    qa = dot(q, q)
    qb = dot(p, q)
    qc = dot(p, p) - reach * reach
    discriminant = qb * qb - qa * qc
    denominator = -qb + np.sqrt(np.maximum(discriminant, 0))
    separate = np.sqrt(np.maximum(qc + reach * reach, 0)) - reach > slop
    hit = separate & (qb < 0) & (discriminant >= 0) & (denominator > 0)
    time = np.where(hit, qc / np.where(hit, denominator, 1), np.inf)
    hit &= time < 1
    if not hit.any():
        return stopped
    first = np.full(len(start), np.inf, start.dtype)
    np.minimum.at(first, a[hit], time[hit])
    np.minimum.at(first, b[hit], time[hit])
    stopped = np.isfinite(first)
    end[stopped] = start[stopped] + first[stopped][:, None] * d[stopped]
    return stopped
