"""The contact solver for bodies that are not spheres: impulses at contact points.

A sphere's contact point is always r n from its centre, and its inertia the same about every
axis, which is what makes impulses.py short. A box touches the floor at its corners, and its
inertia is a tensor. With the lever arm r = p - x from a body's centre to the contact point p
and the world-frame inverse inertia tensor I^-1 (solids.py), the velocity of a's contact point
relative to b's is

    v_rel = (v_a + w_a x r_a) - (v_b + w_b x r_b),

an impulse P at p (and -P on b) changes

    v_a += P / m_a,   w_a += I_a^-1 (r_a x P),   v_b -= P / m_b,   w_b -= I_b^-1 (r_b x P),

and so changes v_rel along a direction d by k_d per unit impulse along d:

    k_d = 1/m_a + 1/m_b + (r_a x d) . I_a^-1 (r_a x d) + (r_b x d) . I_b^-1 (r_b x d)

(Mirtich, "Impulse-based dynamic simulation of rigid body systems", 1996, ch. 4; Catto,
"Iterative dynamics with temporal coherence", GDC 2005). For a sphere (r = -r n, I^-1 = 1/I)
these are the formulas of impulses.py.

In matrix form (Catto, "Iterative dynamics", 2005): with the body's velocity as one 6-vector
V = (v, w), the velocity along d is J V with the Jacobian row J_a = (d, r_a x d) (and
J_b = -(d, r_b x d)), an impulse lambda along d changes V by M^-1 J^T lambda, and
k_d = J M^-1 J^T. `solve_points` builds these rows once a step for the three directions of
each contact (n, t1, t2), so a pass is a few products of small arrays.

The solver is Catto's sequential impulses in the order of Box2D v3 (solver.c, contact_solver.c):

1. warm start: apply last step's accumulated impulses of the contacts that persist;
2. passes over the contacts (until they settle; at most `PASSES_PER_ITERATION` times the
   world's ``iterations``), one at a time in a fixed order: greedy colours in
   key order (`colour_levels`, Box2D v3's graph colouring), so contacts that share no body
   are solved at once with the result of solving them one by one; the
   accumulated normal impulse may only push, and reaches the target normal velocity -gap/h
   (0 for touching bodies; for a speculative contact, what closes its gap in one step and no
   more); friction along two tangent directions, accumulated and clamped to the circle
   |J_t| <= mu j_n (Coulomb's cone);
3. restitution: contacts that approached faster than the threshold before the solve, and
   pushed, get the normal velocity e times that approach speed.

A box lands, slides and stacks with these; a 5-box stack rests because the warm start carries
each contact's share of the weight from step to step (tests/physics/test_solids.py).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from physics.impulses import cross
# m/s: passes stop once none changes a contact's velocity by more than this. Looser than the
# sphere solver's 1e-9 (solvers.SETTLED): a box's corners share its weight in any proportion,
# and Gauss-Seidel goes on shifting the share among them by about 1e-7 m/s a pass long after
# the velocities are right (1e-7 m/s for a step moves a body 4e-10 m). docs/performance.md
# measures what the passes cost.
SETTLED = 1e-7

# Passes per iteration of the world: a box's four corner contacts pull against each other
# through its rotation, and need more passes to agree than a ball's single contact (10 passes
# left a 5-box stack creeping 0.2 mm a second and a capsule on a box rolling off; 40 settle
# both to 1e-10).
PASSES_PER_ITERATION = 4
from scene_model.geometry import dot


@dataclass
class PointBodies:
    """Velocities and inverse masses of N bodies plus the static world as row N.

    velocity, spin : (N + 1, 3) m/s and rad/s; row N stays zero.
    inverse_mass : (N + 1,) 1/kg; inverse_inertia : (N + 1, 3, 3) world-frame I^-1 in
    1/(kg m^2); both 0 in row N.
    """
    velocity: np.ndarray
    spin: np.ndarray
    inverse_mass: np.ndarray
    inverse_inertia: np.ndarray


def tangent_basis(normal: np.ndarray):
    """Two unit tangents t1, t2 (K, 3) with (t1, t2, n) orthonormal: t1 = n x e / |n x e| for
    the coordinate axis e least aligned with n (never parallel to it)."""
    axis = np.zeros_like(normal)
    axis[np.arange(len(normal)), np.argmin(np.abs(normal), axis=1)] = 1
    t1 = cross(normal, axis)
    t1 /= np.sqrt(dot(t1, t1))[:, None]
    return t1, cross(normal, t1)


def jacobians(bodies: PointBodies, contacts, directions):
    """The Jacobian rows of each contact along its three ``directions`` (K, 3, 3) (rows n, t1,
    t2): J_a, J_b (K, 3, 6); their images M^-1 J^T, W_a and W_b (K, 3, 6), the change of each
    body's (v, w) per unit impulse; and k = J M^-1 J^T (K, 3) in 1/kg."""
    a, b = contacts.a, contacts.b
    turn_a = np.cross(contacts.lever_a[:, None, :], directions)          # r_a x d
    turn_b = np.cross(contacts.lever_b[:, None, :], directions)
    jacobian_a = np.concatenate([directions, turn_a], axis=2)
    jacobian_b = -np.concatenate([directions, turn_b], axis=2)
    image_a = np.concatenate([directions * bodies.inverse_mass[a][:, None, None],
                              np.einsum("kij,kdj->kdi", bodies.inverse_inertia[a], turn_a)],
                             axis=2)
    image_b = -np.concatenate([directions * bodies.inverse_mass[b][:, None, None],
                               np.einsum("kij,kdj->kdi", bodies.inverse_inertia[b], turn_b)],
                              axis=2)
    k = np.sum(jacobian_a * image_a, axis=2) + np.sum(jacobian_b * image_b, axis=2)
    return jacobian_a, jacobian_b, image_a, image_b, k


def colour_levels(a, b, static: int) -> list:
    """Contacts 0..K-1 split into levels, each solvable at once: contact k, in order, gets the
    lowest level (colour) that none of the earlier contacts of its moving bodies has.

    Any fixed order of a Gauss-Seidel sweep is one, and this one needs few levels: a stack of
    boxes, each joined to the next by four corner contacts, needs about eight, where keeping
    the contacts' own order (solvers.sequential_levels) needs one per contact. Returns a list
    of (L_i,) index arrays, level by level.
    """
    taken = {}
    colour = []
    for body_a, body_b in zip(a.tolist(), b.tolist()):
        used = taken.setdefault(body_a, set())
        other = taken.setdefault(body_b, set()) if body_b != static else set()
        c = 0
        while c in used or c in other:
            c += 1
        colour.append(c)
        used.add(c)
        other.add(c)
    colour = np.asarray(colour, np.int64)
    return [np.flatnonzero(colour == c) for c in range(colour.max() + 1)] if len(colour) else []


def visiting_order(point, gravity) -> np.ndarray:
    """The order (K,) in which the passes visit the contacts: highest point first, along
    -``gravity``, ties (and a world without gravity) in key order.

    In a stack the weight of each box then reaches the contact under it within the same
    pass, top to bottom, instead of climbing one contact a pass: a resting five-box stack
    settles in one pass a step instead of 10-18 (docs/performance.md).
    """
    return np.argsort(point @ np.asarray(gravity, point.dtype), kind="stable")


def solve_points(bodies: PointBodies, contacts, gravity_part, h, threshold, iterations, warm,
                 counter=None, gravity=(0.0, 0.0, 0.0), restitution_passes=None):
    """Sequential impulses at contact points. Updates ``bodies`` in place.

    Parameters
    ----------
    bodies : PointBodies
        Velocities after this step's gravity (row N: the static world).
    contacts : physics.solid_contacts.PointContacts
        With their lever arms set.
    gravity_part : (K,) ndarray
        What this step's gravity added to n . v_rel (m/s): h n.g against the static world, 0
        between two bodies (both fall alike).
    h : float
        Time step (s).
    threshold : float
        Approach speeds below this (m/s) do not bounce.
    iterations : int
        The world's iterations: at most PASSES_PER_ITERATION times this many passes of the
        contact stage, and this many of the restitution stage.
    warm : (K,) and (K, 3) ndarrays
        Accumulated normal impulse and friction impulse vector to start from (N s): last
        step's for the contacts that persist. Updated in place to this step's.
    counter : collections.Counter, optional
        Gets ``"resting passes"``, ``"restitution passes"`` and ``"solver levels"`` added.
    gravity : (3,) array_like
        The contacts are visited from the highest (along -gravity) down: see `visiting_order`.
    restitution_passes : int, optional
        Most passes of the restitution stage, if not ``iterations``.

    Returns
    -------
    list of (contact indices, approach speeds, normal impulses)
        The contacts that bounced or stopped an approach faster than the threshold.
    """
    counter = Counter() if counter is None else counter
    a, b, n = contacts.a, contacts.b, contacts.normal
    t1, t2 = tangent_basis(n)
    directions = np.stack([n, t1, t2], axis=1)                            # (K, 3, 3)
    jacobian_a, jacobian_b, image_a, image_b, k = jacobians(bodies, contacts, directions)
    surface = np.einsum("kdj,kj->kd", directions, contacts.surface_velocity)
    body_velocity = np.concatenate([bodies.velocity, bodies.spin], axis=1)   # (N + 1, 6)
    order = visiting_order(contacts.point, gravity)
    levels = [order[level] for level in colour_levels(a[order], b[order],
                                                      len(bodies.velocity) - 1)]
    counter["solver levels"] += len(levels)
    # Each level's rows, cut out once: a pass is then a few small products per level.
    # Each level's rows, cut out once: a pass is then a few small products per level. The two
    # bodies of a contact are gathered as one 12-vector (v_a, w_a, v_b, w_b), so J is (3, 12).
    rows = [(level, np.stack([a[level], b[level]], axis=1).reshape(-1),
             np.concatenate([jacobian_a[level], jacobian_b[level]], axis=2),
             np.concatenate([image_a[level], image_b[level]], axis=2), k[level],
             surface[level]) for level in levels]

    def velocity(row):
        """J V (L, 3): the level's relative velocities along n, t1, t2 (m/s)."""
        _, pair, jacobian, _, _, moving = row
        gathered = body_velocity[pair].reshape(len(jacobian), 12, 1)
        return (jacobian @ gathered)[:, :, 0] - moving

    def push(row, change):
        """Apply impulses ``change`` (L, 3) along n, t1, t2. Within a level no moving body
        repeats; the static row may, but its images are 0."""
        _, pair, _, image, _, _ = row
        body_velocity[pair] += (change[:, None, :] @ image).reshape(len(pair), 6)

    approach = np.zeros(len(a), body_velocity.dtype)
    for row in rows:
        approach[row[0]] = gravity_part[row[0]] - velocity(row)[:, 0]

    normal_total, tangent_total = warm
    total = np.stack([normal_total, dot(tangent_total, t1), dot(tangent_total, t2)], axis=1)
    for row in rows:
        push(row, total[row[0]])
    target = -np.maximum(contacts.gap, 0) / h

    for _ in range(PASSES_PER_ITERATION * iterations):
        counter["resting passes"] += 1
        change = 0.0
        for row in rows:
            level, kl = row[0], row[4]
            v = velocity(row)
            old = total[level]
            new = old - v / kl
            new[:, 0] = np.maximum(old[:, 0] + (target[level] - v[:, 0]) / kl[:, 0], 0)
            # Friction along t1 and t2, each with its own effective mass, then the pair
            # clamped to the circle of radius mu j_n (Coulomb's cone).
            length = np.sqrt(new[:, 1] ** 2 + new[:, 2] ** 2)
            limit = contacts.friction[level] * new[:, 0]
            new[:, 1:] *= np.where(length > limit, limit / np.where(length > 0, length, 1),
                                   1)[:, None]
            total[level] = new
            push(row, new - old)
            change = max(change, float(np.max(np.abs(new - old) * kl)))
        if change < SETTLED:
            break

    # Restitution (Box2D v3, b2ApplyRestitution): only contacts that pushed and that were
    # approaching faster than the threshold before the solve.
    bounce = (approach > threshold) & (total[:, 0] > 0)
    bouncing = [row for row in rows if np.any(bounce[row[0]] & (contacts.restitution[row[0]] > 0))]
    most = iterations if restitution_passes is None else restitution_passes
    for _ in range(most if bouncing else 0):
        counter["restitution passes"] += 1
        change = 0.0
        for row in bouncing:
            level, kl = row[0], row[4]
            wanted = contacts.restitution[level] * approach[level]
            old = total[level, 0]
            new = np.where(bounce[level],
                           np.maximum(old + (wanted - velocity(row)[:, 0]) / kl[:, 0], 0), old)
            total[level, 0] = new
            step = np.zeros((len(level), 3), total.dtype)
            step[:, 0] = new - old
            push(row, step)
            change = max(change, float(np.max(np.abs(new - old) * kl[:, 0])))
        if change < SETTLED:
            break

    bodies.velocity[:] = body_velocity[:, :3]
    bodies.spin[:] = body_velocity[:, 3:]
    normal_total[:] = total[:, 0]
    tangent_total[:] = total[:, 1:2] * t1 + total[:, 2:3] * t2
    hit = np.flatnonzero(bounce)
    return [(hit, approach[hit], total[hit, 0].copy())] if len(hit) else []
