"""Contacts of boxes and capsules: with planes, shapes, spheres and each other, at points.

A sphere's contact needs no point: it is always r n from the centre (contacts.py). A box's
is wherever the two surfaces meet, so a contact here is a `PointContacts` row: the point p,
the unit normal n from b to a, the gap along n (negative when they overlap), and the lever
arms p - x_a and p - x_b that the solver turns into torque (point_solver.py). How each pair
finds its points, the exact test where there is one, samples where there is not::

    box-plane        the 8 corners: gap = n . c - offset                         exact
    capsule-plane    the 2 segment ends, spheres of the capsule's radius         exact
    box-shape        26 points of the box's surface (corners, edge midpoints,
                     face centres) in the shape's SDF: gap = d(p)                sampled
    capsule-shape    5 points along the segment: gap = d(p) - r                  sampled
    sphere-box       the centre in the box's exact SDF: gap = d(x) - r           exact
    sphere-capsule   the centre against the segment's nearest point             exact
    box-box          separating axes and face clipping (box_contacts.py)         exact
    capsule-box      the segment's ends and its point nearest the box (the box's
                     SDF is convex along the segment: a ternary search finds it)  exact
    capsule-capsule  the segments' nearest points, and each end against the
                     other segment (two points for capsules lying side by side)  exact
    convex-plane     its contact patch: its support point along the plane's -n,
                     and those along directions tilted around it that reach as
                     deep (convex_contacts.py)                                   exact
    convex-shape,    its patch against the other's SDF (from its nearest point,
    convex-body      found by an alternating search), and a box's, capsule's
                     samples in its SDF                                          sampled
    sphere-convex    the centre in the body's SDF: gap = d(x) - r                exact

("One body's SDF at the other's surface samples", Guendelman, Bridson and Fedkiw,
"Nonconvex rigid bodies with stacking", SIGGRAPH 2003, section 5: a sampled surface touches
where a sample is inside; what lies between two samples is not seen, so a peg thinner than
half a box's side can poke into its face. docs/physics.md says so.)

A contact is found while its gap is below each body's **reach** (`contact_reach`): the slop
plus how far the two surfaces can close in one step, h (|v| + R |w|) + h^2 |g| for each body
(R its bounding radius), but never more than `SPECULATIVE_SLOPS` slops. The solver lets such a
contact close its gap and no more (target normal velocity -gap / h, as in Box2D v3's
speculative contacts), and bounces it if it pushed; the cap is Box2D v3's
b2_speculativeDistance (4 b2_linearSlop, constants.h): a speculative contact that bounces
turns the body round where it is, at most its gap away from the surface, so the gap must stay
small. What a body could reach beyond its reach in a step is found by the swept test of
solid_sweeps.py, at its time of impact. Each contact has a key that names it from step to step
(the pair and a feature: which corner, which sample), for warm starting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.box_contacts import box_box_contacts
from physics.colliders import FALLBACK_NORMAL, shape_normals, surface_near
from physics.convex_contacts import body_distance, contact_patch, placed_distance
from physics.quaternions import rotation_matrices
from physics.solids import (BOX, CAPSULE, CAPSULE_SAMPLES, CONVEX, KIND_NAMES, SPHERE,
                            box_distance, box_points, bounding_radius, capsule_ends,
                            segment_closest, segments_closest)
from scene_model.geometry import dot

FEATURES = 4096          # features per pair in a contact key (box_contacts stays below it)
# A pair's features: the first body's samples from 0, the second's from OTHER_SAMPLES, a
# convex body's contact patch (convex_contacts.py) from PATCH_FEATURE, the second body's
# from PATCH_FEATURE + PATCH_OTHER.
OTHER_SAMPLES = 2048
PATCH_FEATURE, PATCH_OTHER = FEATURES - 64, 32
SCAN_POINTS = 17         # points along a capsule's segment looked at first for its nearest
TERNARY_STEPS = 24       # then this many steps, each keeping 2/3 of the bracket: 1e-5 of it
END_SKIP = 0.01          # the nearest point within this fraction of an end: the end's contact
# The largest gap (in slops) at which a contact is speculative: Box2D v3's
# b2_speculativeDistance = 4 b2_linearSlop. A contact the solver bounces is at most this far
# from the surface, so a bounce never happens farther away ("ghost" bounces).
SPECULATIVE_SLOPS = 4


@dataclass
class PointContacts:
    """K contacts at points, in a fixed order. Arrays of length K.

    Attributes
    ----------
    a, b : (K,) int64
        The bodies; b is N (the static world) for a plane or shape.
    static : (K,) bool
        Whether b is the static world.
    other : (K,) int64
        What an event names as b: the plane's, the shape's or the body's index.
    kind : (K,) str
        ``"box-plane"``, ``"sphere-box"``, ... (a's kind, then b's).
    point : (K, 3)
        Contact point (m), on or between the two surfaces.
    lever_a, lever_b : (K, 3)
        p - x_a and p - x_b (m); 0 for the static world.
    normal : (K, 3)
        Unit normal from b toward a.
    gap : (K,)
        Separation along the normal (m), negative when they overlap.
    restitution, friction : (K,)
        The pair's coefficients, max(e_a, e_b) and sqrt(mu_a mu_b).
    surface_velocity : (K, 3)
        Velocity of a moving static surface at p (m/s), 0 for everything else.
    key : (K,) int64
        Names the contact from step to step (sorted ascending).
    """
    a: np.ndarray
    b: np.ndarray
    static: np.ndarray
    other: np.ndarray
    kind: np.ndarray
    point: np.ndarray
    lever_a: np.ndarray
    lever_b: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    restitution: np.ndarray
    friction: np.ndarray
    surface_velocity: np.ndarray
    key: np.ndarray

    def __len__(self) -> int:
        return len(self.a)

    def select(self, keep) -> "PointContacts":
        """The contacts at ``keep`` (a boolean mask or indices), in that order."""
        return PointContacts(**{name: value[keep] for name, value in vars(self).items()})



def solid_key_base(bodies: int, planes: int, shapes: int, shape_slots: int) -> int:
    """The first key of a solid contact: above every key `solvers.contact_keys` gives a
    sphere contact, so both kinds of contact share one warm-start store."""
    return bodies * (bodies + 1 + planes + shapes * shape_slots) + 1


def speculative_margin(world) -> np.ndarray:
    """How far (m) each body's surface can move toward another in one step, plus the slop:
    slop + h (|v| + R |w|) + h^2 |g|, (N,)."""
    h = world.dtype(world.dt)
    speed = np.sqrt(dot(world.velocity, world.velocity))
    spin = np.sqrt(dot(world.angular_velocity, world.angular_velocity))
    reach = bounding_radius(world.kind, world.radius, world.extent)
    gravity = np.sqrt(world.gravity @ world.gravity)
    return (world.slop + h * (speed + reach * spin) + h * h * gravity).astype(world.dtype)


def speculative_distance(world) -> float:
    """The largest gap (m) of a speculative contact: `SPECULATIVE_SLOPS` slops."""
    return SPECULATIVE_SLOPS * world.slop


def contact_reach(world) -> np.ndarray:
    """The largest gap (m) at which each body's contacts are found, (N,): its
    `speculative_margin`, capped at the `speculative_distance`."""
    return np.minimum(speculative_margin(world),
                      world.dtype(speculative_distance(world))).astype(world.dtype)


def find_solid_contacts(world, shapes, shape_slots: int, reach=None) -> PointContacts:
    """Every contact of the world's active boxes and capsules, with gap below the bodies'
    reach (`contact_reach`), sorted by key.

    Parameters
    ----------
    world : physics.World
    shapes : list of physics.colliders.Shape
        The static shapes where they are now.
    shape_slots : int
        Contacts a sphere may have per shape (for the key base, see `solid_key_base`).
    reach : (N,) ndarray, optional
        Each body's reach (m); default `contact_reach`.
    """
    n = world.count
    planes, nshapes = len(world.plane_offset), len(shapes)
    solids = np.flatnonzero(world.active & (world.kind != SPHERE))
    margin = contact_reach(world) if reach is None else reach
    parts = []
    if len(solids):
        parts += _plane_contacts(world, solids, margin)
        parts += _shape_contacts(world, shapes, solids, margin)
        parts += _body_contacts(world, solids, margin)
    statics = n + 1 + planes + nshapes
    base = solid_key_base(n, planes, nshapes, shape_slots)
    return _join(parts, n, statics, base, world.dtype)


def static_contacts(world, shapes, rows, margin, pose, shape_slots: int) -> PointContacts:
    """The contacts of solids ``rows`` (M,) with the planes and ``shapes``, gap below
    ``margin`` (N,), with the bodies at ``pose`` = (position (N, 3), orientation (N, 4)) and
    their lever arms from there: what a swept test resolves at a time of impact."""
    n, planes = world.count, len(world.plane_offset)
    parts = (_plane_contacts(world, rows, margin, pose)
             + _shape_contacts(world, shapes, rows, margin, pose))
    contacts = _join(parts, n, n + 1 + planes + len(shapes),
                     solid_key_base(n, planes, len(shapes), shape_slots), world.dtype)
    return with_levers(contacts, pose[0])


def _part(a, b, other, other_id, kind, feature, point, normal, gap, restitution, friction,
          surface_velocity=None) -> dict:
    """One batch of contacts as a dict of arrays (joined by `_join`)."""
    count = len(a)
    return dict(a=np.asarray(a, np.int64), b=np.asarray(b, np.int64),
                other=np.broadcast_to(np.asarray(other, np.int64), (count,)),
                other_id=np.broadcast_to(np.asarray(other_id, np.int64), (count,)),
                kind=np.broadcast_to(np.asarray(kind, "U15"), (count,)),
                feature=np.asarray(feature, np.int64), point=point, normal=normal, gap=gap,
                restitution=np.broadcast_to(restitution, (count,)),
                friction=np.broadcast_to(friction, (count,)),
                surface_velocity=(np.zeros_like(point) if surface_velocity is None
                                  else surface_velocity))


def _join(parts, n, statics, base, dtype) -> PointContacts:
    parts = [p for p in parts if len(p["a"])]
    if not parts:
        return empty_point_contacts(dtype)
    column = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
    key = base + (column["a"] * statics + column["other_id"]) * FEATURES + column["feature"]
    order = np.argsort(key, kind="stable")
    return point_contacts(column["a"][order], column["b"][order], column["other"][order],
                          column["kind"][order], column["point"][order].astype(dtype),
                          column["normal"][order].astype(dtype),
                          column["gap"][order].astype(dtype),
                          column["restitution"][order].astype(dtype),
                          column["friction"][order].astype(dtype),
                          column["surface_velocity"][order].astype(dtype), key[order], n)


def point_contacts(a, b, other, kind, point, normal, gap, restitution, friction,
                   surface_velocity, key, static_row, position=None) -> PointContacts:
    """A `PointContacts` with its lever arms taken from ``position`` (N, 3), if given, else
    left to `with_levers`."""
    contacts = PointContacts(a=a, b=b, static=b == static_row, other=other, kind=kind,
                             point=point, lever_a=np.zeros_like(point),
                             lever_b=np.zeros_like(point), normal=normal, gap=gap,
                             restitution=restitution, friction=friction,
                             surface_velocity=surface_velocity, key=key)
    if position is not None:
        with_levers(contacts, position)
    return contacts


def with_levers(contacts: PointContacts, position) -> PointContacts:
    """Set the lever arms p - x_a and p - x_b (0 for the static world) from centres (N, 3)."""
    padded = np.concatenate([position, np.zeros((1, 3), position.dtype)])
    contacts.lever_a = contacts.point - padded[contacts.a]
    contacts.lever_b = np.where(contacts.static[:, None], 0,
                                contacts.point - padded[contacts.b])
    return contacts


def empty_point_contacts(dtype) -> PointContacts:
    none = np.zeros(0, np.int64)
    vectors = np.zeros((0, 3), dtype)
    return PointContacts(a=none, b=none, static=np.zeros(0, bool), other=none,
                         kind=np.zeros(0, "U15"), point=vectors, lever_a=vectors,
                         lever_b=vectors, normal=vectors, gap=np.zeros(0, dtype),
                         restitution=np.zeros(0, dtype), friction=np.zeros(0, dtype),
                         surface_velocity=vectors, key=none)


def sphere_point_contacts(contacts, world, keys) -> PointContacts:
    """Sphere contacts (contacts.py `Contacts`) as point contacts: the point is r_a n from
    a's centre toward b; ``keys`` (K,) from `solvers.contact_keys`."""
    point = world.position[contacts.a] - contacts.radius_a[:, None] * contacts.normal
    return point_contacts(contacts.a, contacts.b, contacts.other(), contacts.kind(), point,
                          contacts.normal, contacts.gap, contacts.restitution,
                          contacts.friction, contacts.surface_velocity, keys, world.count)


def join_point_contacts(first: PointContacts, second: PointContacts) -> PointContacts:
    """Both sets, sorted by key (the keys of the two never coincide)."""
    joined = PointContacts(**{name: np.concatenate([getattr(first, name),
                                                     getattr(second, name)])
                              for name in vars(first)})
    return joined.select(np.argsort(joined.key, kind="stable"))


# --- the pairs ----------------------------------------------------------------------------

def support_points(world, rows, which: str, pose=None):
    """Points of bodies ``rows`` that meet a plane or an SDF first: (body (K,), point (K, 3),
    radius (K,), feature (K,)). Boxes: their corners (``which = "corners"``) or 26 surface
    points (``"surface"``), radius 0. Capsules: their two ends, or CAPSULE_SAMPLES points along
    the segment, with the capsule's radius. Convex bodies: their surface samples either way,
    radius 0. Spheres: their centre, with their radius. ``pose`` = (position (N, 3),
    orientation (N, 4)) places the bodies elsewhere than the world has them (a swept test's
    time of impact)."""
    position, orientation = (world.position, world.orientation) if pose is None else pose
    return placed_points(world, rows, which, position[rows], orientation[rows])


def placed_points(world, rows, which: str, position, orientation):
    """`support_points` of bodies ``rows`` (M,) centred at ``position`` (M, 3) and turned by
    ``orientation`` (M, 4)."""
    dtype = world.dtype
    kind = world.kind[rows]
    body, point, radius, feature = [], [], [], []
    box = kind == BOX
    if box.any():
        boxes = rows[box]
        local = box_points(world.extent[boxes], which).astype(dtype)       # (M, P, 3)
        rotation = rotation_matrices(orientation[box])
        where = position[box][:, None, :] + np.einsum("mij,mpj->mpi", rotation, local)
        count = local.shape[1]
        body.append(np.repeat(boxes, count))
        point.append(where.reshape(-1, 3))
        radius.append(np.zeros(len(boxes) * count, dtype))
        feature.append(np.tile(np.arange(count), len(boxes)))
    capsule = kind == CAPSULE
    if capsule.any():
        capsules = rows[capsule]
        start, end = capsule_ends(position[capsule], orientation[capsule],
                                  world.extent[capsules])
        t = np.array([0.0, 1.0]) if which == "corners" else np.linspace(0, 1, CAPSULE_SAMPLES)
        where = start[:, None, :] + t[None, :, None].astype(dtype) * (end - start)[:, None, :]
        body.append(np.repeat(capsules, len(t)))
        point.append(where.reshape(-1, 3))
        radius.append(np.repeat(world.radius[capsules], len(t)))
        feature.append(np.tile(np.arange(len(t)), len(capsules)))
    for k in np.flatnonzero(kind == CONVEX):
        j = rows[k]
        local = world.solids[world.solid_of[j]].samples
        rotation = rotation_matrices(np.asarray(orientation[k:k + 1], np.float64))[0]
        body.append(np.full(len(local), j))
        point.append(np.asarray(position[k], np.float64) + local @ rotation.T)
        radius.append(np.zeros(len(local), dtype))
        feature.append(np.arange(len(local)))
    sphere = kind == SPHERE
    if sphere.any():
        body.append(rows[sphere])
        point.append(position[sphere])
        radius.append(world.radius[rows[sphere]])
        feature.append(np.zeros(int(sphere.sum()), np.int64))
    if not body:
        return (np.zeros(0, np.int64), np.zeros((0, 3), dtype), np.zeros(0, dtype),
                np.zeros(0, np.int64))
    return (np.concatenate(body), np.concatenate(point).astype(dtype),
            np.concatenate(radius).astype(dtype), np.concatenate(feature))


def sampled_gap(world, a: int, b: int, x_a, q_a, x_b, q_b) -> float:
    """The least gap (m) of each body's surface samples (`placed_points`) in the other's SDF,
    bodies a and b placed at x (3,) and turned by q (4,): the distance between them where a
    sample decides it (exact for a sphere's centre; otherwise at most the samples' spacing
    too much)."""
    least = np.inf
    for mine, x, q, other, y, r in ((a, x_a, q_a, b, x_b, q_b), (b, x_b, q_b, a, x_a, q_a)):
        _, point, radius, _ = placed_points(world, np.array([mine]), "surface",
                                            np.asarray(x)[None, :], np.asarray(q)[None, :])
        least = min(least, float(np.min(placed_distance(world, other, y, r, point)[0] - radius)))
    return least


def _kind(world, body) -> np.ndarray:
    return np.asarray(KIND_NAMES)[world.kind[body]]


def _plane_contacts(world, solids, margin, pose=None) -> list:
    plain = solids[world.kind[solids] != CONVEX]       # a convex body has its patch instead
    body, point, radius, feature = support_points(world, plain, "corners", pose)
    n = world.count
    parts = []
    for plane, (normal, offset) in enumerate(zip(world.plane_normal, world.plane_offset)):
        gap = point @ normal - offset - radius
        near = gap <= margin[body]
        rows = body[near]
        parts.append(_part(
            rows, np.full(len(rows), n), plane, n + 1 + plane,
            np.char.add(_kind(world, rows), "-plane"), feature[near],
            point[near] - radius[near, None] * normal, np.tile(normal, (len(rows), 1)),
            gap[near], np.maximum(world.restitution[rows], world.plane_restitution[plane]),
            np.sqrt(world.friction[rows] * world.plane_friction[plane])))
        def plane_distance(p, normal=normal, offset=offset):
            return p @ normal - offset, np.tile(np.asarray(normal, np.float64), (len(p), 1))

        for j in solids[world.kind[solids] == CONVEX]:
            patch = _patch(world, j, plane_distance, margin[j], pose)
            if patch is not None:
                point_j, gap_j, _, feature_j = patch
                count = len(gap_j)
                parts.append(_part(
                    np.full(count, j), np.full(count, n), plane, n + 1 + plane,
                    "convex-plane", feature_j, point_j, np.tile(normal, (count, 1)), gap_j,
                    max(world.restitution[j], world.plane_restitution[plane]),
                    np.sqrt(world.friction[j] * world.plane_friction[plane])))
    return parts


def _patch(world, j, other_distance, reach, pose=None):
    """Convex body j's contact patch (convex_contacts.contact_patch) with the solid of
    ``other_distance``, searched from j's sample nearest it: (points, gaps, normals,
    features) of the patch points within ``reach``, or None."""
    centre = (world.position if pose is None else pose[0])[j:j + 1]
    if other_distance(centre)[0][0] - world.radius[j] > reach:
        return None                            # its bounding sphere is out of reach
    _, samples, _, _ = support_points(world, np.array([j]), "surface", pose)
    start = samples[np.argmin(other_distance(samples)[0])]
    point, gap, normal, patch = contact_patch(world, j, other_distance, start, world.slop,
                                              pose)
    near = gap <= reach
    if not near.any():
        return None
    return point[near], gap[near], normal[near], PATCH_FEATURE + patch[near]


def _shape_contacts(world, shapes, solids, margin, pose=None) -> list:
    plain = solids[world.kind[solids] != CONVEX]
    body, point, radius, feature = support_points(world, plain, "surface", pose)
    n, planes = world.count, len(world.plane_offset)
    parts = []
    for index, shape in enumerate(shapes):
        for j in solids[world.kind[solids] == CONVEX]:
            patch = _patch(world, j, _shape_distance(shape), margin[j], pose)
            if patch is not None:
                point_j, gap_j, normal_j, feature_j = patch
                count = len(gap_j)
                e, mu = shape.coefficients(point_j)
                parts.append(_part(
                    np.full(count, j), np.full(count, n), index, n + 1 + planes + index,
                    "convex-shape", feature_j, point_j, normal_j, gap_j,
                    np.maximum(world.restitution[j], e),
                    np.sqrt(world.friction[j] * np.asarray(mu, world.dtype)),
                    shape.surface_velocity(point_j.astype(world.dtype))))
        distance = np.asarray(shape.distance(point), world.dtype)
        near = np.flatnonzero(distance - radius <= margin[body])
        if len(near) == 0:
            continue
        d, normal = surface_near(shape, point[near], distance[near])
        rows = body[near]
        touch = point[near] - radius[near, None] * normal
        e, mu = shape.coefficients(touch)
        parts.append(_part(
            rows, np.full(len(rows), n), index, n + 1 + planes + index,
            np.char.add(_kind(world, rows), "-shape"), feature[near], touch, normal,
            d - radius[near], np.maximum(world.restitution[rows], e),
            np.sqrt(world.friction[rows] * np.asarray(mu, world.dtype)),
            shape.surface_velocity(touch)))
    return parts


def _shape_distance(shape):
    """``points -> (distance, normal)`` of a shape, in float64."""
    def distance(p):
        return (np.asarray(shape.distance(p), np.float64),
                np.asarray(shape_normals(shape, p), np.float64))
    return distance


def _body_contacts(world, solids, margin) -> list:
    """Contacts of each solid with the spheres and the later solids near it."""
    x, active = world.position, world.active
    reach = bounding_radius(world.kind, world.radius, world.extent)
    parts = []
    for s in solids:
        d = x - x[s]
        close = np.sqrt(dot(d, d)) <= reach + reach[s] + margin + margin[s]
        close &= active & ((world.kind == SPHERE) | (np.arange(world.count) > s))
        close[s] = False
        others = np.flatnonzero(close)
        if len(others) == 0:
            continue
        spheres = others[world.kind[others] == SPHERE]
        if len(spheres):
            parts.append(_sphere_solid(world, spheres, s, margin))
        for j in others[world.kind[others] != SPHERE]:
            parts.append(_solid_solid(world, s, j, margin[s] + margin[j]))
    return parts


def _coefficients(world, a, b):
    return (np.maximum(world.restitution[a], world.restitution[b]),
            np.sqrt(world.friction[a] * world.friction[b]))


def _sphere_solid(world, spheres, s, margin) -> dict:
    """Spheres (K,) against solid s: the sphere is a, the solid b."""
    x, dtype = world.position, world.dtype
    centre = x[spheres]
    if world.kind[s] == BOX:
        rotation = rotation_matrices(world.orientation[s:s + 1])[0]
        local = (centre - x[s]) @ rotation
        distance, gradient = box_distance(local, np.broadcast_to(world.extent[s], local.shape))
        normal = gradient @ rotation.T
    elif world.kind[s] == CONVEX:
        distance, normal = body_distance(world, s, centre)
    else:
        start, end = capsule_ends(x[s:s + 1], world.orientation[s:s + 1], world.extent[s:s + 1])
        start, end = np.repeat(start, len(spheres), 0), np.repeat(end, len(spheres), 0)
        t = segment_closest(start, end, centre)
        nearest = start + t[:, None] * (end - start)
        distance, normal = _apart(centre, nearest)
        distance = distance - world.radius[s]
    gap = (distance - world.radius[spheres]).astype(dtype)
    near = gap <= margin[spheres] + margin[s]
    rows, normal = spheres[near], normal[near].astype(dtype)
    e, mu = _coefficients(world, rows, s)
    return _part(rows, np.full(len(rows), s), s, s, "sphere-" + KIND_NAMES[world.kind[s]],
                 np.zeros(len(rows)), centre[near] - world.radius[rows, None] * normal, normal,
                 gap[near], e, mu)


def _apart(p, q):
    """|p - q| (K,) and the unit direction from q to p (K, 3), FALLBACK_NORMAL where p = q."""
    d = p - q
    distance = np.sqrt(dot(d, d))
    same = distance == 0
    normal = np.where(same[:, None], np.asarray(FALLBACK_NORMAL, p.dtype),
                      d / np.where(same, 1, distance)[:, None])
    return distance, normal


def _solid_solid(world, s, j, reach) -> dict:
    """Contacts of two solids, s before j in the world."""
    kinds = (int(world.kind[s]), int(world.kind[j]))
    if CONVEX in kinds:
        return _sampled_pair(world, s, j, reach)
    if kinds == (BOX, BOX):
        return _box_box(world, s, j, reach)
    if kinds == (CAPSULE, CAPSULE):
        return _capsule_capsule(world, s, j, reach)
    capsule, box = (s, j) if kinds[0] == CAPSULE else (j, s)
    return _capsule_box(world, capsule, box, reach)


def _sampled_pair(world, a, b, reach) -> dict:
    """Two bodies, one of them convex or both: a convex one's contact patch with the other
    (convex_contacts.py), the other's surface samples in its SDF. The normal is b's outward
    one at a's points, the reverse of a's at b's."""
    e, mu = _coefficients(world, a, b)
    chosen = []                      # (features, points, normals from b to a, gaps) batches
    for mine, other, sign, first in ((a, b, 1.0, 0), (b, a, -1.0, OTHER_SAMPLES)):
        def other_distance(p, other=other):
            return body_distance(world, other, p)
        if world.kind[mine] == CONVEX:
            patch = _patch(world, mine, other_distance, reach)
            if patch is not None:
                point, gap, normal, feature = patch
                chosen.append((feature + (mine == b) * PATCH_OTHER, point, sign * normal, gap))
            continue
        _, point, radius, feature = support_points(world, np.array([mine]), "surface")
        distance, normal = other_distance(point)
        # The point of the sample's surface nearest the other.
        chosen.append((first + feature, point - radius[:, None] * normal, sign * normal,
                       distance - radius))
    if not chosen:
        return _part([], [], b, b, "", [], np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                     e, mu)
    feature, point, normal, gap = (np.concatenate(column) for column in zip(*chosen))
    near = gap <= reach
    count = int(near.sum())
    kind = f"{KIND_NAMES[world.kind[a]]}-{KIND_NAMES[world.kind[b]]}"
    return _part(np.full(count, a), np.full(count, b), b, b, kind, feature[near],
                 point[near].astype(world.dtype), normal[near].astype(world.dtype),
                 gap[near].astype(world.dtype), e, mu)


def _box_box(world, a, b, reach) -> dict:
    x, q = world.position, world.orientation
    rotation = rotation_matrices(q[[a, b]])
    point, normal, gap, feature = box_box_contacts(x[a], rotation[0], world.extent[a], x[b],
                                                   rotation[1], world.extent[b], reach)
    e, mu = _coefficients(world, a, b)
    count = len(gap)
    return _part(np.full(count, a), np.full(count, b), b, b, "box-box", feature, point, normal,
                 gap, e, mu)


def box_distance_along(start, end, centre, rotation, half, t):
    """The box's signed distance (T,) and its gradient in the box's frame (T, 3) at the points
    start + t (end - start) of a segment, for t (T,); start, end (1, 3), the box's centre (3,),
    rotation (3, 3) and half sizes (3,)."""
    t = np.asarray(t, start.dtype)
    local = (start + t[:, None] * (end - start) - centre) @ rotation
    return box_distance(local, np.broadcast_to(half, local.shape))


def segment_nearest_box(start, end, centre, rotation, half):
    """The parameter t of the point of the segment start-end (each (1, 3)) nearest to a box,
    and how far (m) the point found may be from the true nearest one.

    The signed distance to a convex solid is convex, and so along a segment: the least of a
    few samples brackets the nearest point, and a ternary search narrows the bracket (each
    step keeps 2/3 of it). The distance is 1-Lipschitz, so the least distance along the
    segment is at least the distance at t less that bound.
    """
    scan = np.linspace(0, 1, SCAN_POINTS)
    best = int(np.argmin(box_distance_along(start, end, centre, rotation, half, scan)[0]))
    low, high = scan[max(best - 1, 0)], scan[min(best + 1, SCAN_POINTS - 1)]
    for _ in range(TERNARY_STEPS):
        third = (high - low) / 3
        pair = box_distance_along(start, end, centre, rotation, half,
                                  [low + third, high - third])[0]
        if pair[0] <= pair[1]:
            high = high - third
        else:
            low = low + third
    length = float(np.sqrt(np.sum((end - start) ** 2)))
    return 0.5 * (low + high), 0.5 * (high - low) * length


def _capsule_box(world, capsule, box, reach) -> dict:
    """The capsule's segment ends and its point nearest the box: the capsule is a."""
    x, dtype = world.position, world.dtype
    start, end = capsule_ends(x[capsule:capsule + 1], world.orientation[capsule:capsule + 1],
                              world.extent[capsule:capsule + 1])
    rotation = rotation_matrices(world.orientation[box:box + 1])[0]
    half = world.extent[box]
    middle, _ = segment_nearest_box(start, end, x[box], rotation, half)
    t = np.array([0.0, 1.0] + ([middle] if END_SKIP < middle < 1 - END_SKIP else []))
    d, gradient = box_distance_along(start, end, x[box], rotation, half, t)
    normal = (gradient @ rotation.T).astype(dtype)
    gap = (d - world.radius[capsule]).astype(dtype)
    near = gap <= reach
    point = start + t[:, None].astype(dtype) * (end - start) - world.radius[capsule] * normal
    e, mu = _coefficients(world, capsule, box)
    count = int(near.sum())
    return _part(np.full(count, capsule), np.full(count, box), box, box, "capsule-box",
                 np.flatnonzero(near), point[near], normal[near], gap[near], e, mu)


def _capsule_capsule(world, a, b, reach) -> dict:
    """Nearest points of the two segments, and each end against the other segment."""
    x, q, e3 = world.position, world.orientation, world.extent
    p1, q1 = capsule_ends(x[a:a + 1], q[a:a + 1], e3[a:a + 1])
    p2, q2 = capsule_ends(x[b:b + 1], q[b:b + 1], e3[b:b + 1])
    s, t = segments_closest(p1, q1, p2, q2)
    on_a = [p1 + s[:, None] * (q1 - p1), p1, q1]
    on_b = [p2 + t[:, None] * (q2 - p2)]
    for end in (p1, q1):
        on_b.append(p2 + segment_closest(p2, q2, end)[:, None] * (q2 - p2))
    for end in (p2, q2):
        on_a.append(p1 + segment_closest(p1, q1, end)[:, None] * (q1 - p1))
        on_b.append(end)
    pa, pb = np.concatenate(on_a), np.concatenate(on_b)
    distance, normal = _apart(pa, pb)
    gap = distance - world.radius[a] - world.radius[b]
    # Keep one contact per distinct point of a: the nearest points often are an end.
    size = max(float(e3[a, 1]), float(e3[b, 1]), float(world.radius[a]))
    keep = [k for k in range(len(pa)) if gap[k] <= reach and not any(
        np.sum((pa[k] - pa[m]) ** 2) <= (1e-6 * size) ** 2 and gap[m] <= reach
        for m in range(k))]
    e, mu = _coefficients(world, a, b)
    return _part(np.full(len(keep), a), np.full(len(keep), b), b, b, "capsule-capsule", keep,
                 pa[keep] - world.radius[a] * normal[keep], normal[keep], gap[keep], e, mu)
