"""The impulse one contact needs, for solid spheres; shared by both solvers and by the
continuous collision test.

A contact joins sphere a (radius r_a) to b (radius r_b, or the static world) with the unit
normal n from b to a. The contact point is -r_a n from a's centre and +r_b n from b's, so the
velocity of a's surface point relative to b's is

    v_rel = (v_a + w_a x (-r_a n)) - (v_b + w_b x (r_b n)) = v_a - v_b - (r_a w_a + r_b w_b) x n.

An impulse P on a (and -P on b) changes

    v_a += P / m_a,   v_b -= P / m_b,   w_a += -r_a (n x P) / I_a,   w_b += -r_b (n x P) / I_b,

with I = 2/5 m r^2 for a solid sphere. Along n the spin terms vanish (n x n = 0), so a normal
impulse j changes the normal relative velocity by j k_n, k_n = 1/m_a + 1/m_b; along a tangent t
it changes the tangential one by |J| k_t with k_t = 1/m_a + 1/m_b + r_a^2/I_a + r_b^2/I_b (for a
lone sphere on the ground, k_t = 7 / (2m): the 7 of the sliding-to-rolling answer 5/7 v0).

Friction is Coulomb's law applied to impulses (Mirtich, "Impulse-based dynamic simulation of
rigid body systems", PhD thesis, 1996, ch. 4): the tangential impulse that would stop the
sliding, -v_t / k_t, cut down to length mu j if it is longer (the ball then keeps sliding).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.geometry import dot


@dataclass
class SolverBodies:
    """Velocities and inverse masses of N spheres plus the static world as row N.

    Attributes
    ----------
    motion : (N + 1, 6)
        Each body's velocity (m/s) then spin (rad/s); row N stays zero. One array, so that a
        contact gathers what it needs of its bodies in one `take` and an impulse's two
        effects go in one scattered add; stored column by column (`columns`). ``velocity``
        and ``spin`` are its halves, (N + 1, 3) views.
    inverse_mass : (N + 1,)
        1/kg; 0 in row N.
    inverse_inertia : (N + 1,)
        1/(kg m^2); 0 in row N.
    """
    motion: np.ndarray
    inverse_mass: np.ndarray
    inverse_inertia: np.ndarray

    def __post_init__(self):
        self.motion = columns(self.motion)

    @property
    def velocity(self) -> np.ndarray:
        return self.motion[:, :3]

    @property
    def spin(self) -> np.ndarray:
        return self.motion[:, 3:]


def columns(array: np.ndarray) -> np.ndarray:
    """The same (K, C) array stored column by column (Fortran order); itself if it already is.

    NumPy runs its inner loops along the last axis: on rows of 3 they are 3 long, and an
    operation of a (K,) array with a (K, 3) one, the solvers' commonest, pays a loop per row.
    With x, y and z each contiguous the same arithmetic runs along K, as in the reference
    tracer (reference_cpu.march.columns). No value changes: only where the numbers lie.
    """
    return np.asfortranarray(array)


# The columns of p and q that p x q multiplies: (y z x | z x y) of p times (z x y | y z x) of q.
_P_COLUMNS, _Q_COLUMNS = np.array([1, 2, 0, 2, 0, 1]), np.array([2, 0, 1, 1, 2, 0])


def cross(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Row-wise cross product p x q of (K, 3) arrays, written out (np.cross is slower here)."""
    return cross_of_columns(cross_columns(p, "p"), cross_columns(q, "q"))


def cross_columns(v: np.ndarray, side: str) -> np.ndarray:
    """The columns (K, 6) of v (K, 3) that a cross product p x q multiplies, where v is p
    (``side`` "p": y z x z x y) or q ("q": z x y y z x); worked out once for a vector that
    takes part in many products (a contact's normal, in every solver pass)."""
    # Taken as rows of the transpose, so that arrays stored column by column stay so.
    return v.T.take(_P_COLUMNS if side == "p" else _Q_COLUMNS, axis=0).T


def cross_of_columns(p_columns: np.ndarray, q_columns: np.ndarray) -> np.ndarray:
    """p x q (K, 3) from the `cross_columns` of p and q: the six products at once, p_y q_z,
    p_z q_x, p_x q_y | p_z q_y, p_x q_z, p_y q_x, then the first three minus the last three,
    the same products and differences as component by component in two NumPy calls."""
    products = p_columns * q_columns
    return products[:, :3] - products[:, 3:]


def take_rows(array: np.ndarray, index) -> np.ndarray:
    """array[index]: the rows ``index`` (K,) of an (N, C) array, stored column by column
    (`columns`), or a view where ``index`` is a slice.

    The same rows as fancy indexing, by ``ndarray.take``, which skips most of its work on the
    arguments (1.4 against 4.5 microseconds for 100 rows of 3), gathering along each column
    of the transpose.
    """
    return array[index] if isinstance(index, slice) else array.T.take(index, axis=1).T


def scatter_add(target: np.ndarray, rows, values: np.ndarray) -> None:
    """target[rows] += values (target (M, C), rows (K,), values (K, C)), a row named twice
    getting both, in order: np.add.at, through the flat view of ``target``.

    NumPy (2.x) adds at one-dimensional indices on a fast path: 13 against 29 microseconds
    for 600 rows of 3 (the solvers' impulses take that path through `add_at_flat`). Every
    element still receives the same additions in the same order, so the sums are the same
    to the bit.
    """
    if not target.flags.c_contiguous:           # no flat view to add into
        np.add.at(target, rows, values)
        return
    add_at_flat(target, flat_index(rows, target.shape[1]), values)


def flat_index(rows, columns: int) -> np.ndarray:
    """The elements (K C,) of rows ``rows`` (K,) in the flat view of a C-column array, row by
    row: row * C + column."""
    return (np.asarray(rows)[:, None] * columns + np.arange(columns)).reshape(-1)


def add_at_flat(target: np.ndarray, flat, values) -> None:
    """target.flat[flat] += values, repeats summed in order (np.add.at into a view of the
    C-contiguous ``target``: an error, never a copy that takes the adds)."""
    view = target.view()
    view.shape = (-1,)
    np.add.at(view, flat, np.asarray(values).reshape(-1))


def relative_velocity(bodies: SolverBodies, rows: "ContactRows", surface=None) -> np.ndarray:
    """v_rel (K, 3) of a's contact point relative to b's (m/s), for the contacts of ``rows``
    (`contact_rows`); ``surface`` (K, 3), the velocity of a moving static surface b (a
    kinematic object), is b's where given."""
    motion_a, motion_b = take_rows(bodies.motion, rows.a), take_rows(bodies.motion, rows.b)
    turning = rows.radius_a * motion_a[:, 3:] + rows.radius_b * motion_b[:, 3:]
    # v_a - v_b - (r_a w_a + r_b w_b) x n, with n's columns for the product taken once.
    v_rel = (motion_a[:, :3] - motion_b[:, :3]
             - cross_of_columns(cross_columns(turning, "p"), rows.normal_as_q))
    return v_rel if surface is None else v_rel - surface


def effective_masses(inverse_mass_a, inverse_mass_b, inverse_inertia_a, inverse_inertia_b,
                     radius_a, radius_b):
    """k_n and k_t (K,) in 1/kg: change of relative velocity per unit impulse, along n and t."""
    k_normal = inverse_mass_a + inverse_mass_b
    k_tangent = (k_normal + radius_a * radius_a * inverse_inertia_a
                 + radius_b * radius_b * inverse_inertia_b)
    return k_normal, k_tangent


SHORTEST = 1e-37    # N s: a normal float32 number (a GPU may flush smaller ones to 0)


def friction_impulse(v_tangent: np.ndarray, k_tangent, limit) -> np.ndarray:
    """Coulomb friction: -v_t / k_t (K, 3), shortened to length ``limit`` (K,) where longer."""
    sticking = -v_tangent / k_tangent[:, None]
    length = np.sqrt(dot(sticking, sticking))
    # limit / length where longer, else length / length = 1: no branch, and a length below
    # SHORTEST (where the impulse is 0, or as good as) counts as SHORTEST, never divides by 0.
    scale = np.minimum(limit, length) / np.maximum(length, SHORTEST)
    return sticking * scale[:, None]


def collision_impulse(v_rel, normal, gravity_part, restitution, friction, k_normal, k_tangent,
                      threshold, u=None, approach=None):
    """The impulse of one collision, from the current relative velocity.

    Parameters
    ----------
    v_rel : (K, 3)
        Relative contact velocity now, this step's gravity included (m/s).
    normal : (K, 3)
        Unit normals from b to a.
    gravity_part : (K,)
        What this step's gravity added to n . v_rel: h n.g for a plane contact, 0 between two
        falling spheres (m/s). The bounce is computed from the approach speed without it, so
        the velocity gravity adds while a ball rests on the floor (g h each step) never turns
        into a bounce, and at e = 1 a bounce returns exactly the speed the ball arrived with.
    restitution, friction : (K,)
    k_normal, k_tangent : (K,)
        Effective inverse masses (1/kg), see module docstring.
    threshold : float
        Approach speeds below this (m/s) do not bounce: the restitution threshold that lets
        resting contact rest.
    u, approach : (K,), optional
        n . v_rel and gravity_part - u, where the caller has worked them out already (m/s).

    Returns
    -------
    impulse : (K, 3)
        P on body a (N s); zero for contacts that are not approaching.
    normal_impulse : (K,)
        Its normal part j (N s).
    approach : (K,)
        Approach speed -n.v_rel before this step's gravity (m/s); positive means approaching.
    """
    u = dot(v_rel, normal) if u is None else u
    approach = gravity_part - u if approach is None else approach
    colliding = approach > threshold
    # The normal velocity afterwards is e times the approach speed, leaving: solve for j.
    j = np.where(colliding, (restitution * approach - u) / k_normal, 0)
    j = np.maximum(j, 0)
    v_tangent = v_rel - u[:, None] * normal
    tangent = friction_impulse(v_tangent, k_tangent, friction * j)
    tangent *= colliding[:, None]
    return j[:, None] * normal + tangent, j, approach


def apply_impulse(bodies: SolverBodies, a, b, normal, radius_a, radius_b, impulse) -> None:
    """Add P to body a and -P to b (rows of ``bodies``, in place; sums repeated bodies)."""
    apply_rows(bodies, impulse, contact_rows(bodies, a, b, radius_a, radius_b, normal))


@dataclass
class ContactRows:
    """Where K contacts find their bodies in `SolverBodies.motion`, worked out once for a
    solver's passes over the same contacts.

    Attributes
    ----------
    a, b : (K,) int
        The bodies.
    both : (2 K,) int
        a then b, one array (to count each body's contacts with one `np.bincount`).
    radius_a, radius_b : (K, 3)
        The lever arms r_a and r_b (m), one column each for x, y and z, so that r w is a
        product of equal shapes, NumPy's fastest.
    normal : (K, 3)
        The unit normals n, stored column by column (`columns`).
    normal_as_p, normal_as_q : (K, 6)
        Their `cross_columns`, for n x q and p x n.
    flat : (12 K,) int
        Where `apply_rows` adds: the rows' elements in the flat view of motion's transpose,
        (6, N + 1): a's velocity x, y, z and spin x, y, z, then b's.
    scale : (12, K)
        What P and n x P are multiplied by for them: 1/m_a (three rows), -r_a / I_a
        (three), -1/m_b, -r_b / I_b.
    """
    a: np.ndarray
    b: np.ndarray
    both: np.ndarray
    radius_a: np.ndarray
    radius_b: np.ndarray
    normal: np.ndarray
    normal_as_p: np.ndarray
    normal_as_q: np.ndarray
    flat: np.ndarray
    scale: np.ndarray


def contact_rows(bodies: SolverBodies, a, b, radius_a, radius_b, normal) -> ContactRows:
    """`ContactRows` of contacts between bodies a (K,) and b (K,) with normals (K, 3)."""
    im, ii = bodies.inverse_mass, bodies.inverse_inertia
    scale = np.repeat(np.stack([im[a], -(radius_a * ii[a]), -im[b], -(radius_b * ii[b])]), 3,
                      axis=0)
    body = np.repeat(np.stack([a, b]), 6, axis=0)                      # (12, K)
    flat = (body + np.tile(np.arange(6), 2)[:, None] * len(im)).reshape(-1)
    lever = lambda r: columns(np.repeat(r[:, None], 3, axis=1))       # noqa: E731
    normal = columns(normal)
    return ContactRows(a, b, np.concatenate([a, b]), lever(radius_a), lever(radius_b), normal,
                       cross_columns(normal, "p"), cross_columns(normal, "q"), flat, scale)


def apply_rows(bodies: SolverBodies, impulse, rows: ContactRows) -> None:
    """`apply_impulse` with its rows worked out (`contact_rows`).

    One scattered add for a's rows then b's, velocity and spin together: every element gets
    the same additions in the same order as from one add per body and per quantity (a's all
    first), and np.add.at costs per call, not per row, and adds along one-dimensional indices
    fastest (`scatter_add`). -P/m_b is P times -1/m_b, the same number: a product's rounding
    does not depend on the signs.
    """
    turn = cross_of_columns(rows.normal_as_p, cross_columns(impulse, "q"))     # n x P
    push, turn = impulse.T, turn.T                                     # (3, K) each
    change = np.concatenate([push, turn, push, turn])                  # a's, then b's
    add_at_flat(bodies.motion.T, rows.flat, change * rows.scale)


def contact_impulse(v_rel, normal, target, friction, k_normal, k_tangent, normal_total,
                    tangent_total):
    """One solver pass over resting contacts: the change of their accumulated impulses.

    The accumulated normal impulse may only push (>= 0), and the accumulated friction impulse
    stays within mu times it (Catto, "Iterative dynamics with temporal coherence", GDC 2005:
    clamp the sum, not each increment, so later passes can take back what earlier ones overdid).

    Parameters
    ----------
    v_rel, normal : (K, 3)
        Relative contact velocity now (m/s) and unit normals.
    target : (K,)
        Lowest allowed normal velocity (m/s): 0, or -gap/h to let a small gap close this step.
    friction, k_normal, k_tangent : (K,)
    normal_total : (K,), tangent_total : (K, 3)
        Impulses accumulated so far this step (N s); updated in place.

    Returns
    -------
    (K, 3) ndarray
        The impulse to apply now to body a (N s).
    """
    u = dot(v_rel, normal)
    new_normal = np.maximum(normal_total + (target - u) / k_normal, 0)
    v_tangent = v_rel - u[:, None] * normal
    # The accumulated friction that would stop the sliding, tangent_total - v_t / k_t, clamped
    # to the friction cone |J| <= mu j.
    new_tangent = friction_impulse(v_tangent - tangent_total * k_tangent[:, None],
                                   k_tangent, friction * new_normal)
    impulse = (new_normal - normal_total)[:, None] * normal + (new_tangent - tangent_total)
    normal_total[:] = new_normal
    tangent_total[:] = new_tangent
    return impulse
