"""Where two oriented boxes touch: the separating axis theorem, then face clipping.

Separating axes. Two convex shapes are apart if and only if there is a line onto which their
shadows (projections) do not overlap. For two boxes only 15 lines need trying (Gottschalk, Lin
and Manocha, "OBBTree: a hierarchical structure for rapid interference detection", SIGGRAPH
1996): the 3 face normals of each box and the 9 cross products of an edge direction of one with
an edge direction of the other. Along a unit axis L, with d = c_a - c_b,

    separation(L) = |d . L| - (r_a(L) + r_b(L)),      r(L) = sum_k h_k |e_k . L|,

where r(L) is the half length of a box's shadow (e_k its axes, h_k its half extents). When the
boxes overlap, the largest of the 15 separations is minus the penetration depth and its axis
is the shortest way to push them apart: the 15 axes are the face normals of the Minkowski
difference of the two boxes, and the point of its surface nearest the origin lies on a face.

Faces before edges. The axis decides the kind of contact. On a face axis a face of one box
(the reference face) is pressed by the face of the other that is turned most against it (the
incident face). The incident face's 4 corners are a polygon; cutting away the parts outside the
4 side planes of the reference face (Sutherland and Hodgman, "Reentrant polygon clipping", CACM
1974) leaves up to 8 points, each a contact with its own depth. This is Erin Catto's scheme
(Box2D-Lite, and "Contact manifolds", GDC 2007); ODE's dBoxBox does the same in 3-D. A box lying
flat gets 4 points and stays flat, where one point would let it rock. On an edge axis two edges
cross; they get one contact, at their closest points. A resting box has several axes of almost
equal separation; following the largest exactly would let rounding flip the choice, and the
whole manifold, from one step to the next. So b's face axis is taken over a's, and an edge axis
over the best face axis, only when its separation is larger by

    margin(s) = 0.05 |s| + 0.01 h_min        (s: the separation it must beat, h_min: the
                                              smallest half extent of the two boxes)

These are Box2D-Lite's relative and absolute tolerances. Box2D-Lite writes s_b > 0.95 s_a +
0.01 h, which is right for a penetration (s_a < 0); for a speculative contact (s_a > 0) 0.95 s_a
would lower the bar below s_a itself, hence |s| here. The price: the preferred face may miss
the deepest point by up to that margin, and, rarely, keep no point at all over the reference
face; then the deepest axis is taken after all, which always keeps one for overlapping boxes.

Clipping a corner that lies exactly on a side plane, with its edge leaving through it (boxes
that touch along a line), would add a crossing on top of the corner. Corners within a tolerance
of a plane (1e-9 of the box size) therefore count as on it and make no crossing, and points
closer than it are merged. A quadrilateral cut by 4 planes keeps at most 8 points, few enough
for a solver, so the manifold is not reduced to 4 as some engines do.

Features. A solver that starts each step from the last step's impulses (warm starting; Catto,
"Iterative dynamics with temporal coherence", GDC 2005) must know which new contact is which
old one. Each contact gets a number built from what produced it, which stays the same while the
boxes move a little::

    face contact:  ((box * 6 + reference face) * 6 + incident face) * 24 + point
                   box 0 when a holds the reference face, 1 when b does; face 2k (+e_k) or
                   2k + 1 (-e_k); point 0-3 an incident corner, 4 + 4 e + p the crossing of
                   incident edge e (corner e to e + 1) with side plane p, 20 + c a corner of
                   the reference face, seen through the incident face. On incident face j the
                   corners 0-3 are at (+, +), (-, +), (-, -), (+, -) along the axes (j + 1) % 3,
                   (j + 2) % 3; on reference face i side planes 0, 1 bound +-e_u and 2, 3 bound
                   +-e_v, u = (i + 1) % 3, v = (i + 2) % 3; corner c = 2 (u plane) + (v plane - 2)
    edge contact:  EDGE_FEATURE_BASE + 12 * (edge of a) + (edge of b)    (see box_edges)
"""

from __future__ import annotations

import numpy as np

from physics.solids import segments_closest

RELATIVE_TOLERANCE = 0.05     # face preference: fraction of |separation| ...
ABSOLUTE_TOLERANCE = 0.01     # ... plus this fraction of the smallest half extent
PARALLEL_TOLERANCE = 1e-6     # |e_a x e_b| below this: parallel edges, no edge axis
FACE_POINT_CODES = 24         # 4 incident corners, 16 (edge, side plane), 4 reference corners
EDGE_FEATURE_BASE = 2 * 6 * 6 * FACE_POINT_CODES


def box_corners(centre, rotation, half) -> np.ndarray:
    """The 8 corners (8, 3) of a box, in world coordinates (m).

    Corner c is at local coordinate +h_k along axis k where bit k of c is set, -h_k where not.
    ``rotation`` (3, 3) has the box's local axes as columns; ``centre``, ``half`` are (3,).
    """
    bits = (np.arange(8)[:, None] >> np.arange(3)) & 1
    local = np.where(bits == 1, half, -half)
    return centre + local @ rotation.T


def box_edges(centre, rotation, half) -> np.ndarray:
    """The 12 edges of a box (arrays as in box_corners) as segments (12, 2, 3): start and end in
    world coordinates (m).

    Edge 4 k + q runs along local axis k, from -h_k to +h_k. Bit 0 of q says on which side of
    axis (k + 1) % 3 it lies (set: +h), bit 1 the same for axis (k + 2) % 3.
    """
    edges = np.empty((12, 2, 3), dtype=centre.dtype)
    for k in range(3):
        for q in range(4):
            local = np.zeros(3, dtype=centre.dtype)
            for bit, other in ((1, (k + 1) % 3), (2, (k + 2) % 3)):
                local[other] = half[other] if q & bit else -half[other]
            middle = centre + rotation @ local
            edges[4 * k + q] = middle - half[k] * rotation[:, k], middle + half[k] * rotation[:, k]
    return edges


def candidate_axes(rotation_a, rotation_b):
    """The 15 candidate separating axes of two boxes.

    Returns
    -------
    axes : (15, 3)
        Unit axes: rows 0-2 a's local axes, 3-5 b's, 6 + 3 i + j the normalised a_i x b_j.
        Rows of near-parallel edge pairs are zero: their cross product has no reliable
        direction, and the face axes already cover that case.
    usable : (15,) bool
        False for those zero rows.
    """
    crossed = np.cross(rotation_a.T[:, None, :], rotation_b.T[None, :, :]).reshape(9, 3)
    length = np.sqrt(np.sum(crossed * crossed, axis=1))
    usable = length > PARALLEL_TOLERANCE
    crossed = crossed * (usable / np.where(usable, length, 1))[:, None].astype(crossed.dtype)
    axes = np.concatenate([rotation_a.T, rotation_b.T, crossed])
    return axes, np.concatenate([np.ones(6, dtype=bool), usable])


def separations(axes, centre_a, rotation_a, half_a, centre_b, rotation_b, half_b) -> np.ndarray:
    """|d . L| - (r_a(L) + r_b(L)) (M,) for unit axes L (M, 3): the gap between the boxes'
    shadows on each axis (m), negative where the shadows overlap (see module docstring)."""
    radius_a = np.abs(axes @ rotation_a) @ half_a        # (axes @ R)[m, k] = L_m . e_k
    radius_b = np.abs(axes @ rotation_b) @ half_b
    return np.abs(axes @ (centre_a - centre_b)) - (radius_a + radius_b)


def largest_separation(centre_a, rotation_a, half_a, centre_b, rotation_b, half_b):
    """The largest of the 15 separations (K,) of K pairs of boxes at once (m): `candidate_axes`
    and `separations` on stacks of K pairs ((K, 3) centres and half sizes, (K, 3, 3)
    rotations), the near-parallel edge axes left out. Positive exactly when the boxes are
    apart (the separating axis theorem), and never more than their distance: a shadow is
    never farther from another than the boxes are. What a swept test advances by
    (solid_sweeps.py); tests/physics/test_solid_sweeps.py checks it against the two."""
    axes_a, axes_b = np.swapaxes(rotation_a, 1, 2), np.swapaxes(rotation_b, 1, 2)
    crossed = np.cross(axes_a[:, :, None, :], axes_b[:, None, :, :]).reshape(-1, 9, 3)
    length = np.sqrt(np.sum(crossed * crossed, axis=2))
    usable = length > PARALLEL_TOLERANCE
    crossed = crossed * (usable / np.where(usable, length, 1))[:, :, None].astype(crossed.dtype)
    axes = np.concatenate([axes_a, axes_b, crossed], axis=1)                 # (K, 15, 3)
    radius_a = np.sum(np.abs(axes @ rotation_a) * half_a[:, None, :], axis=2)
    radius_b = np.sum(np.abs(axes @ rotation_b) * half_b[:, None, :], axis=2)
    apart = np.abs(np.einsum("kmj,kj->km", axes, centre_a - centre_b)) - (radius_a + radius_b)
    usable = np.concatenate([np.ones((len(axes), 6), bool), usable], axis=1)
    return np.max(np.where(usable, apart, -np.inf), axis=1)


def choose_axis(separation, usable, absolute, relative=RELATIVE_TOLERANCE) -> int:
    """The axis (index into ``candidate_axes``) whose contact is built: a's best face axis,
    unless b's, and then an edge axis, beats it by margin(s) = relative |s| + absolute (m)."""
    def margin(s):
        return relative * abs(s) + absolute

    best = int(np.argmax(separation[0:3]))
    face_b = 3 + int(np.argmax(separation[3:6]))
    if separation[face_b] > separation[best] + margin(separation[best]):
        best = face_b
    if usable[6:].any():
        edge = 6 + int(np.argmax(np.where(usable[6:], separation[6:], -np.inf)))
        if separation[edge] > separation[best] + margin(separation[best]):
            best = edge
    return best


def clip_polygon(points, codes, labels, plane_normal, plane_offset, plane, tolerance):
    """Sutherland-Hodgman: the part of a convex polygon where plane_normal . p <= plane_offset.

    Each vertex carries a feature code and the label of the polygon edge that leaves it:
    0-3 an edge of the incident face, 4 + p a side plane p that cut the polygon earlier. A new
    vertex where an edge crosses side plane ``plane`` gets code 4 + 4 e + plane on incident
    edge e, or 20 + (reference corner) on an earlier side plane. Vertices within ``tolerance``
    (m) of the plane count as on it and make no new vertex, so an edge that leaves through a
    corner lying on the plane does not add a second copy of that corner.

    points : (P, 3), codes : (P,), labels : (P,) -> the same for the clipped polygon.
    """
    distance = points @ plane_normal - plane_offset
    kept_points, kept_codes, kept_labels = [], [], []

    def crossing(i, j):
        t = distance[i] / (distance[i] - distance[j])
        label = labels[i]
        if label < 4:
            code = 4 + 4 * label + plane
        else:                       # two side planes meet: u planes are 0, 1; v planes 2, 3
            first, second = sorted((label - 4, plane))
            code = 20 + 2 * first + (second - 2)
        return points[i] + t * (points[j] - points[i]), code

    for i in range(len(points)):
        j = (i + 1) % len(points)
        if distance[i] <= tolerance:                         # this vertex is kept
            leaves = distance[j] > tolerance
            if leaves and distance[i] >= -tolerance:         # leaves right at this vertex
                kept_points.append(points[i]), kept_codes.append(codes[i])
                kept_labels.append(4 + plane)
                continue
            kept_points.append(points[i]), kept_codes.append(codes[i])
            kept_labels.append(labels[i])
            if leaves:                                       # leaves between i and j
                point, code = crossing(i, j)
                kept_points.append(point), kept_codes.append(code), kept_labels.append(4 + plane)
        elif distance[j] < -tolerance:                       # enters between i and j
            point, code = crossing(i, j)
            kept_points.append(point), kept_codes.append(code), kept_labels.append(labels[i])
    return (np.array(kept_points, dtype=points.dtype).reshape(-1, 3),
            np.array(kept_codes, dtype=np.int64), np.array(kept_labels, dtype=np.int64))


def _face_contacts(axis, boxes, reach, tolerance):
    """Clip the incident face against the reference face on face axis 0-5 (see module)."""
    owner = axis // 3                                   # 0: a holds the reference face
    i = axis % 3
    centre_r, rotation_r, half_r = boxes[owner]
    centre_i, rotation_i, half_i = boxes[1 - owner]
    # The reference face is the one facing the other box (+e_i if the centres tie).
    sign = 1 if (centre_i - centre_r) @ rotation_r[:, i] >= 0 else -1
    n = sign * rotation_r[:, i]
    face_point = centre_r + half_r[i] * n
    reference_face = 2 * i + (0 if sign > 0 else 1)
    # The incident face is the one whose outward normal is most anti-parallel to n.
    along = n @ rotation_i
    j = int(np.argmax(np.abs(along)))
    incident_sign = -1 if along[j] > 0 else 1
    incident_face = 2 * j + (0 if incident_sign > 0 else 1)
    k, m = (j + 1) % 3, (j + 2) % 3
    middle = centre_i + incident_sign * half_i[j] * rotation_i[:, j]
    signs = [(1, 1), (-1, 1), (-1, -1), (1, -1)]         # in order around the face
    polygon = np.array([middle + s * half_i[k] * rotation_i[:, k] + t * half_i[m] * rotation_i[:, m]
                        for s, t in signs])
    codes, labels = np.arange(4), np.arange(4)          # edge e runs from corner e to e + 1
    # Side planes 0, 1: +-e_u; 2, 3: +-e_v, each h from the reference face's centre line.
    for plane in range(4):
        u = (i + 1 + plane // 2) % 3
        outward = (1 if plane % 2 == 0 else -1) * rotation_r[:, u]
        offset = outward @ centre_r + half_r[u]
        polygon, codes, labels = clip_polygon(polygon, codes, labels, outward, offset, plane,
                                              tolerance)
    # A corner just inside a plane, by more than the tolerance but less than rounding can
    # resolve, and the crossing next to it can still nearly coincide: keep the first of them.
    unique = [p for p in range(len(polygon))
              if all(np.max(np.abs(polygon[p] - polygon[q])) > tolerance for q in range(p))]
    polygon, codes = polygon[unique], codes[unique]
    depth = (polygon - face_point) @ n
    near = depth < reach
    points = polygon[near] - 0.5 * depth[near][:, None] * n
    normal = n if owner == 1 else -n                    # always from b toward a
    features = ((owner * 6 + reference_face) * 6 + incident_face) * FACE_POINT_CODES + codes[near]
    return points, np.tile(normal, (len(points), 1)), depth[near], features


def _edge_contact(axis_index, axis, separation, boxes):
    """One contact between the supporting edges of a and b on edge axis 6-14."""
    (centre_a, rotation_a, half_a), (centre_b, rotation_b, half_b) = boxes
    i, j = divmod(axis_index - 6, 3)
    normal = axis if axis @ (centre_a - centre_b) >= 0 else -axis       # from b toward a
    # a's edge along e_i lowest along the normal (nearest b); b's edge along e_j highest.
    low = normal @ rotation_a < 0
    high = normal @ rotation_b > 0
    edge_a = 4 * i + int(low[(i + 1) % 3]) + 2 * int(low[(i + 2) % 3])
    edge_b = 4 * j + int(high[(j + 1) % 3]) + 2 * int(high[(j + 2) % 3])
    segment_a = box_edges(centre_a, rotation_a, half_a)[edge_a]
    segment_b = box_edges(centre_b, rotation_b, half_b)[edge_b]
    # The nearest points of the two edges (Ericson, Real-Time Collision Detection, 5.1.9).
    (start_a, end_a), (start_b, end_b) = segment_a, segment_b
    s, t = segments_closest(start_a[None], end_a[None], start_b[None], end_b[None])
    on_a = start_a + s[0] * (end_a - start_a)
    on_b = start_b + t[0] * (end_b - start_b)
    return (((on_a + on_b) / 2)[None, :], normal[None, :],
            np.array([separation], dtype=axis.dtype),
            np.array([EDGE_FEATURE_BASE + 12 * edge_a + edge_b], dtype=np.int64))


def box_box_contacts(centre_a, rotation_a, half_a, centre_b, rotation_b, half_b, reach):
    """The contact manifold of two oriented boxes (separating axes, then face clipping).

    Parameters
    ----------
    centre_a, centre_b : (3,)
        World centres (m).
    rotation_a, rotation_b : (3, 3)
        Rotation matrices whose columns are the box's local x, y, z axes in world coordinates
        (world = R @ local).
    half_a, half_b : (3,)
        Half extents (m), > 0.
    reach : float
        >= 0 (m). Contacts whose separation is below ``reach`` are reported: a solver uses a
        small positive reach for speculative contacts. Boxes apart by less than ``reach`` can
        still get none when no part of the incident face lies within reach of the reference
        face (corner near corner).

    Returns
    -------
    points : (K, 3)
        World contact points, midway between the two surfaces along the normal (m).
    normals : (K, 3)
        Unit normals from b toward a (the way a must move to separate); one row repeated.
    gaps : (K,)
        Signed separation along the normal (m), negative for penetration.
    features : (K,) int64
        Ids that name each contact from step to step (see module docstring), distinct.

    K is 0 when the boxes are apart by ``reach`` or more on some axis; at most 8. Computed in
    the floating dtype of ``centre_a``.
    """
    dtype = np.result_type(np.asarray(centre_a).dtype, np.float32)
    boxes = [tuple(np.asarray(x, dtype=dtype) for x in box)
             for box in ((centre_a, rotation_a, half_a), (centre_b, rotation_b, half_b))]
    axes, usable = candidate_axes(boxes[0][1], boxes[1][1])
    separation = np.where(usable, separations(axes, *boxes[0], *boxes[1]), -np.inf)
    if np.max(separation) >= reach:
        return (np.zeros((0, 3), dtype), np.zeros((0, 3), dtype), np.zeros(0, dtype),
                np.zeros(0, np.int64))
    halves = np.concatenate([boxes[0][2], boxes[1][2]])
    # On-plane and duplicate tolerance: 1e-9 of the box size, or rounding in float32.
    tolerance = max(1e-9, 64 * float(np.finfo(dtype).eps)) * float(np.max(halves))

    def contacts_on(best):
        if best < 6:
            return _face_contacts(best, boxes, reach, tolerance)
        return _edge_contact(best, axes[best], separation[best], boxes)

    smallest = float(np.min(halves))
    contacts = contacts_on(choose_axis(separation, usable, ABSOLUTE_TOLERANCE * smallest))
    if len(contacts[0]) == 0:
        # The preferred face, taken over a slightly deeper axis, can have all of its incident
        # face that lies over the reference face cut away. The deepest axis cannot when the
        # boxes overlap: the origin's nearest point on the Minkowski difference lies inside one
        # of its faces. So choose again with no preference beyond rounding (faces still first
        # among equals: an edge axis can repeat a face axis exactly).
        contacts = contacts_on(choose_axis(separation, usable, tolerance, relative=0))
    points, normals, gaps, features = contacts
    return (points.astype(dtype, copy=False), normals.astype(dtype, copy=False),
            gaps.astype(dtype, copy=False), features.astype(np.int64, copy=False))
