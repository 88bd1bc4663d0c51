"""The teacher's version: one worked solution for every exercise of the lessons.

Students do not see this file in the notebooks (each exercise shows the code around it, never
its answer). A teacher can read it, or write the lessons with their exercises solved:

    python lessons/solutions.py OUT_FOLDER      # the notebooks, each exercise cell solved

`tests/lessons/test_solutions.py` runs every solution through its self-check
(`marchlab.check.<name>`), so a solution that stops passing, or a check that stops accepting
a right answer, is caught. The solutions are plain NumPy, written from the lessons' formulas, each
self-contained (it is what replaces the exercise's template in a solved notebook); marchlab's
own versions are shown after the exercises of each lesson.
"""

from __future__ import annotations

import inspect
import math
import sys
from pathlib import Path

import numpy as np


# --- lesson 1 ---------------------------------------------------------------------------------

def sdf_torus(p, major_radius, minor_radius):
    # p : (N, 3) points; return the (N,) signed distances to the torus in the xz-plane.
    # Distance to the ring of radius R in the xz-plane, then the tube of radius r around it.
    ring = np.hypot(p[:, 0], p[:, 2]) - major_radius
    return np.hypot(ring, p[:, 1]) - minor_radius


def sdf_box(p, half_size):
    # p : (N, 3) points, half_size : (3,); return (N,) signed distances to the box.
    # q: how far outside each pair of faces; outside it is the length of the positive part,
    # inside the (negative) largest component.
    q = np.abs(p) - np.asarray(half_size)
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    inside = np.minimum(np.max(q, axis=-1), 0.0)
    return outside + inside


def steps_to_floor(height, angle, epsilon, max_steps):
    # height, angle : (N,), the angle to the floor in radians. Return the (N,) step counts.
    # Evaluation i sees d_i = h q^(i - 1) with q = 1 - sin(angle); the first i with
    # d_i < epsilon is floor(log(epsilon / h) / log q) + 2, or 1 if h < epsilon already.
    q = 1.0 - np.sin(angle)
    with np.errstate(divide="ignore"):
        steps = np.floor(np.log(epsilon / height) / np.log(q)) + 2
    steps = np.where(height < epsilon, 1, steps)
    return np.minimum(steps, max_steps).astype(int)


# --- lesson 2 ---------------------------------------------------------------------------------

def op_subtraction(d1, d2):
    # Shape 1 minus shape 2, from their (N,) distances: inside 1 and outside 2.
    return np.maximum(d1, -d2)


def op_smooth_subtraction(d1, d2, k):
    # Shape 1 minus shape 2 with a rounded edge of width k: the smooth intersection of shape 1
    # with the outside of shape 2, i.e. minus the smooth union of -d1 and d2.
    h = np.clip(0.5 - 0.5 * (d2 + d1) / k, 0.0, 1.0)
    return d1 * (1 - h) + (-d2) * h + k * h * (1 - h)


def op_repeat_limited(p, period, count):
    # p : (N, 3) points; period, count : (3,) (period 0: no repetition on that axis).
    # Subtract the nearest cell centre, its index clamped to -count..count.
    period, count = np.asarray(period, np.float64), np.asarray(count, np.float64)
    safe = np.where(period > 0, period, 1.0)
    cell = np.clip(np.round(p / safe), -count, count)
    return np.where(period > 0, p - safe * cell, p)


# --- lesson 3 ---------------------------------------------------------------------------------

def specular_blinn_phong(n, l, v, shininess):
    # n, l, v : (N, 3) unit vectors; shininess : (N,). Return the (N,) specular term.
    h = (l + v) / np.linalg.norm(l + v, axis=-1, keepdims=True)      # the half vector
    n_dot_l, n_dot_h = np.sum(n * l, axis=-1), np.sum(n * h, axis=-1)
    return np.where(n_dot_l > 0, np.maximum(n_dot_h, 0.0) ** shininess, 0.0)


def shade_phong(s, incoming, ambient):
    # Return the (N, 3) Phong colour of the surface points `s` under the lights `incoming`.
    color = s.ka[:, None] * s.albedo * np.asarray(ambient)
    for to_light, radiance in incoming:
        n_dot_l = np.sum(s.normal * to_light, axis=-1)
        lambert = np.maximum(n_dot_l, 0.0)
        mirrored = 2 * n_dot_l[:, None] * s.normal - to_light        # R = reflect(-L, N)
        r_dot_v = np.sum(mirrored * s.view, axis=-1)
        highlight = np.where(n_dot_l > 0, np.maximum(r_dot_v, 0.0) ** s.shininess, 0.0)
        color = color + radiance * (s.kd[:, None] * lambert[:, None] * s.albedo
                                    + (s.ks * highlight)[:, None])
    return color


# --- lesson 4 ---------------------------------------------------------------------------------

def hard_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance):
    # Return (N,) visibility: 1 where the light is seen, 0 where the shadow ray hits something.
    # Sphere tracing toward the light, no further than the light: a ray that comes within
    # epsilon of a surface is blocked; one that reaches the light or runs out of steps is not.
    limit = np.minimum(light_distance, max_distance)
    t = np.zeros(len(origins))
    blocked = np.zeros(len(origins), bool)
    marching = np.ones(len(origins), bool)
    for _ in range(max_steps):
        h = np.abs(sdf(origins + t[:, None] * to_light)[0])
        hit = marching & (h < epsilon)
        blocked |= hit
        t = np.where(marching, t + h, t)
        marching &= ~hit & (t <= limit)
        if not marching.any():
            break
    return np.where(blocked, 0.0, 1.0)


def soft_shadow(sdf, origins, to_light, light_distance, max_steps, epsilon, max_distance, k):
    # Return (N,) visibility in [0, 1]: Quilez's penumbra estimate, 0 where the shadow ray hits.
    # The same march as hard_shadow, keeping the smallest k h / t after the first step.
    limit = np.minimum(light_distance, max_distance)
    t = np.zeros(len(origins))
    visible = np.ones(len(origins))
    blocked = np.zeros(len(origins), bool)
    marching = np.ones(len(origins), bool)
    for step in range(1, max_steps + 1):
        h = np.abs(sdf(origins + t[:, None] * to_light)[0])
        if step > 1:
            visible = np.where(marching, np.minimum(visible, k * h / np.maximum(t, 1e-300)),
                               visible)
        hit = marching & (h < epsilon)
        blocked |= hit
        t = np.where(marching, t + h, t)
        marching &= ~hit & (t <= limit)
        if not marching.any():
            break
    return np.clip(np.where(blocked, 0.0, visible), 0.0, 1.0)


# --- lesson 5 ---------------------------------------------------------------------------------

def bounce_velocity(v, normal, e):
    # v, normal : (3,), normal unit length, out of the wall; e in [0, 1]. Return v after.
    # The part across the wall reverses and shrinks by e; the part along it stays.
    across = np.dot(v, normal)
    if across >= 0:                     # leaving the wall already: nothing to bounce
        return np.asarray(v, np.float64)
    return v - (1 + e) * across * np.asarray(normal)


# --- lesson 6 ---------------------------------------------------------------------------------

def friction_impulse(v_tangent, k_tangent, limit):
    # v_tangent : (3,) m/s; k_tangent in 1/kg; limit = mu j in N s. Return the impulse (3,).
    # The impulse that stops the sliding, -v_t / k_t, unless Coulomb's cone caps it at
    # mu j: then full friction against the sliding direction.
    v_tangent = np.asarray(v_tangent, np.float64)
    stop = -v_tangent / k_tangent
    size = np.linalg.norm(stop)
    return stop if size <= limit else stop * (limit / size)


def bounce_time(h0, e, n):
    # Time (s) of the n-th impact; the ball is dropped at t = 0, its lowest point h0 up.
    # The fall takes t0 = sqrt(2 h0 / g); after impact i the ball leaves at e^i times the
    # first impact speed and is in the air for 2 e^i t0.
    g = 9.81                                  # m/s^2, the simulator's default gravity
    t0 = math.sqrt(2 * h0 / g)
    return t0 + sum(2 * e ** i * t0 for i in range(1, n))


def velocity_verlet(x, v_old, v_new, h):
    # x, v_old, v_new : (N, 3); h in s. Return the new positions (N, 3).
    # With constant acceleration a, v_new = v_old + h a, and x + h v_old + h^2 a / 2 is
    # x + h (v_old + v_new) / 2.
    return x + h * 0.5 * (v_old + v_new)


# --- lesson 7 ---------------------------------------------------------------------------------

def kinetic_energy(mass, radius, velocity, angular_velocity):
    # mass, radius : (N,); velocity, angular_velocity : (N, 3). Return the total in J.
    # A solid ball: I = 2/5 m r^2.
    inertia = 0.4 * mass * radius ** 2
    v2 = np.sum(velocity * velocity, axis=-1)
    w2 = np.sum(angular_velocity * angular_velocity, axis=-1)
    return float(np.sum(0.5 * mass * v2 + 0.5 * inertia * w2))


def momentum(mass, velocity):
    # mass : (N,); velocity : (N, 3). Return the total momentum (3,) in kg m/s.
    return np.sum(mass[:, None] * velocity, axis=0)


# --- lesson 8 ---------------------------------------------------------------------------------

def refract(d, n_facing, cos_i, eta):
    # d, n_facing : (N, 3) unit, d.n_facing < 0; cos_i, eta = n1 / n2 : (N,).
    # Return the (N, 3) refracted directions, zero where the reflection is total.
    # The part along the surface, d + cos_i n, scales by eta (Snell: sin t = eta sin i); the
    # part along -n has length cos_t = sqrt(k), which does not exist where k <= 0.
    k = 1 - eta * eta * (1 - cos_i * cos_i)
    cos_t = np.sqrt(np.maximum(k, 0.0))
    along_surface = eta[:, None] * (d + cos_i[:, None] * n_facing)
    t = along_surface - cos_t[:, None] * n_facing
    return np.where((k <= 0)[:, None], 0.0, t)


def critical_angle(ior):
    # ior : (N,) indices of refraction (at least 1). Return (N,) angles in radians.
    # Leaving glass eta = ior, and k = 1 - ior^2 sin^2 i = 0 at sin i = 1 / ior.
    return np.arcsin(1.0 / np.asarray(ior, np.float64))


def fresnel_schlick(cos_i, cos_t, n1, n2):
    # cos_i, cos_t, n1, n2 : (N,). Return (N,) the reflected fraction F.
    # R0 is the head-on value; c is the cosine on the side of the lower index (the air).
    r0 = ((n1 - n2) / (n1 + n2)) ** 2
    c = np.where(n1 > n2, cos_t, cos_i)
    return r0 + (1 - r0) * (1 - c) ** 5


def beer_lambert(absorption, distance):
    # absorption : (N, 3) per unit length; distance : (N,). Return (N, 3) the fraction left.
    # dI = -sigma I ds integrates to I = I0 exp(-sigma s), per channel.
    return np.exp(-absorption * np.asarray(distance)[:, None])



# --- lesson 9 ---------------------------------------------------------------------------------

def edge_function(ax, ay, bx, by, px, py):
    # All (N,). Return the (N,) edge function of the edges a -> b at the points p.
    # The 2D cross product (b - a) x (p - a): twice the signed area of the triangle (a, b, p).
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


def perspective_correct(weights, z, attributes):
    # weights : (N, 3) barycentric in the image; z : (N, 3) view depths; attributes (N, 3, A).
    # Return the (N, A) attribute at the surface point the image point shows.
    # a / z and 1 / z vary linearly in the image: interpolate both, then divide.
    over_z = weights / z
    return np.einsum("ni,nia->na", over_z, attributes) / over_z.sum(axis=1)[:, None]


def barycentric(p, a, b, c):
    # p, a, b, c : (N, 3), p in the plane of the triangle. Return the (N, 3) weights of a, b, c.
    # Each corner's weight is the signed area of the triangle p makes with the other two
    # corners, over the whole area; signed along the triangle's normal n.
    n = np.cross(b - a, c - a)
    whole = np.sum(n * n, axis=1)              # |n|^2: the area (times 2) measured along n
    w_a = np.sum(np.cross(c - b, p - b) * n, axis=1) / whole
    w_b = np.sum(np.cross(a - c, p - c) * n, axis=1) / whole
    return np.stack([w_a, w_b, 1 - w_a - w_b], axis=-1)


def cube_face(directions):
    # directions : (N, 3) from the light. Return the (N,) face: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z.
    # The face a direction leans towards most: its largest coordinate in size, with its sign.
    axis = np.argmax(np.abs(directions), axis=1)
    negative = directions[np.arange(len(directions)), axis] < 0
    return 2 * axis + negative

SOLUTIONS = {name: function for name, function in list(globals().items())
             if inspect.isfunction(function) and not name.startswith("_")
             and function.__module__ == __name__}


def solved_notebooks(folder) -> list[Path]:
    """Write every lesson into ``folder`` with each exercise template (a cell that defines a
    function this module solves and raises NotImplementedError) replaced by its solution."""
    import nbformat
    lessons = Path(__file__).resolve().parent
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for path in sorted(lessons.glob("*.ipynb")):
        notebook = nbformat.read(path, as_version=4)
        for cell in notebook.cells:
            if cell.cell_type == "code" and "NotImplementedError" in cell.source:
                cell.source = _solved(cell.source)
        out = folder / path.name
        nbformat.write(notebook, out)
        written.append(out)
    return written


def _solved(source: str) -> str:
    """``source`` with each ``def name(...)`` whose body raises NotImplementedError replaced
    by this module's ``name``; the rest of the cell (its check, say) kept."""
    lines, out, skipping = source.splitlines(), [], False
    for line in lines:
        if line.startswith("def ") and line[4:].split("(")[0] in SOLUTIONS:
            name = line[4:].split("(")[0]
            out.append(inspect.getsource(SOLUTIONS[name]).rstrip())
            skipping = True
            continue
        if skipping and (line.startswith(" ") or not line.strip()):
            if not line.strip():
                out.append(line)
            continue
        skipping = False
        out.append(line)
    return "\n".join(out).replace("\n\n\n\n", "\n\n\n")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python lessons/solutions.py OUT_FOLDER")
    for written in solved_notebooks(sys.argv[1]):
        print(written)
