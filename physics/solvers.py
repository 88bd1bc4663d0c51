"""Contact solvers: the impulses that stop spheres passing into each other and the floor.

Resolving contacts has two stages (after Guendelman, Bridson and Fedkiw, "Nonconvex rigid
bodies with stacking", SIGGRAPH 2003, which separates collision from contact):

1. collisions: every contact whose bodies approach faster than the restitution threshold gets
   the impulse of a collision with restitution e and Coulomb friction; repeated until nothing
   approaches (at most ``iterations`` sweeps);
2. resting contact: impulses that only stop interpenetration (e = 0) and apply friction,
   accumulated and clamped over ``iterations`` passes (Catto's sequential impulses, GDC 2005).

The two solvers differ only in which velocities a contact sees:

sequential (Gauss-Seidel)
    Contacts are visited one at a time in a fixed order (planes first, then pairs by index),
    each seeing the velocities left by the one before. A collision travels down a row of
    touching balls within one step, as the impact does in a real Newton's cradle.

simultaneous (Jacobi)
    Every contact computes its impulse from the same velocities and the impulses are summed:
    what a GPU does, one thread per contact. Summing two impulses meant for one body would
    overshoot (and could add energy), so each body's mass is shared among its contacts
    (Tonge, Benevolenski and Voroshilov, "Mass splitting for jitter-free parallel rigid body
    simulation", SIGGRAPH 2012): as if each contact pushed its own copy of the body and the
    copies' velocities were then averaged. Kinetic energy is convex in the velocities, so the
    average has no more energy than the copies had: no sweep can add energy. In a collision
    sweep the mass is shared only among the contacts that collide in that sweep.

Newton's cradle (5 touching balls, e = 1, the first struck at speed V). The sequential solver
meets contact 1-2 first and swaps the velocities of balls 1 and 2, then 2-3 and swaps again,
and so on: ball 5 leaves at V and balls 1-4 stand still, with momentum and energy conserved,
as on the desk. The simultaneous solver gets the same answer, one contact per sweep: in each
sweep only one contact of the row is closing, so no mass is shared and each collision is a
plain two-ball swap. (Had the mass been shared among all touching contacts, balls 2-4, each
touched twice, would weigh half as much to each contact and the row would end moving together
at V/5, keeping momentum but losing 80% of the energy.)

Where they differ is a true simultaneous impact, one ball striking two at once: a ball falling
onto two touching balls, exactly between them. The sequential solver collides with the
lower-numbered ball first, as if the other were not there, then with the other: energy is
conserved but the answer is lopsided and depends on the numbering. The simultaneous solver
treats both at once and stays symmetric, but the averaging loses energy (a third of it at
e = 1 in tests/physics/test_collisions.py). Neither is wrong: simultaneous impact has no single
right answer (Smith et al., "Reflections on simultaneous impact", SIGGRAPH 2012); a real
cradle behaves sequentially because the impact runs through the balls as a wave.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import replace

import numpy as np

from physics.colliders import MAX_SHAPE_CONTACTS
from physics.impulses import (SolverBodies, apply_impulse, apply_rows, collision_impulse,
                              columns, contact_impulse, contact_rows, effective_masses,
                              relative_velocity, scatter_add, take_rows)
from scene_model.geometry import dot

SETTLED = 1e-9   # m/s: resting passes stop once none changes a velocity by more than this


def solve_sequential(bodies: SolverBodies, contacts, gravity_part, h, threshold, iterations,
                     warm, counter=None):
    """Gauss-Seidel: contacts one by one in their fixed order. Updates ``bodies`` in place.

    Parameters
    ----------
    bodies : SolverBodies
        Velocities after this step's gravity, and inverse masses (row N: the static world).
    contacts : Contacts
    gravity_part : (K,) ndarray
        h n.g for plane contacts, 0 between spheres (m/s); see impulses.collision_impulse.
    h : float
        Time step (s).
    threshold : float
        Restitution threshold (m/s).
    iterations : int
        Most collision sweeps, and resting-contact passes.
    warm : (K,) and (K, 3) ndarrays
        Resting impulses to start from (N s): last step's, for the contacts that persist
        (`warm_start`). Updated in place to this step's.
    counter : collections.Counter, optional
        Gets the work done added to ``"collision sweeps"`` and ``"resting passes"`` (each at
        most ``iterations``) and, here only, ``"solver levels"`` (the levels that each sweep
        and pass runs through, at most one per contact).

    Returns
    -------
    list of (contact indices, approach speeds, normal impulses)
        The collisions, in the order they happened.

    Contacts that share no body do not affect each other, so the fixed order is run in
    ``levels``: a contact goes in the first level after every earlier contact it shares a body
    with. All contacts of a level are computed at once, with exactly the result of visiting
    them one by one.
    """
    counter = Counter() if counter is None else counter
    contacts = _in_columns(contacts)
    k_normal, k_tangent = _masses(bodies, contacts, 1)
    levels = sequential_levels(contacts.a, contacts.b, len(bodies.velocity) - 1)
    counter["solver levels"] += len(levels)
    rows = [_level_rows(bodies, contacts, level) for level in levels]
    collisions = []
    for _ in range(iterations):
        counter["collision sweeps"] += 1
        collided = False
        for level, where in zip(levels, rows):
            hit = _collide(bodies, contacts, level, where, gravity_part, k_normal, k_tangent,
                           threshold)
            if hit is not None:
                collisions.append(hit)
                collided = True
        if not collided:
            break

    normal_total, tangent_total = warm
    _apply_warm_start(bodies, contacts, normal_total, tangent_total,
                      _level_rows(bodies, contacts, slice(None)))
    target = _resting_target(contacts, h)
    for _ in range(iterations):
        counter["resting passes"] += 1
        change = max((_rest(bodies, contacts, level, target, k_normal, k_tangent, normal_total,
                            tangent_total, where) for level, where in zip(levels, rows)),
                     default=0)
        if change < SETTLED:
            break
    return collisions


def solve_simultaneous(bodies: SolverBodies, contacts, gravity_part, h, threshold, iterations,
                       warm, counter=None):
    """Jacobi with mass splitting: all contacts from the same velocities, impulses summed.

    Same parameters and return value as `solve_sequential`. In a collision sweep a body's mass
    is shared among the contacts that collide in that sweep; in a resting pass, among all its
    contacts.
    """
    counter = Counter() if counter is None else counter
    contacts = _in_columns(contacts)
    every = slice(None)                 # all contacts, as views rather than copies
    rows = _level_rows(bodies, contacts, every)     # where every sweep's impulses go
    collisions = []
    for _ in range(iterations):
        counter["collision sweeps"] += 1
        hit = _collide_together(bodies, contacts, gravity_part, threshold, rows)
        if hit is None:
            break
        collisions.append(hit)

    share = _count(bodies, rows.both)
    k_normal, k_tangent = _masses(bodies, contacts, share)
    normal_total, tangent_total = warm
    _apply_warm_start(bodies, contacts, normal_total, tangent_total, rows)
    target = _resting_target(contacts, h)
    for _ in range(iterations):
        counter["resting passes"] += 1
        if _rest(bodies, contacts, every, target, k_normal, k_tangent, normal_total,
                 tangent_total, rows) < SETTLED:
            break
    return collisions


SOLVERS = {"sequential": solve_sequential, "simultaneous": solve_simultaneous}


def sequential_levels(a, b, static: int) -> list:
    """Split contacts 0..K-1 into levels that can each be solved at once, keeping their order.

    Contact k's level is one more than the highest level of any earlier contact that shares a
    moving body with it (the static world, index ``static``, is shared freely: it never moves).
    Returns a list of (L_i,) index arrays, in order.
    """
    last = {}
    level_of = []
    for body_a, body_b in zip(a.tolist(), b.tolist()):
        level = max(last.get(body_a, -1), last.get(body_b, -1) if body_b != static else -1) + 1
        level_of.append(level)
        last[body_a] = level
        if body_b != static:
            last[body_b] = level
    if not level_of:
        return []
    level_of = np.asarray(level_of)
    order = np.argsort(level_of, kind="stable")
    bounds = np.searchsorted(level_of[order], np.arange(1, level_of.max() + 1))
    return np.split(order, bounds)


def contact_keys(contacts, bodies: int, planes: int, shapes: int = 0) -> np.ndarray:
    """One int64 per contact that names it from step to step: (a, b), (a, plane) or
    (a, shape, slot)."""
    statics = bodies + 1 + planes
    other = np.where(contacts.plane >= 0, bodies + 1 + contacts.plane, contacts.b)
    other = np.where(contacts.shape >= 0,
                     statics + contacts.shape * MAX_SHAPE_CONTACTS + contacts.slot, other)
    return contacts.a * (statics + shapes * MAX_SHAPE_CONTACTS) + other


def warm_start(keys, previous, dtype):
    """Last step's accumulated resting impulses for the contacts in ``keys`` (K,), 0 for new ones.

    Starting from them is what lets a stack rest (Catto, GDC 2005, "warm starting"): the
    weight of the top ball reaches the floor contact over several steps instead of needing
    many passes within one. ``previous`` is (keys, normal, tangent) from the last step or None.
    """
    normal = np.zeros(len(keys), dtype)
    tangent = np.zeros((len(keys), 3), dtype, order="F")
    if previous is not None and len(previous[0]) and len(keys):
        old_keys, old_normal, old_tangent = previous
        slot = np.minimum(np.searchsorted(old_keys, keys), len(old_keys) - 1)
        found = old_keys[slot] == keys
        normal[found] = old_normal[slot[found]]
        tangent[found] = old_tangent[slot[found]]
    return normal, tangent


def separate_overlaps(position, contacts, inverse_mass, slop, fraction):
    """Push overlapping spheres apart by moving them, never by giving them speed.

    Each contact deeper than ``slop`` (m) asks for ``fraction`` of its remaining depth to be
    removed, shared between a and b in proportion to their inverse masses; a body in several
    such contacts moves by the mean of their requests. Velocities are not touched, so no
    kinetic energy appears (a Baumgarte velocity bias would turn the overlap into speed and
    launch the spheres). This is the position stage of Box2D v2 (b2ContactSolver::
    SolvePositionConstraints, with fraction 0.2 and a small slop left so contacts persist).
    World.step runs it once a step, never more: the cap on push-out work. Moving bodies apart
    can lift them, so it may add potential energy (docs/physics.md).

    position : (N, 3) m, updated in place; contacts : Contacts; inverse_mass : (N + 1,) 1/kg.
    """
    deep = contacts.gap < -slop
    if not deep.any():
        return
    a, b = contacts.a[deep], contacts.b[deep]
    im_a, im_b = inverse_mass[a], inverse_mass[b]
    depth = fraction * (-contacts.gap[deep] - slop) / (im_a + im_b)
    push = depth[:, None] * contacts.normal[deep]
    n = len(position)
    total = np.zeros((n + 1, 3), position.dtype)
    count = np.bincount(np.concatenate([a, b]), minlength=n + 1).astype(position.dtype)
    scatter_add(total, a, push * im_a[:, None])
    scatter_add(total, b, -push * im_b[:, None])
    position += total[:n] / np.maximum(count[:n], 1)[:, None]


def _masses(bodies, contacts, share):
    """k_n, k_t (K,) with each body's inverse mass multiplied by ``share`` (its contact count
    under mass splitting, 1 for the sequential solver)."""
    im = bodies.inverse_mass * share
    ii = bodies.inverse_inertia * share
    a, b = contacts.a, contacts.b
    return effective_masses(im[a], im[b], ii[a], ii[b], contacts.radius_a, contacts.radius_b)


def _count(bodies, both, which=None):
    """How many contacts each body (row) is in, as the solver's float dtype: of contacts
    between a and b, ``both`` is a then b (2K,); ``which`` (2K,) bool, if given, counts only
    the contacts it marks (twice over: for a, then for b)."""
    return np.bincount(both, which, minlength=len(bodies.velocity)).astype(
        bodies.velocity.dtype)


def _collide_together(bodies, contacts, gravity_part, threshold, rows):
    """One Jacobi collision sweep: every contact from the same velocities, mass split among the
    contacts that collide. Applied through ``rows`` (`_level_rows` of every contact); None if
    nothing collides.

    The sweep is worked out for every contact, not only the colliding ones: the others get a
    zero impulse (`collision_impulse`), and adding zero leaves a velocity as it was. That
    spares gathering the colliding contacts' rows and working out where their impulses go in
    each sweep, some 30 NumPy calls: with ~150 contacts a call costs about the same for all
    of them as for the few that collide (a fifth, in a pile).
    """
    n = contacts.normal
    v_rel = relative_velocity(bodies, rows, contacts.surface_velocity)
    u = dot(v_rel, n)
    approach = gravity_part - u
    colliding = approach > threshold
    if not colliding.any():
        return None
    # A body in no colliding contact keeps share 1: its contacts' impulses are zero whatever
    # their k, and k must not be 0.
    share = np.maximum(_count(bodies, rows.both, np.tile(colliding, 2)), 1)
    k_normal, k_tangent = _masses(bodies, contacts, share)
    impulse, j, approach = collision_impulse(v_rel, n, gravity_part, contacts.restitution,
                                             contacts.friction, k_normal, k_tangent, threshold, u,
                                             approach)
    hit = (j > 0).nonzero()[0]
    if not len(hit):
        return None
    apply_rows(bodies, impulse, rows)
    return hit, approach[hit], j[hit]


def _resting_target(contacts, h):
    """Lowest normal velocity allowed in resting contact: -gap/h lets a small gap close in one
    step (a speculative contact, as in Box2D v3), 0 once the bodies touch."""
    return -np.maximum(contacts.gap, 0) / h


def _collide(bodies, contacts, index, rows, gravity_part, k_normal, k_tangent, threshold):
    """Collision impulses for contacts ``index`` (a level of the sequential solver, whose
    bodies are ``rows``, `_level_rows`), applied; None if none of them collides."""
    a, b, n = contacts.a[index], contacts.b[index], rows.normal
    ra, rb = contacts.radius_a[index], contacts.radius_b[index]
    v_rel = relative_velocity(bodies, rows, _surface(contacts, index))
    impulse, j, approach = collision_impulse(
        v_rel, n, gravity_part[index], contacts.restitution[index], contacts.friction[index],
        k_normal[index], k_tangent[index], threshold)
    hit = np.flatnonzero(j > 0)
    if not len(hit):
        return None
    apply_impulse(bodies, a[hit], b[hit], take_rows(n, hit), ra[hit], rb[hit],
                  take_rows(impulse, hit))
    return index[hit], approach[hit], j[hit]


def _apply_warm_start(bodies, contacts, normal_total, tangent_total, rows):
    """Apply the starting impulses, the friction part turned into the current tangent plane;
    ``rows``: `_level_rows` of every contact."""
    n = contacts.normal
    tangent_total -= dot(tangent_total, n)[:, None] * n
    impulse = normal_total[:, None] * n + tangent_total
    apply_rows(bodies, impulse, rows)


def _in_columns(contacts):
    """``contacts`` with its (K, 3) arrays stored column by column (`impulses.columns`), as
    the solvers' arithmetic runs fastest; surface_velocity None where every surface is still
    (subtracting its zeros changes no velocity: it would only cost a NumPy call a pass)."""
    moving = contacts.surface_velocity.any()
    return replace(contacts, normal=columns(contacts.normal),
                   surface_velocity=columns(contacts.surface_velocity) if moving else None)


def _surface(contacts, index):
    """The surface velocities (K, 3) of contacts ``index``, None where all are still."""
    surface = contacts.surface_velocity
    return None if surface is None else take_rows(surface, index)


def _level_rows(bodies, contacts, index):
    """`impulses.ContactRows` of contacts ``index``: the same in every sweep and pass."""
    return contact_rows(bodies, contacts.a[index], contacts.b[index], contacts.radius_a[index],
                        contacts.radius_b[index], take_rows(contacts.normal, index))


def _rest(bodies, contacts, index, target, k_normal, k_tangent, normal_total, tangent_total,
          rows):
    """One resting-contact pass over contacts ``index`` (an index array, or a slice: every
    contact, read without copying), whose impulses go to ``rows`` (`_level_rows`): impulses
    applied, totals updated.

    Returns the largest change of relative velocity it caused (m/s), 0 for no contacts.
    """
    n = rows.normal
    if len(n) == 0:
        return 0.0
    v_rel = relative_velocity(bodies, rows, _surface(contacts, index))
    normal_part, tangent_part = normal_total[index], take_rows(tangent_total, index)
    impulse = contact_impulse(v_rel, n, target[index], contacts.friction[index],
                              k_normal[index], k_tangent[index], normal_part, tangent_part)
    if not isinstance(index, slice):        # a slice's parts are views: already written
        normal_total[index] = normal_part
        tangent_total[index] = tangent_part
    apply_rows(bodies, impulse, rows)
    size = np.sqrt(dot(impulse, impulse))
    return float((size * k_tangent[index]).max())
