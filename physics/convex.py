"""Bodies of any convex shape, given by their signed distance: mass, inertia, surface points.

A box and a capsule have closed forms (solids.py). A cylinder, a cone, a rounded box or the
intersection of a few primitives does not need one: its SDF says everything the step needs.

**Mass and inertia by integration.** A grid of cells covers the solid; a cell whose centre
lies at signed distance d counts with the fraction f = clip(1/2 - d/w, 0, 1) of its volume,
w being the cell's width along the surface's normal (a plane at distance d from the centre
of a cube of side h cuts off about that share, exactly on average; it makes the sums
second-order accurate where counting whole cells is first-order). Then, for uniform density
(any mechanics text, e.g. Goldstein, Classical Mechanics, 3rd ed., 5.3), with dV a cell's
volume::

    V = sum f dV,     c = sum f x dV / V,
    J = sum f (|r|^2 1 - r r^T) dV / V + (the cell's own)     (r = x - c; per unit mass)

the last term being each cell's own inertia (a box's m (h_j^2 + h_k^2) / 12 about axis i).
J's eigenvectors are the principal axes: the body's own frame is the one with its origin at
c and its axes along them, so that its inertia is diagonal there, as the step needs
(solids.free_rotation), and J's eigenvalues are the `gyration` (I / m, m^2) about them. A
first pass over the box it is given finds the axes; a second, over the tightest box along
them, gives the answer: a rod or a plate then has `GRID_CELLS` cells across its thinnest
side too (a rod of radius 0.02 m and length 1 m: volume within 3e-5, moments within 4e-4,
where one pass over its bounding cube was 5% and 26% out).

**Surface samples** (`ConvexSolid.samples`): where the surface meets what it touches is
found from points of it, as for a box (Guendelman, Bridson and Fedkiw, "Nonconvex rigid
bodies with stacking", SIGGRAPH 2003). A point far away in each of `SAMPLE_DIRECTIONS`
directions (a Fibonacci sphere) and the 26 directions of a cube's corners, edges and faces
is moved to the surface point nearest it, p - d(p) grad d(p) (exact in one step for an exact
SDF: Hart, "Sphere tracing", 1996, section 2; repeated for a bound). Every direction of a
corner's normal cone lands on the corner, so corners and edges, where a solid meets a floor
first, are always among the samples; points that land on the same spot count once.

**Support points** (`support`): the surface point farthest along a direction u, where a
convex body first meets a plane of normal -u. The nearest surface point to s + D u is s
exactly when the surface's normal at s is u, which is the support point; so s is moved to
the surface point nearest s + D u until it stops (a contraction by rho / (rho + D) on a
surface of curvature radius rho, so D = `SUPPORT_REACH` radii gains a factor of 17 or more a
move). On a face nearly square to u a move only slides s along it by D times the angle
between them, so D doubles while s keeps moving. So a cylinder rolls on its side
as smoothly as a ball, with no bumps from the spacing of its samples.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from physics.errors import PhysicsError

GRID_CELLS = 96             # cells along each side of the box the integration covers
SAMPLE_DIRECTIONS = 160     # Fibonacci directions whose nearest surface points are samples
PROJECTION_STEPS = 32       # at most this many p - d grad d moves to reach the surface
SUPPORT_STEPS = 40          # moves of a support point toward its direction, at most
SUPPORT_REACH = 16          # ... the first from a point this many radii out along it,
MAX_SUPPORT_REACH = 4096    # ... each later one twice as far while it still moves, to this
# ... until what it could still gain along its direction is below this fraction of the radius
# r (see `support_of`).
SUPPORT_TOLERANCE = 1e-6
SURFACE_TOLERANCE = 1e-10   # |d| below this fraction of the size: on the surface
SAME_SAMPLE = 1e-6          # samples closer than this fraction of the size are one


@dataclass(frozen=True)
class ConvexSolid:
    """A convex solid in its own frame: origin at its centre of mass, axes its principal axes.

    Attributes
    ----------
    name : str
        What error messages call it (the scene's path to the body).
    distance : callable
        ``distance(p)`` for points p (K, 3) of the body's own frame returns the signed
        distance (K,) in m, negative inside.
    normal : callable
        ``normal(p)`` (K, 3) -> (K, 3): the unit gradient of ``distance``.
    samples : (P, 3) ndarray
        Points of the surface, own frame (m).
    volume : float
        m^3.
    gyration : (3,) ndarray
        Principal moments of inertia per unit mass, I / m (m^2), about the own axes.
    centroid : (3,) ndarray
        The centre of mass in the frame the solid was given in (m).
    axes : (3, 3) ndarray
        Columns: the own axes in that frame (a rotation): a given point u is the own point
        axes^T (u - centroid).
    radius : float
        A sphere about the centre of mass of this radius holds the solid (m).
    """
    name: str
    distance: Callable[[np.ndarray], np.ndarray]
    normal: Callable[[np.ndarray], np.ndarray]
    samples: np.ndarray
    volume: float
    gyration: np.ndarray
    centroid: np.ndarray
    axes: np.ndarray
    radius: float

    @property
    def extent(self) -> np.ndarray:
        """Half sizes (3,) of the box about the centre that holds the samples (m)."""
        return np.max(np.abs(self.samples), axis=0)


def grid_moments(distance, normal, low, high, cells: int = GRID_CELLS):
    """Volume (m^3), centre of mass (3,), inertia per unit mass about it (3, 3) (m^2), and the
    radius of a sphere about the centre that holds the solid (m), integrated over a grid of
    ``cells`` cells along each side of the box (low, high) (module docstring).

    The cells may be longer along one axis than another (a rod's box): a cell's share inside
    then ramps over its width along the surface's normal n, sum |n_i| h_i, the extent of a box
    of sides h_i along n.
    """
    low, high = np.asarray(low, np.float64), np.asarray(high, np.float64)
    h = (high - low) / cells
    # One cell more than the box on every side, so the surface's ramp is never cut off.
    axes = [a - s + s * (np.arange(cells + 3) + 0.5) for a, s in zip(low, h)]
    x = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    d = np.asarray(distance(x), np.float64)
    widest = float(np.sum(h))
    fraction = (d < 0).astype(np.float64)
    near = np.flatnonzero(np.abs(d) < widest)
    width = np.abs(np.asarray(normal(x[near]), np.float64)) @ h
    width = np.where(width > 0, width, widest)
    fraction[near] = np.clip(0.5 - d[near] / width, 0, 1)
    inside = fraction > 0
    x, fraction = x[inside], fraction[inside]
    weight = fraction.sum()
    if not weight > 0:
        raise PhysicsError("the solid has no volume")
    centroid = fraction @ x / weight
    r = x - centroid
    square = np.sum(r * r, axis=1)
    # Each cell's own inertia: a box's m (h_j^2 + h_k^2) / 12 about axis i.
    own = np.diag((np.sum(h * h) - h * h) / 12)
    inertia = (np.eye(3) * (fraction @ square) - np.einsum("k,ki,kj->ij", fraction, r, r)
               ) / weight + own
    reach = float(np.sqrt(np.max(square)) + np.sqrt(np.sum(h * h)) / 2)
    return weight * float(np.prod(h)), centroid, inertia, reach


def mass_properties(distance, normal, low, high, cells: int = GRID_CELLS):
    """Volume (m^3), centre of mass (3,), inertia per unit mass about it (3, 3) (m^2) and a
    radius about the centre that holds the solid (m), in the frame the solid is given in,
    for a solid inside the box (low, high).

    Two passes of `grid_moments`: the first over the given box finds the principal axes; the
    second over the tightest box along them (from the solid's support points), so a rod or a
    plate turned any way gets ``cells`` cells across its thinnest side too.
    """
    volume, centroid, inertia, reach = grid_moments(distance, normal, low, high, cells)
    _, axes = principal_axes(inertia)
    own_distance, own_normal = in_frame(distance, normal, centroid, axes)
    sides = support_of(own_distance, own_normal, np.concatenate([np.eye(3), -np.eye(3)]),
                       reach)
    box_low = np.array([sides[3 + i, i] for i in range(3)])
    box_high = np.array([sides[i, i] for i in range(3)])
    volume, own_centroid, own_inertia, reach = grid_moments(own_distance, own_normal,
                                                            box_low, box_high, cells)
    return volume, centroid + axes @ own_centroid, axes @ own_inertia @ axes.T, reach


def in_frame(distance, normal, origin, axes):
    """The ``distance`` and ``normal`` functions of a solid, taking and giving points and
    vectors in the frame with its origin at ``origin`` (3,) and its axes the columns of
    ``axes`` (3, 3): a point p there is origin + axes p where the functions were given."""
    def own_distance(p):
        return np.asarray(distance(np.asarray(p, np.float64) @ axes.T + origin), np.float64)

    def own_normal(p):
        return np.asarray(normal(np.asarray(p, np.float64) @ axes.T + origin),
                          np.float64) @ axes
    return own_distance, own_normal


def principal_axes(inertia):
    """Eigenvalues (3,) ascending and eigenvectors (3, 3), columns, of a symmetric inertia,
    the eigenvectors a rotation (determinant +1)."""
    values, vectors = np.linalg.eigh(inertia)
    if np.linalg.det(vectors) < 0:
        vectors[:, 2] = -vectors[:, 2]
    return values, vectors


def fibonacci_directions(count: int) -> np.ndarray:
    """``count`` unit vectors (count, 3) spread evenly over the sphere (the Fibonacci
    lattice: heights evenly spaced, turning by the golden angle; Gonzalez, "Measurement of
    areas on a sphere using Fibonacci and latitude-longitude lattices", Math. Geosci. 2010)."""
    k = np.arange(count) + 0.5
    y = 1 - 2 * k / count
    ring = np.sqrt(1 - y * y)
    angle = np.pi * (3 - np.sqrt(5)) * k
    return np.stack([ring * np.cos(angle), y, ring * np.sin(angle)], axis=1)


def cube_directions() -> np.ndarray:
    """The 26 unit directions from a cube's centre to its corners, edges' and faces' middles."""
    steps = (-1.0, 0.0, 1.0)
    grid = np.array([(i, j, k) for i in steps for j in steps for k in steps
                     if (i, j, k) != (0, 0, 0)])
    return grid / np.sqrt(np.sum(grid * grid, axis=1))[:, None]


def project(distance, normal, p, size: float) -> np.ndarray:
    """The surface points (K, 3) nearest the points p (K, 3): p - d(p) grad d(p), repeated
    until |d| is below `SURFACE_TOLERANCE` of ``size`` (one move for an exact SDF)."""
    p = np.array(p, np.float64)
    rows = np.arange(len(p))
    for _ in range(PROJECTION_STEPS):
        d = np.asarray(distance(p[rows]), np.float64)
        far = np.abs(d) > SURFACE_TOLERANCE * size
        rows, d = rows[far], d[far]
        if len(rows) == 0:
            break
        p[rows] -= d[:, None] * np.asarray(normal(p[rows]), np.float64)
    return p


def support(solid: ConvexSolid, direction) -> np.ndarray:
    """The surface points (K, 3) of ``solid`` farthest along unit directions (K, 3), both in
    its own frame (module docstring)."""
    return support_of(solid.distance, solid.normal, direction, solid.radius)


def support_of(distance, normal, direction, size: float) -> np.ndarray:
    """`support` of the convex solid given by its ``distance`` and ``normal`` functions, which
    a sphere of radius ``size`` (m) about the origin holds."""
    direction = np.asarray(direction, np.float64)
    s = project(distance, normal, SUPPORT_REACH * size * direction, size)
    rows = np.arange(len(s))
    reach = np.full(len(s), SUPPORT_REACH * size)
    last = np.full(len(s), np.inf)          # how far each point moved the time before
    for _ in range(SUPPORT_STEPS):
        moved = project(distance, normal, s[rows] + reach[rows, None] * direction[rows], size)
        move = np.sqrt(np.sum((moved - s[rows]) ** 2, axis=1))
        s[rows] = moved
        # A move of m from s + D u slides s along a face at the angle m / D to u, so what is
        # left to gain along u is at most the face's width, 2 size, times that. Done when
        # that is below the tolerance twice running (a move cut short by the face's edge
        # understates the angle to the next face or edge); on a curved surface, when s moves
        # less than 8e-6 of the size, which leaves the gap (8e-6 size)^2 / rho short.
        small = 2 * size * move / reach[rows] <= SUPPORT_TOLERANCE * size
        going = ~(small & (2 * size * last[rows] / reach[rows] <= SUPPORT_TOLERANCE * size))
        rows, move = rows[going], move[going]
        if len(rows) == 0:
            break
        # Sliding along a face nearly square to the direction, each move covers only reach
        # times the small angle between them: while the moves do not shrink, reach twice as
        # far (up to MAX_SUPPORT_REACH); once one falls short (the face's edge is reached),
        # settle from SUPPORT_REACH again, where the normal's rounding does not show.
        sliding = move >= 0.5 * last[rows]
        reach[rows] = np.where(sliding, np.minimum(2 * reach[rows], MAX_SUPPORT_REACH * size),
                               SUPPORT_REACH * size)
        last[rows] = move
    return s


def surface_samples(distance, normal, size: float) -> np.ndarray:
    """Surface points (P, 3) of a convex solid about the origin of its frame (module
    docstring), ``size`` a radius that holds it (m)."""
    directions = np.concatenate([cube_directions(), fibonacci_directions(SAMPLE_DIRECTIONS)])
    points = project(distance, normal, 4 * size * directions, size)
    # Keep the first of the points that landed on one spot (a corner's many directions).
    keys = np.round(points / (SAME_SAMPLE * size)).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return points[np.sort(first)]


def convex_solid(name: str, distance, normal, low, high,
                 cells: int = GRID_CELLS) -> ConvexSolid:
    """A `ConvexSolid` from the signed distance of a convex solid in the frame it is given
    in, and a box (low, high) that holds it.

    Parameters
    ----------
    name : str
    distance, normal : callable
        Signed distance (K,) and unit gradient (K, 3) at points (K, 3) of the given frame.
    low, high : (3,) array_like
        A box holding the solid (m).
    cells : int
        Grid cells along the box's longest side for the integration.

    Raises
    ------
    PhysicsError
        A solid without volume.
    """
    try:
        volume, centroid, inertia, radius = mass_properties(distance, normal, low, high,
                                                            cells)
    except PhysicsError as err:
        raise PhysicsError(f"{name}: {err}") from None
    gyration, axes = principal_axes(inertia)
    own_distance, own_normal = in_frame(distance, normal, centroid, axes)
    samples = surface_samples(own_distance, own_normal, radius)
    radius = max(radius, float(np.sqrt(np.max(np.sum(samples * samples, axis=1)))))
    return ConvexSolid(name, own_distance, own_normal, samples, volume, gyration, centroid,
                       axes, radius)
