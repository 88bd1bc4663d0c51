"""Reference distances for the SDF tests, derived from closest points, not from Quilez's formulas.

Each function finds the nearest point of a shape from its geometry (clamping to a box, the
nearest point of a circle or a segment, a 2-D cross-section for shapes of revolution) and
measures the distance to it; the sign says whether the point is inside. `first_roots` finds
where a field first meets 0 along rays by dense sampling, for the tests that a march never
skips a surface. Shared by tests/test_sdf_*.py and tests/hard_cases/ (``pythonpath =
["tests"]`` in pyproject.toml makes it importable).
"""

from __future__ import annotations

import numpy as np

EXACT = 1e-12   # float64: the formulas lose a few ulps of numbers of size ~10
SINGLE = 1e-5   # float32: ~100 ulps of numbers of size ~10 (float32 eps is 1.2e-7)


# --- Reference distances, from the nearest point of each shape ------------------------------------

def unit(v):
    """v : (..., k) scaled to unit length along the last axis."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def box_distance(p, half):
    """Signed distance to the box [-half, half] in any dimension; p : (N, k), half : (k,).

    Outside, the nearest point of the box is p clamped into it. Inside, the nearest surface
    point lies on the nearest face, at distance min(half - |p|).
    """
    nearest = np.clip(p, -half, half)
    outside = np.linalg.norm(p - nearest, axis=-1)
    to_nearest_face = np.min(half - np.abs(p), axis=-1)
    is_inside = np.all(np.abs(p) <= half, axis=-1)
    return np.where(is_inside, -to_nearest_face, outside)


def sphere_distance(p, radius):
    """The nearest point of the sphere is radius * p / |p|; negative inside."""
    nearest = radius * unit(p)
    sign = np.where(np.linalg.norm(p, axis=-1) < radius, -1.0, 1.0)
    return sign * np.linalg.norm(p - nearest, axis=-1)


def plane_frame(normal):
    """An orthonormal frame (t1, t2, n) whose last vector is the unit normal; (3, 3) rows."""
    n = unit(np.asarray(normal, dtype=np.float64))
    # QR of a matrix whose first column is n gives two further orthonormal columns.
    q, _ = np.linalg.qr(np.column_stack([n, np.eye(3)[:, :2]]))
    return np.array([q[:, 1], q[:, 2], n])


def plane_distance(p, normal, offset):
    """Coordinate of p along the unit normal, measured from the plane's point offset * n."""
    frame = plane_frame(normal)
    return (p - offset * frame[2]) @ frame[2]


def azimuth_frame(p):
    """Distance from the y axis and the unit radial direction in the xz-plane; p : (N, 3)."""
    rho = np.hypot(p[:, 0], p[:, 2])
    radial = np.column_stack([p[:, 0], np.zeros(len(p)), p[:, 2]]) / rho[:, None]
    return rho, radial


def torus_distance(p, major, minor):
    """Distance to the nearest point of the centre circle (radius ``major`` in the xz-plane), minus
    the tube radius."""
    _, radial = azimuth_frame(p)
    nearest_on_circle = major * radial
    return np.linalg.norm(p - nearest_on_circle, axis=-1) - minor


def capped_cylinder_distance(p, radius, half_height):
    """In the (rho, y) half-plane the cylinder is the rectangle [0, R] x [-h, h]; measuring to
    [-R, R] x [-h, h] instead keeps the axis rho = 0 from counting as a boundary."""
    rho, _ = azimuth_frame(p)
    return box_distance(np.column_stack([rho, p[:, 1]]), np.array([radius, half_height]))


def capsule_distance_brute_force(p, a, b, radius, samples=20001):
    """Distance to the nearest of ``samples`` evenly spaced points of the segment a-b, minus r.

    The true nearest point of the segment is within half a spacing, |b - a| / (2 (samples - 1)),
    of a sample, so this overestimates the exact distance by at most that step, never less.
    """
    segment = a + np.linspace(0.0, 1.0, samples)[:, None] * (b - a)
    nearest_squared = np.empty(len(p))
    for start in range(0, len(p), 64):                     # (64, samples, 3) at a time
        offsets = p[start:start + 64, None, :] - segment[None, :, :]
        nearest_squared[start:start + 64] = np.einsum("nsk,nsk->ns", offsets, offsets).min(axis=1)
    return np.sqrt(nearest_squared) - radius


def capsule_sampling_step(a, b, samples=20001):
    return np.linalg.norm(np.subtract(b, a)) / (2 * (samples - 1))


def segment_distance_2d(p, a, b):
    """Distance from points p : (N, 2) to the segment a-b, by clamped projection (Ericson,
    Real-Time Collision Detection, section 5.1.2)."""
    ab = b - a
    t = np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=-1)


def cone_distance(p, radius, height):
    """In the (rho, y) half-plane the cone is the triangle (0, 0), (R, 0), (0, H).

    Its boundary there is the base [(0,0), (R,0)] and the slant [(R,0), (0,H)]; the edge on the
    axis is not a surface of the solid. Inside: above the base and below the slant line
    rho / R + y / H = 1.
    """
    rho, _ = azimuth_frame(p)
    q = np.column_stack([rho, p[:, 1]])
    origin, rim, apex = np.array([0.0, 0.0]), np.array([radius, 0.0]), np.array([0.0, height])
    distance = np.minimum(segment_distance_2d(q, origin, rim), segment_distance_2d(q, rim, apex))
    is_inside = (q[:, 1] >= 0) & (q[:, 0] / radius + q[:, 1] / height <= 1)
    return np.where(is_inside, -distance, distance)


def disk_distance(p, radius, thickness):
    """The nearest point of the flat circle of radius a = radius - thickness / 2 in y = 0 is p's
    foot (x, 0, z), pulled in to the rim if it lies outside; the disk is everything within
    thickness / 2 of that circle."""
    a, rounding = radius - thickness / 2, thickness / 2
    rho, radial = azimuth_frame(p)
    foot = np.column_stack([p[:, 0], np.zeros(len(p)), p[:, 2]])
    rim = a * np.nan_to_num(radial)                      # rho = 0: the centre is the foot
    nearest = np.where((rho <= a)[:, None], foot, rim)
    return np.linalg.norm(p - nearest, axis=-1) - rounding


# --- Convex polyhedra as triangle meshes -----------------------------------------------------

def triangle_closest_points(p, a, b, c):
    """The nearest point of the triangle abc (each (3,)) to each of the points p : (N, 3).

    Ericson, Real-Time Collision Detection, section 5.1.5 (ClosestPtPointTriangle): the
    Voronoi regions of the vertices, then of the edges, then the face, tested in that order.
    Vectorised, every region's answer is computed and the first region that holds wins (they
    are assigned in reverse order, so an earlier region overwrites a later one).
    """
    ab, ac = b - a, c - a
    ap, bp, cp = p - a, p - b, p - c
    d1, d2 = ap @ ab, ap @ ac
    d3, d4 = bp @ ab, bp @ ac
    d5, d6 = cp @ ab, cp @ ac
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denominator = va + vb + vc
        regions = [   # (holds, nearest point), Ericson's order
            ((d1 <= 0) & (d2 <= 0), np.broadcast_to(a, p.shape)),
            ((d3 >= 0) & (d4 <= d3), np.broadcast_to(b, p.shape)),
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + (d1 / (d1 - d3))[:, None] * ab),
            ((d6 >= 0) & (d5 <= d6), np.broadcast_to(c, p.shape)),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + (d2 / (d2 - d6))[:, None] * ac),
            ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),
             b + ((d4 - d3) / ((d4 - d3) + (d5 - d6)))[:, None] * (c - b)),
        ]
        nearest = a + (vb / denominator)[:, None] * ab + (vc / denominator)[:, None] * ac
    for holds, point in reversed(regions):
        nearest = np.where(holds[:, None], point, nearest)
    return nearest


def convex_polyhedron_distance(p, vertices, faces):
    """Signed distance to a convex polyhedron given as a closed triangle mesh.

    The nearest point of the surface is the nearest of the triangles' nearest points; p is
    inside where it lies behind the plane of every face (each face's normal turned away from
    the centroid of the vertices, which a convex solid holds).
    """
    centre = vertices.mean(axis=0)
    nearest = np.full(len(p), np.inf)
    inside = np.ones(len(p), dtype=bool)
    for i, j, k in faces:
        a, b, c = vertices[i], vertices[j], vertices[k]
        nearest = np.minimum(nearest, np.linalg.norm(p - triangle_closest_points(p, a, b, c),
                                                     axis=-1))
        normal = np.cross(b - a, c - a)
        normal = -normal if (centre - a) @ normal > 0 else normal
        inside &= (p - a) @ normal <= 0
    return np.where(inside, -nearest, nearest)


def pyramid_mesh(base, height):
    """Vertices (5, 3) and triangles (6, 3): the base square's corners at y = 0, the apex."""
    s = base / 2
    vertices = np.array([[s, 0, s], [-s, 0, s], [-s, 0, -s], [s, 0, -s], [0, height, 0]])
    faces = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 1, 2], [0, 2, 3]])
    return vertices, faces


def hex_prism_mesh(apothem, half_length):
    """Vertices (12, 3) and triangles (20, 3) of the prism along z whose regular hexagon has
    its corners at 2 apothem / sqrt(3) from the axis, at 0, 60, ..., 300 degrees from +x
    (so its flat sides lie at y = +-apothem)."""
    corner = 2 * apothem / np.sqrt(3)
    angles = np.radians(np.arange(0, 360, 60))
    ring = np.column_stack([corner * np.cos(angles), corner * np.sin(angles)])
    vertices = np.vstack([np.column_stack([ring, np.full(6, z)])
                          for z in (-half_length, half_length)])
    caps = [[top + 0, top + k, top + k + 1] for top in (0, 6) for k in range(1, 5)]
    sides = [[k, (k + 1) % 6, 6 + k] for k in range(6)] + [[(k + 1) % 6, 6 + (k + 1) % 6, 6 + k]
                                                          for k in range(6)]
    return vertices, np.array(caps + sides)


def pyramid_distance(p, base, height):
    return convex_polyhedron_distance(p, *pyramid_mesh(base, height))


def hex_prism_distance(p, apothem, half_length):
    return convex_polyhedron_distance(p, *hex_prism_mesh(apothem, half_length))


# --- Roots along rays, for the tests that a march never skips a surface --------------------

def first_roots(f, origins, directions, reach, samples):
    """The first root of a field along each ray, and the least value sampled along it.

    ``f(p)`` for ``p : (N, 3)`` returns ``(distance (N,), ...)``; the rays o + t d (origins and
    directions (M, 3) float64) are sampled at ``samples + 1`` values of t from 0 to ``reach``
    and the first interval whose far end is inside (f <= 0) is bisected 50 times. A 1-Lipschitz
    field dips at most reach / (2 samples) below its sampled values between two samples, so
    outside that band of the least value a ray has a root iff a sample is inside.

    Returns
    -------
    root : (M,) ndarray
        t of the first root, inf where the samples found none.
    lowest : (M,) ndarray
        The least sampled value of each ray.
    """
    t = np.linspace(0, reach, samples + 1)
    values = np.empty((len(origins), len(t)))
    for chunk in np.array_split(np.arange(len(t)), max(1, len(t) // 100)):
        points = origins[:, None, :] + t[None, chunk, None] * directions[:, None, :]
        # stored column by column, as the march stores points: the SDF runs faster so
        values[:, chunk] = f(np.asfortranarray(points.reshape(-1, 3)))[0].reshape(
            len(origins), -1)
    inside = values <= 0
    has_root = inside.any(axis=1)
    first = np.argmax(inside, axis=1)
    lo, hi = t[np.maximum(first - 1, 0)], t[first]
    for _ in range(50):
        mid = (lo + hi) / 2
        outside = f(origins + mid[:, None] * directions)[0] > 0
        lo, hi = np.where(outside, mid, lo), np.where(outside, hi, mid)
    return np.where(has_root, hi, np.inf), values.min(axis=1)
