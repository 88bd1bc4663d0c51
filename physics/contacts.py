"""Contacts: where two spheres, or a sphere and a plane, touch or overlap.

A contact joins body ``a`` (always a sphere) to body ``b`` (a sphere, or the static world for a
plane). Its normal points from b to a, the direction in which a is pushed, and its gap is the
distance between the surfaces, negative when they overlap:

    sphere-sphere   gap = |x_a - x_b| - (r_a + r_b),   n = (x_a - x_b) / |x_a - x_b|
    sphere-plane    gap = n_p . x_a - offset - r_a,     n = n_p            (plane n_p . x = offset)
    sphere-shape    gap = d(x_a) - r_a,                 n = grad d / |grad d|   (colliders.py)

(Ericson, Real-Time Collision Detection, 2005, ch. 4.3 and 5.2 give the same tests.) Two centres
that coincide have no direction between them; they get a fixed fallback normal, +y, so the
answer is deterministic and never NaN.

The static world is stored as one extra body after the last sphere, index N, with zero inverse
mass: the solvers then treat plane, shape and sphere contacts with the same formulas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.broadphase import CROWD_WINDOW, find_pairs
from physics.colliders import FALLBACK_NORMAL, shape_contacts
from scene_model.geometry import dot


@dataclass
class Contacts:
    """K contacts, in the fixed order the sequential solver visits them.

    Attributes
    ----------
    a, b : (K,) int64
        The bodies; b is N (the static world) for a plane or shape contact.
    plane : (K,) int64
        The plane's index for a sphere-plane contact, -1 for any other.
    shape : (K,) int64
        The shape's index for a sphere-shape contact, -1 for any other.
    slot : (K,) int64
        Which of a ball's contacts with one shape this is (0 for the nearest surface; see
        colliders.py), 0 for the others.
    normal : (K, 3)
        Unit normal from b toward a.
    gap : (K,)
        Surface separation (m), negative when the bodies overlap.
    radius_a, radius_b : (K,)
        Lever arms (m) from each centre to the contact point; 0 for the static world.
    restitution, friction : (K,)
        The pair's coefficients: max(e_a, e_b) and sqrt(mu_a mu_b), as Box2D mixes them
        (box2d v3 src/contact.c, b2MixRestitution and b2MixFriction).
    surface_velocity : (K, 3)
        Velocity of b's surface at the contact (m/s): that of a moving shape (a kinematic
        object), 0 for everything else.
    """
    a: np.ndarray
    b: np.ndarray
    plane: np.ndarray
    shape: np.ndarray
    slot: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    radius_a: np.ndarray
    radius_b: np.ndarray
    restitution: np.ndarray
    friction: np.ndarray
    surface_velocity: np.ndarray

    def __len__(self) -> int:
        return len(self.a)

    def select(self, keep: np.ndarray) -> "Contacts":
        """The contacts where ``keep`` (K,) is True, in the same order (these very arrays,
        not copies, where every one is kept)."""
        index = np.flatnonzero(keep)        # taken once, for all thirteen fields (`take`)
        if len(index) == len(self):
            return self
        return Contacts(**{name: value.take(index, axis=0) for name, value in vars(self).items()})

    @property
    def static(self) -> np.ndarray:
        """(K,) bool: whether b is the static world (a plane or a shape)."""
        return (self.plane >= 0) | (self.shape >= 0)

    def kind(self) -> np.ndarray:
        """``"sphere-plane"``, ``"sphere-shape"`` or ``"sphere-sphere"`` per contact, (K,)."""
        return np.where(self.plane >= 0, "sphere-plane",
                        np.where(self.shape >= 0, "sphere-shape", "sphere-sphere"))

    def other(self) -> np.ndarray:
        """(K,) int64: the plane, the shape or the sphere b, as an event names it."""
        return np.where(self.plane >= 0, self.plane,
                        np.where(self.shape >= 0, self.shape, self.b))


def sphere_plane_gaps(position, radius, plane_normal, plane_offset) -> np.ndarray:
    """Gap (N, P) between N spheres and P planes: n_p . x - offset - r (m)."""
    return dot(position[:, None, :], plane_normal[None, :, :]) - plane_offset - radius[:, None]


def sphere_sphere_normals(position, a, b):
    """Unit normals (K, 3) from b toward a, and centre distances (K,), for sphere pairs.

    Where the centres coincide (distance 0) the normal is FALLBACK_NORMAL.
    """
    d = position[a] - position[b]
    distance = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
    coincident = distance == 0
    safe = np.where(coincident, 1, distance)
    normal = np.where(coincident[:, None], np.asarray(FALLBACK_NORMAL, position.dtype),
                      d / safe[:, None])
    return normal, distance


def spread_coincident(existing, new, distance, rng) -> np.ndarray:
    """Move each of the ``new`` centres (M, 3) that equals an earlier centre (of ``existing``
    (N, 3) or of ``new``) by ``distance`` (M,) in a direction drawn from ``rng``; returns them.

    Two equal centres have no direction between them (their contact would fall back to
    FALLBACK_NORMAL, the same for every such pair), so one is moved off in a random direction;
    with a seeded generator the pair separates the same way on every run.
    """
    new = new.copy()
    while True:
        everything = np.concatenate([existing, new])
        _, first = np.unique(everything, axis=0, return_index=True)
        repeated = np.ones(len(everything), bool)
        repeated[first] = False
        moved = np.flatnonzero(repeated[len(existing):])
        if len(moved) == 0:
            return new
        for row in moved:
            direction = rng.normal(size=3)
            new[row] = new[row] + distance[row] * direction / np.sqrt(direction @ direction)


def find_contacts(world, reach: float, counter=None, shapes=None,
                  neighbours=None) -> Contacts:
    """Every contact with gap <= ``reach`` (m) among the active spheres of ``world``.

    Plane contacts come first, ordered by (sphere, plane), then shape contacts ordered by
    (sphere, shape, slot), then sphere pairs ordered by (a, b) with a < b. The order depends
    only on the state, never on how the pairs were found. Inside a crowd (spheres piled into
    each other far past touching, as when many are spawned at one point) each sphere gets only
    the contacts of its nearest neighbours along a Morton curve, so the work stays bounded
    (crowds.py). ``counter``: see `broadphase.find_pairs`. ``shapes``: the world's shapes
    where they are now (`physics.colliders.Shape.at`); default ``world.shapes``.
    ``neighbours``: a `broadphase.NeighbourList` kept from step to step (the same pairs,
    found with less work), or None.
    """
    n = world.count
    dtype = world.dtype
    alive = np.flatnonzero(world.spheres)       # boxes and capsules: solid_contacts.py
    x, r = world.position, world.radius

    gaps = sphere_plane_gaps(x[alive], r[alive], world.plane_normal, world.plane_offset)
    body, plane = np.nonzero(gaps <= reach)             # row-major: sorted by (sphere, plane)
    plane_a = alive[body]

    shapes = world.shapes if shapes is None else shapes
    (shape_a, shape_index, slot, shape_normal, shape_gap, shape_e, shape_mu,
     shape_velocity) = _shape_contacts(world, shapes, alive, reach)

    i, j = find_pairs(x[alive], r[alive] + 0.5 * reach, CROWD_WINDOW, counter, neighbours, alive)
    a, b = alive[i], alive[j]
    normal, distance = sphere_sphere_normals(x, a, b)
    gap = distance - (r[a] + r[b])
    near = gap <= reach
    a, b, normal, gap = a[near], b[near], normal[near], gap[near]

    none = lambda count: np.full(count, -1, np.int64)  # noqa: E731
    return Contacts(
        a=np.concatenate([plane_a, shape_a, a]),
        b=np.concatenate([np.full(len(plane_a) + len(shape_a), n, np.int64), b]),
        plane=np.concatenate([plane, none(len(shape_a) + len(a))]).astype(np.int64),
        shape=np.concatenate([none(len(plane_a)), shape_index, none(len(a))]),
        slot=np.concatenate([np.zeros(len(plane_a), np.int64), slot,
                             np.zeros(len(a), np.int64)]),
        normal=np.concatenate([world.plane_normal[plane], shape_normal,
                               normal]).astype(dtype, copy=False),
        gap=np.concatenate([gaps[body, plane], shape_gap, gap]).astype(dtype, copy=False),
        radius_a=np.concatenate([r[plane_a], r[shape_a], r[a]]),
        radius_b=np.concatenate([np.zeros(len(plane_a) + len(shape_a), dtype), r[b]]),
        restitution=np.concatenate([
            np.maximum(world.restitution[plane_a], world.plane_restitution[plane]), shape_e,
            np.maximum(world.restitution[a], world.restitution[b])]).astype(dtype, copy=False),
        friction=np.concatenate([
            np.sqrt(world.friction[plane_a] * world.plane_friction[plane]), shape_mu,
            np.sqrt(world.friction[a] * world.friction[b])]).astype(dtype, copy=False),
        surface_velocity=np.concatenate([np.zeros((len(plane_a), 3), dtype), shape_velocity,
                                         np.zeros((len(a), 3), dtype)]),
    )


def _shape_contacts(world, shapes, alive, reach):
    """The sphere-shape contacts of `find_contacts`, ordered by (sphere, shape, slot): the
    spheres (C,), shapes (C,), slots (C,), normals (C, 3), gaps (C,), mixed restitution and
    friction (C,) and surface velocities (C, 3)."""
    dtype = world.dtype
    touching = [shape_contacts(shape, world.position, world.radius, alive, reach)
                for shape in shapes]
    shape_index = np.concatenate([np.full(len(c.body), q, np.int64)
                                  for q, c in enumerate(touching)] + [np.zeros(0, np.int64)])
    if len(shape_index) == 0:           # no shape, or none near: no bookkeeping to pay for
        none, vectors = np.zeros(0, dtype), np.zeros((0, 3), dtype)
        return shape_index, shape_index, shape_index, vectors, none, none, none, vectors
    join = lambda name, empty: np.concatenate(  # noqa: E731
        [getattr(c, name) for c in touching] + [empty]).astype(empty.dtype, copy=False)
    shape_a = join("body", np.zeros(0, np.int64))
    slot = join("slot", np.zeros(0, np.int64))
    order = np.lexsort((slot, shape_index, shape_a))
    shape_a, slot, shape_index = shape_a[order], slot[order], shape_index[order]
    shape_normal = join("normal", np.zeros((0, 3), dtype))[order]
    shape_gap = join("gap", np.zeros(0, dtype))[order]
    shape_e = np.maximum(world.restitution[shape_a], join("restitution", np.zeros(0, dtype))[order])
    shape_mu = np.sqrt(world.friction[shape_a] * join("friction", np.zeros(0, dtype))[order])
    shape_velocity = join("velocity", np.zeros((0, 3), dtype))[order]
    return shape_a, shape_index, slot, shape_normal, shape_gap, shape_e, shape_mu, shape_velocity
