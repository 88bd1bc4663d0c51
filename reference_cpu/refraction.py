"""Glass: Snell's law, Fresnel's split between reflection and refraction, Beer-Lambert.

A transparent surface sends a ray on two ways (Whitted 1980): reflected, and refracted into
(or out of) the solid. Fresnel's equations say how the light divides between them; what
enters a coloured glass fades with the distance it travels inside. The GLSL and OpenCL twins
are in gpu_shader/glsl/glass.glsl, function for function.

The solid is always the denser side: a ray meets a surface from outside (d.n < 0, n the
SDF's outward gradient) going from air (index 1) into the material's index, and from inside
going out. Which side a ray is on is therefore read from the SDF's sign, and glass inside
glass needs no bookkeeping: a hollow in a glass ball is air because the SDF says so.

References: Snell's law in vector form and the Fresnel equations for unpolarised light are
written out in Bram de Greve, "Reflections and Refractions in Ray Tracing" (2006), eqs. 22
and 25-27; Schlick's approximation is Schlick, "An Inexpensive BRDF Model for
Physically-based Rendering", Computer Graphics Forum 13(3), 1994, eq. 24.
"""

from __future__ import annotations

import numpy as np

from scene_model.geometry import dot

# Adaptive tree depth (Hall and Greenberg, "A Testbed for Realistic Image Synthesis", IEEE
# CG&A 3(8), 1983): a secondary ray whose weight is at most this in every channel is not
# traced; what it would add is below a quarter of an 8-bit level of a colour of 1.
MIN_RAY_WEIGHT = 1.0 / 1024.0
# A ray whose weight is at most this in every channel is left out of the pixel's path label
# (`reference_cpu.render.Tracer.lit_color`): a jump in what it sees (another surface, a
# checker cell, a shadow) moves the pixel's colour by less than the equivalence gates' level
# of 1/255 for any colour up to 2, so it is no discontinuity for the comparisons.
LABEL_WEIGHT = 1.0 / 512.0


def facing(d, n):
    """Which side of the surface each ray comes from, and the normal facing it.

    Parameters
    ----------
    d : (N, 3) ndarray
        Unit ray directions.
    n : (N, 3) ndarray
        Unit outward normals (the SDF's gradient) at the points hit.

    Returns
    -------
    entering : (N,) bool ndarray
        True where the ray comes from outside the solid (d.n < 0).
    n_facing : (N, 3) ndarray
        The normal on the ray's side: n where entering, -n where leaving.
    cos_i : (N,) ndarray
        cos of the angle of incidence, -d.n_facing >= 0.
    """
    entering = dot(d, n) < 0
    n_facing = np.where(entering[:, None], n, -n)
    return entering, n_facing, -dot(d, n_facing)


def refract_k(cos_i, eta):
    """cos^2 of the refracted angle, k = 1 - eta^2 (1 - cos_i^2), by Snell's law
    n1 sin i = n2 sin t with eta = n1 / n2 (de Greve 2006, eq. 22). k <= 0 is total internal
    reflection (k = 0, a refracted ray along the surface, counts as total too).

    cos_i, eta : (N,) ndarray. Returns k : (N,).
    """
    return 1 - eta * eta * (1 - cos_i * cos_i)


def refract_direction(d, n_facing, cos_i, eta, cos_t):
    """The refracted direction t = eta d + (eta cos_i - cos_t) n_facing (de Greve 2006,
    eq. 22), a unit vector when d and n_facing are.

    d, n_facing : (N, 3) ndarray; cos_i, eta, cos_t : (N,) ndarray. Returns (N, 3).
    """
    return eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * n_facing


def refract(d, n_facing, cos_i, eta):
    """Snell's law in vector form: `refract_k`, then `refract_direction`.

    Parameters
    ----------
    d : (N, 3) ndarray
        Unit ray directions.
    n_facing : (N, 3) ndarray
        Unit normals facing the incoming ray (`facing`).
    cos_i : (N,) ndarray
        -d.n_facing.
    eta : (N,) ndarray
        n1 / n2, the index the ray leaves over the one it enters.

    Returns
    -------
    t : (N, 3) ndarray
        Unit refracted directions (zero where the reflection is total).
    cos_t : (N,) ndarray
        cos of the refracted angle (0 where the reflection is total).
    total : (N,) bool ndarray
        Total internal reflection.
    """
    k = refract_k(cos_i, eta)
    total = k <= 0
    cos_t = np.sqrt(np.maximum(k, 0))
    t = refract_direction(d, n_facing, cos_i, eta, cos_t)
    return np.where(total[:, None], 0, t), cos_t, total


def fresnel(model, cos_i, cos_t, n1, n2, total):
    """The reflected fraction F by ``model`` ("exact" or "schlick"), 1 where the
    reflection is total."""
    with np.errstate(invalid="ignore", divide="ignore"):    # 0 / 0 only where total
        f = FRESNEL[model](cos_i, np.where(total, 0, cos_t), n1, n2)
    return np.where(total, 1, f)


def fresnel_exact(cos_i, cos_t, n1, n2):
    """The reflected fraction of unpolarised light: Fresnel's equations (de Greve 2006,
    eqs. 25-27), the mean of the s- and p-polarised reflectances. Exactly 0 at normal
    incidence between equal indices, so glass of index 1 is invisible.

    cos_i, cos_t, n1, n2 : (N,) ndarray. Returns F : (N,).
    """
    r_s = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    r_p = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    return (r_s * r_s + r_p * r_p) / 2


def fresnel_schlick(cos_i, cos_t, n1, n2):
    """Schlick's approximation of the reflected fraction (Schlick 1994, eq. 24):

        F = R0 + (1 - R0) (1 - c)^5,   R0 = ((n1 - n2) / (n1 + n2))^2,

    with c the cosine on the less dense side: cos_i entering, cos_t leaving (de Greve 2006,
    eq. 29; using cos_i there puts the jump to 1 at the wrong angle). Unlike the exact
    equations it leaves a grazing reflection between equal indices: (1 - c)^5.

    cos_i, cos_t, n1, n2 : (N,) ndarray. Returns F : (N,).
    """
    r0 = (n1 - n2) / (n1 + n2)
    r0 = r0 * r0
    m = 1 - np.where(n1 > n2, cos_t, cos_i)
    return r0 + (1 - r0) * (m * m * m * m * m)


FRESNEL = {"exact": fresnel_exact, "schlick": fresnel_schlick}


def beer_lambert(absorption, distance):
    """The fraction of light left after ``distance`` inside a medium: exp(-sigma distance)
    per channel (the Beer-Lambert law).

    absorption : (N, 3) ndarray, per unit length; distance : (N,) ndarray. Returns (N, 3).
    """
    return np.exp(-(absorption * distance[:, None]))
