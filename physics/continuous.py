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

Between two spheres both move, so the test uses their straight paths over the step:
|p + t d|^2 = R^2 with p, d the differences of the start points and displacements and R the
sum of the radii. Both spheres are stopped at the first touch; the solver resolves the
collision at the start of the next step, so it can happen up to one step late.
"""

from __future__ import annotations

import numpy as np

from physics.broadphase import CROWD_WINDOW, find_pairs
from physics.contacts import sphere_plane_gaps
from physics.impulses import collision_impulse, cross, effective_masses
from scene_model.geometry import dot


def first_plane_hit(gap, speed, acceleration, duration):
    """First time (s) in (0, duration] at which a gap s(t) = gap + speed t + acceleration t^2/2
    reaches 0; +inf where it does not. All arguments (K,) arrays (m, m/s, m/s^2), gap >= 0."""
    discriminant = speed * speed - 2 * acceleration * gap
    denominator = -speed + np.sqrt(np.maximum(discriminant, 0))
    hit = (discriminant >= 0) & (denominator > 0)
    time = np.where(hit, 2 * gap / np.where(hit, denominator, 1), np.inf)
    return np.where(time <= duration, time, np.inf)


def bounce_off_planes(world, start, u, acceleration, spin, skip, h, passes=3):
    """Follow each body's parabola over the step, bouncing off planes it would cross.

    Parameters
    ----------
    world : World
        For the planes, radii, masses and coefficients.
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
    passes : int
        Most bounces per body per step (a ball driven into a corner meets two or three walls).

    Returns
    -------
    bounced : (N,) bool
        Bodies that hit a plane; only their rows of the results below are meaningful.
    position, velocity_at_end, acceleration : (N, 3)
        Where each bounced body ends the step, its parabola velocity there and its acceleration.
    hits : list of (body, plane, approach speed, normal impulse) arrays
    """
    n = world.count
    bounced = np.zeros(n, bool)
    position, velocity, acceleration = start.copy(), u.copy(), acceleration.copy()
    elapsed = np.zeros(n, start.dtype)
    skip = skip.copy()
    hits = []
    if len(world.plane_offset) == 0:
        passes = 0
    for _ in range(passes):
        normal, offset = world.plane_normal, world.plane_offset
        gap = sphere_plane_gaps(position, world.radius, normal, offset)
        speed = dot(velocity[:, None, :], normal[None, :, :])
        accel = dot(acceleration[:, None, :], normal[None, :, :])
        remaining = (h - elapsed)[:, None]
        time = np.where(skip | (gap < 0), np.inf,
                        first_plane_hit(np.maximum(gap, 0), speed, accel, remaining))
        time = np.where(world.active[:, None], time, np.inf)
        plane = np.argmin(time, axis=1)
        body = np.flatnonzero(np.isfinite(time[np.arange(n), plane]))
        if len(body) == 0:
            break
        plane = plane[body]
        t = time[body, plane][:, None]
        # Move to the moment of impact, on the parabola.
        position[body] += t * velocity[body] + (0.5 * t * t) * acceleration[body]
        velocity[body] += t * acceleration[body]
        elapsed[body] += t[:, 0]
        approach, j = _impact(world, body, plane, velocity, spin)
        hits.append((body, plane, approach, j))
        # If the ball would fall back through the plane before the step ends, it has landed:
        # it keeps no normal velocity and the plane holds it against any acceleration into it.
        n_p = normal[plane]
        left = (h - elapsed[body])
        u_n = dot(velocity[body], n_p)
        a_n = dot(acceleration[body], n_p)
        landed = u_n * left + 0.5 * a_n * left * left <= 0
        velocity[body] -= (landed * u_n)[:, None] * n_p
        acceleration[body] -= (landed * np.minimum(a_n, 0))[:, None] * n_p
        skip[body, plane] = True
        bounced[body] = True
    left = (h - elapsed)[:, None]
    end = position + left * velocity + (0.5 * left * left) * acceleration
    return bounced, end, velocity + left * acceleration, acceleration, hits


def _impact(world, body, plane, velocity, spin):
    """Apply the collision impulse of ``body`` against ``plane`` to velocity and spin (in place).

    A contact approaching slower than the restitution threshold still gets an inelastic
    impulse: here the ball is at the wall, so something must stop it going through.
    """
    normal = world.plane_normal[plane]
    static = np.zeros(len(body), velocity.dtype)
    inverse_mass, inverse_inertia = world.inverse_mass[body], world.inverse_inertia[body]
    radius = world.radius[body]
    v_rel = velocity[body] - cross(radius[:, None] * spin[body], normal)
    approach = -dot(v_rel, normal)
    restitution = np.maximum(world.restitution[body], world.plane_restitution[plane])
    restitution = np.where(approach > world.restitution_threshold, restitution, 0)
    friction = np.sqrt(world.friction[body] * world.plane_friction[plane])
    k_normal, k_tangent = effective_masses(inverse_mass, static, inverse_inertia, static,
                                           radius, static)
    impulse, j, approach = collision_impulse(v_rel, normal, static, restitution, friction,
                                             k_normal, k_tangent, 0)
    velocity[body] += impulse * inverse_mass[:, None]
    spin[body] -= (radius * inverse_inertia)[:, None] * cross(normal, impulse)
    return approach, j


def stop_sphere_sweeps(start, end, radius, active, slop, counter=None):
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
                      CROWD_WINDOW, counter)
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
