"""Static shapes as colliders: any solid the renderer draws, given by its signed distance.

A plane has its own exact test (contacts.py). Every other static object of a scene (a box, a
bowl carved by a subtraction, a row of pegs made by repetition) is a `Shape`: a function giving
the signed distance d(p) from points to its surface, the very SDF the renderer marches, and a
function giving its normal, the normalised gradient of d. A sphere of radius r centred at x
touches the shape where

    gap = d(x) - r <= slop,        n = grad d(x) / |grad d(x)|,

because for an exact SDF the nearest surface point is x - d(x) n (Hart, "Sphere tracing",
The Visual Computer 12, 1996, section 2; the same test is the "SDF collision" of Macklin et
al., "Local optimization for robust signed distance field collision", 2020, for a point with
an offset r). The contact's lever arm is r and the static world is body N, as for a plane.

**Concave corners.** One distance gives one contact, the nearest surface. A ball lying in the
corner of a box's inside touches the floor and the wall at once, and with only the nearest of
the two it would be pushed into the other. So each contact found is followed by a probe: the
point x + s n, moved along n just far enough (s) that this surface is out of reach. There the
SDF sees only the other surfaces; one found within reach of the ball (its distance from x
estimated along its own normal, d(x) ~ d(probe) - (probe - x).m, which never overestimates
the distance to a convex surface) with a normal that differs from those already found is a
further contact. At most `MAX_SHAPE_CONTACTS` per ball and shape: three faces meet at a box
corner.

**Ridges and points without a gradient.** Where two surfaces are equally near, the SDF has a
ridge and no gradient. A ball resting in a corner sits on one (as near the floor as the wall),
and the finite differences there give a blend of the two normals that belongs to neither, and
would push it diagonally out of the corner. `surface_near` tells a ridge by the derivative
along the estimated normal (1 on a face, less on a ridge) and takes the normal a few steps
away in a fixed direction, where one face is strictly nearest; the probes then find the
others. Where the gradient vanishes altogether (the centre of a sphere, the exact middle of
a slot) and that is not enough, the contact uses `FALLBACK_NORMAL` (+y), the same fixed
choice as for two coincident sphere centres: deterministic and never NaN; the push-out moves
the ball off the point and the next step has a gradient again.

**Continuous collision** by conservative advancement (Mirtich, "Impulse-based dynamic
simulation of rigid body systems", PhD thesis, UC Berkeley 1996, ch. 4; the sphere-tracing
form is Hart's): the centre moves along the step's parabola x(t) = x0 + t u + t^2 A / 2 with
speed at most V = max(|u|, |u + A h|) (|v(t)|^2 is a convex quadratic in t, largest at an end
of the step), so in the time gap / V it cannot reach the surface. Stepping t by that much
until the gap is within a small ``touch`` of zero never passes through a wall, however thin or fast:
a ball at 200 m/s stops at a 1 cm wall. For an SDF that only bounds the distance up to a
factor L (`Shape.lipschitz`, 1 for every exact or bound SDF), the step is gap / (L V).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from scene_model.geometry import dot
from scene_model.motion import Motion, motion_pose, motion_velocity

FALLBACK_NORMAL = (0.0, 1.0, 0.0)   # the normal where the gradient vanishes (as contacts.py)
MAX_SHAPE_CONTACTS = 3              # contacts per ball and shape: the faces of a box corner
SAME_SURFACE = 0.999                # normals closer than this cosine (2.6 degrees) are one surface
MAX_ADVANCE = 48                    # conservative-advancement steps per ball, shape and bounce
RIDGE = 0.99                        # a directional derivative below this along the normal: ridge
# The direction in which a ridge's normal is looked for: (1, sqrt 2, sqrt 3) / sqrt 6, whose
# components are rationally independent, so no two faces of an axis-aligned box (normals
# differing by integer vectors) are equally near along it.
OFF_RIDGE = (0.4082482904638631, 0.5773502691896258, 0.7071067811865476)
OFF_RIDGE_STEPS = 8                 # how far off a ridge its normal is taken, in normal steps


@dataclass(frozen=True)
class Shape:
    """A static solid given by its signed distance function.

    Attributes
    ----------
    name : str
        What error messages and events call it (the scene's path to the object).
    distance : callable
        ``distance(p)`` for points p (N, 3) returns the signed distance (N,) in m, negative
        inside.
    normal : callable
        ``normal(p)`` (N, 3) -> (N, 3): the unit gradient of ``distance``, the zero vector where
        it vanishes.
    restitution, friction : float
        The surface's coefficients; a pair uses max(e_ball, e) and sqrt(mu_ball mu).
    surface : callable, optional
        ``surface(p)`` -> (restitution (N,), friction (N,)) where the coefficients vary over
        the shape (a CSG object of several materials); overrides the two constants.
    lipschitz : float
        L >= 1 with |d(p) - d(q)| <= L |p - q|: 1 for an exact or bounding SDF; more for a
        distance that may overestimate (continuous collision then steps by d / L).
    normal_step : float
        The finite-difference step of ``normal`` (m); see `surface_near`.
    motion : scene_model.motion.Motion, optional
        Moves the shape over time (a kinematic object): `at` gives it where it is.
    velocity : callable, optional
        ``velocity(p)`` (N, 3) -> (N, 3): the surface's velocity at points p (m/s), for a
        shape that `at` put in place; None for a still one.
    """
    name: str
    distance: Callable[[np.ndarray], np.ndarray]
    normal: Callable[[np.ndarray], np.ndarray]
    restitution: float = 0.0
    friction: float = 0.5
    surface: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None
    lipschitz: float = 1.0
    normal_step: float = 1e-5
    motion: Motion | None = None
    velocity: Callable[[np.ndarray], np.ndarray] | None = None

    def coefficients(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Restitution and friction (N,) of the surface near points p (N, 3)."""
        if self.surface is not None:
            return self.surface(p)
        return np.full(len(p), self.restitution), np.full(len(p), self.friction)

    def surface_velocity(self, p: np.ndarray) -> np.ndarray:
        """Velocity (N, 3) of the surface at points p (N, 3) (m/s): 0 for a still shape."""
        if self.velocity is None:
            return np.zeros_like(p)
        return np.asarray(self.velocity(p), p.dtype)

    def at(self, t: float) -> "Shape":
        """The shape where its motion puts it at time ``t`` (s), as a still shape whose
        ``velocity`` is its surface's then; the shape itself if it does not move.

        With x(t) = R (x - pivot) + pivot + s (scene_model/motion.py), a point p of the
        world is the point R^T (p - pivot - s) + pivot of the shape as given, and normals
        turn with R.
        """
        if self.motion is None:
            return self
        rotation, shift = motion_pose(self.motion, t)
        pivot = np.asarray(self.motion.pivot, np.float64)
        motion, still = self.motion, self

        def local(p):
            return ((p - pivot - shift) @ rotation + pivot).astype(p.dtype)

        return dataclasses.replace(
            self, motion=None,
            distance=lambda p: still.distance(local(p)),
            normal=lambda p: (np.asarray(still.normal(local(p)), np.float64)
                              @ rotation.T).astype(p.dtype),
            surface=lambda p: still.coefficients(local(p)),
            velocity=lambda p: motion_velocity(motion, t, p).astype(p.dtype))


def shape_normals(shape: Shape, p: np.ndarray) -> np.ndarray:
    """Unit normals (N, 3) of ``shape`` at p (N, 3), FALLBACK_NORMAL where the gradient
    vanishes or is not finite."""
    normal = np.asarray(shape.normal(p), p.dtype)
    size = dot(normal, normal)
    bad = ~(np.isfinite(size) & (size > 0.5))
    return np.where(bad[:, None], np.asarray(FALLBACK_NORMAL, p.dtype), normal)


def surface_near(shape: Shape, p: np.ndarray, distance: np.ndarray):
    """The surface a ball centred at p (N, 3) meets: its distance (N,) and unit normal (N, 3).

    ``distance`` (N,) is the SDF at p. Away from ridges the answer is that distance and the
    normal at p. On a ridge, a point as near to two faces as makes no difference to the
    finite differences (a ball in a corner rests there), the gradient is a blend of the faces'
    normals and belongs to neither; the directional derivative along it is then less than 1
    (cos 45 degrees for two faces at right angles), which is how a ridge is told
    (`RIDGE`). There the normal is taken a short fixed step away, at p + s v with v the
    fixed direction `OFF_RIDGE` and s = `OFF_RIDGE_STEPS` finite-difference steps, where one
    face is strictly nearest; its distance from p is d(p + s v) - s v.n along that normal.
    """
    h = shape.normal_step
    normal = shape_normals(shape, p)
    slope = (np.asarray(shape.distance(p + h * normal), p.dtype)
             - np.asarray(shape.distance(p - h * normal), p.dtype)) / (2 * h)
    ridge = np.flatnonzero(~(slope >= RIDGE))
    if len(ridge):
        step = (OFF_RIDGE_STEPS * h) * np.asarray(OFF_RIDGE, p.dtype)
        off = p[ridge] + step
        m = shape_normals(shape, off)
        distance = distance.copy()
        distance[ridge] = np.asarray(shape.distance(off), p.dtype) - dot(m, step)
        normal[ridge] = m
    return distance, normal


@dataclass
class ShapeContacts:
    """Contacts of balls with one shape, ordered by (ball, slot). Arrays of length K."""
    body: np.ndarray
    slot: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    restitution: np.ndarray
    friction: np.ndarray
    velocity: np.ndarray


def shape_contacts(shape: Shape, position, radius, bodies, reach: float) -> ShapeContacts:
    """The contacts of balls ``bodies`` (M,) int with ``shape``: every surface of it within
    ``reach`` (m) of a ball, up to MAX_SHAPE_CONTACTS per ball (see the module docstring).

    Parameters
    ----------
    shape : Shape
    position : (N, 3)
        Every ball's centre (m).
    radius : (N,)
    bodies : (M,) int
        The balls to test (the active ones).
    reach : float
        Largest gap counted as a contact (m).
    """
    dtype = position.dtype
    x, r = position[bodies], radius[bodies]
    d = np.asarray(shape.distance(x), dtype)
    near = np.flatnonzero(d - r <= reach)
    found = []                                   # (rows, slot, normal, gap, probe point)
    rows, offset, seen = near, np.zeros((len(near), 3), dtype), []
    distance_here = d[near]
    for slot in range(MAX_SHAPE_CONTACTS):
        if len(rows) == 0:
            break
        probe = x[rows] + offset
        if slot > 0:
            distance_here = np.asarray(shape.distance(probe), dtype)
        distance_here, m = surface_near(shape, probe, distance_here)
        # The surface's distance from the centre, along its own normal (planar estimate).
        gap = distance_here - dot(offset, m) - r[rows]
        new = gap <= reach
        for normals in seen:
            new &= dot(m, normals) < SAME_SURFACE
        found.append((rows[new], slot, m[new], gap[new], probe[new]))
        # Move each probe past this surface's reach and look again from there: farther than
        # a ridge's normal is looked for (`surface_near`), so that look cannot find it again.
        shift = r[rows] + 2 * reach + 2 * OFF_RIDGE_STEPS * shape.normal_step - distance_here
        offset = offset + np.maximum(shift, 0)[:, None] * m
        keep = new
        rows, offset, distance_here = rows[keep], offset[keep], distance_here[keep]
        seen = [normals[keep] for normals in seen] + [m[keep]]
    if not found:
        found = [(np.zeros(0, np.int64), 0, np.zeros((0, 3), dtype), np.zeros(0, dtype),
                  np.zeros((0, 3), dtype))]
    rows = np.concatenate([f[0] for f in found])
    slot = np.concatenate([np.full(len(f[0]), f[1], np.int64) for f in found])
    order = np.lexsort((slot, rows))
    normal = np.concatenate([f[2] for f in found])[order]
    gap = np.concatenate([f[3] for f in found])[order]
    points = np.concatenate([f[4] for f in found])[order]
    rows, slot = rows[order], slot[order]
    restitution, friction = shape.coefficients(points - (gap + r[rows])[:, None] * normal)
    touching = x[rows] - (gap + r[rows])[:, None] * normal        # the surface point
    return ShapeContacts(bodies[rows].astype(np.int64), slot, normal, gap,
                         np.asarray(restitution, dtype), np.asarray(friction, dtype),
                         shape.surface_velocity(touching))


def parabola(start, u, acceleration, t):
    """Points x0 + t u + t^2 A / 2 (K, 3) of K parabolas at times t (K,)."""
    t = t[:, None]
    return start + t * u + (0.5 * t * t) * acceleration


def first_shape_hit(shape: Shape, start, u, acceleration, radius, duration, touch):
    """First time (s) in [0, duration] at which each ball on its parabola comes within
    ``touch`` (m) of ``shape``, by conservative advancement; +inf where it does not.

    Parameters
    ----------
    shape : Shape
    start, u, acceleration : (K, 3)
        The parabola x(t) = start + t u + t^2 acceleration / 2 (m, m/s, m/s^2).
    radius : (K,)
    duration : (K,)
        How long each ball still moves this step (s).
    touch : float
        Gap (m) at which a ball counts as touching.

    A ball whose advancement has not converged after MAX_ADVANCE steps (a path grazing the
    surface, approaching it ever more slowly) is counted as touching where it got to: it is
    no farther than its last gap from the surface and has not passed it.
    """
    k = len(start)
    time = np.full(k, np.inf, start.dtype)
    if k == 0:
        return time
    speed = np.maximum(np.sqrt(dot(u, u)),
                       np.sqrt(dot(u + duration[:, None] * acceleration,
                                   u + duration[:, None] * acceleration)))
    t = np.zeros(k, start.dtype)
    rows = np.flatnonzero(speed > 0)
    for attempt in range(MAX_ADVANCE):
        if len(rows) == 0:
            break
        p = parabola(start[rows], u[rows], acceleration[rows], t[rows])
        gap = np.asarray(shape.distance(p), start.dtype) - radius[rows]
        hit = (gap <= touch) | (attempt == MAX_ADVANCE - 1)
        time[rows[hit]] = t[rows[hit]]
        later = t[rows] + np.maximum(gap, 0) / (shape.lipschitz * speed[rows])
        going = ~hit & (later <= duration[rows])
        t[rows[going]] = later[going]
        rows = rows[going]
    return time
