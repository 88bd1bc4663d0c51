"""Exact glass: Whitted's ray tree through unions of spheres, boxes and planes.

The reference's glass (`reference_cpu.render.Tracer.lit_color`) marches to each surface,
estimates its normal by finite differences and starts each new ray ``surface_offset`` off
the surface. Here every surface is the exact intersection (`analytic.trace_analytic`, which
also finds where a ray inside a solid leaves it), every normal is exact, and each new ray
leaves from the exact point, on the exact line. What the two must share is the optics
(`reference_cpu.refraction`: Snell, Fresnel, Beer-Lambert) and the shape of the tree (the
depth limit and MIN_RAY_WEIGHT), so the reference converges to this as its epsilon, normal
step and surface offset shrink (tests/truth/test_truth_glass.py).

Only pure dielectrics are traced: every material's ka, kd, ks must be 0, so a pixel's
colour is the sum over the tree's escaping rays of weight x background(direction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scene_model.errors import SceneError
from scene_model.scene import Scene
from scene_model.shapes import primitives

from .. import refraction
from ..shading import background, reflect
from .analytic import trace_analytic
from .parts import scene_parts

# A new ray starts this far along its direction from the exact point it leaves, so that the
# intersection does not find that point again (in units of the scene; float64 intersections
# of unit-sized solids are good to about 1e-15).
NUDGE = 1e-9


@dataclass
class Leaves:
    """The rays of the tree that escape to the background, for every pixel.

    Attributes
    ----------
    pixel : (M,) int ndarray
        Which camera ray each escaping ray descends from.
    direction : (M, 3) ndarray
        Its direction as it leaves.
    weight : (M, 3) ndarray
        What of the background it carries to the pixel.
    inside : (M,) ndarray
        The total distance its branch travelled inside glass.
    """
    pixel: np.ndarray
    direction: np.ndarray
    weight: np.ndarray
    inside: np.ndarray


def check_dielectric(scene: Scene) -> None:
    """Raise `SceneError` unless every material the objects use is a pure dielectric."""
    for index, p in enumerate(primitives(scene.objects)):
        m = scene.materials[p.material]
        if m.ka or m.kd or m.ks:
            raise SceneError(f"the exact glass tree takes pure dielectrics (ka = kd = ks = 0); "
                             f"primitive {index} uses {p.material!r}", ("materials",))


def glass_leaves(scene: Scene, origin, directions) -> Leaves:
    """Trace the exact ray tree of every camera ray; return the rays that escape.

    Parameters
    ----------
    scene : Scene
        Spheres, boxes and planes of pure dielectric materials (`check_dielectric`).
    origin : (3,) ndarray
    directions : (N, 3) float64 ndarray
        Unit camera ray directions.
    """
    check_dielectric(scene)
    s = scene.render
    parts = scene_parts(scene.objects)
    mats = [scene.materials[p.material] for p in primitives(scene.objects)]
    kr = np.array([m.kr for m in mats], float)
    tau = np.array([m.transparency for m in mats], float)
    ior = np.array([m.ior for m in mats], float)
    absorption = np.array([m.absorption for m in mats], float).reshape(-1, 3)

    n = len(directions)
    pixel = np.arange(n)
    o = np.broadcast_to(np.asarray(origin, float), (n, 3))
    d = np.asarray(directions, float)
    weight = np.ones((n, 3))
    sigma = np.zeros((n, 3))              # the absorption of the medium each ray is in
    in_glass = np.zeros(n, bool)          # whether it is in glass (the camera is not)
    inside = np.zeros(n)                  # distance travelled in glass along the branch
    out = []
    for bounce in range(s.reflection_depth + 1):
        # Rays after the camera's leave from exact surface points: intersect from NUDGE on,
        # and count the distance from the point.
        nudge = NUDGE if bounce else 0.0
        t, normal, ids = trace_analytic(parts, o + nudge * d, d)
        hit = ids >= 0
        travelled = np.where(hit, t + nudge, s.max_distance)
        weight = weight * refraction.beer_lambert(sigma, travelled)
        inside = inside + np.where(in_glass, travelled, 0)
        out.append((pixel[~hit], d[~hit], weight[~hit], inside[~hit]))
        if not hit.any() or bounce == s.reflection_depth:
            break
        pixel, d, weight, inside = pixel[hit], d[hit], weight[hit], inside[hit]
        sigma, in_glass = sigma[hit], in_glass[hit]
        ids, normal = ids[hit], normal[hit]
        p = o[hit] + travelled[hit, None] * d
        entering, n_facing, cos_i = refraction.facing(d, normal)
        n1 = np.where(entering, 1.0, ior[ids])
        n2 = np.where(entering, ior[ids], 1.0)
        bent, cos_t, total = refraction.refract(d, n_facing, cos_i, n1 / n2)
        glass = tau[ids] > 0
        f = refraction.fresnel(s.fresnel, cos_i, cos_t, n1, n2, total)
        reflected = kr[ids] + np.where(glass, tau[ids] * f, 0)
        transmitted = np.where(glass, tau[ids] * (1 - f), 0)
        w_r, w_t = weight * reflected[:, None], weight * transmitted[:, None]
        go_r = w_r.max(axis=1) > refraction.MIN_RAY_WEIGHT
        go_t = glass & ~total & (w_t.max(axis=1) > refraction.MIN_RAY_WEIGHT)
        d_r = reflect(d, n_facing)
        entered = np.where(entering[:, None], absorption[ids], 0.0)
        o = np.concatenate([p[go_r], p[go_t]])
        d = np.concatenate([d_r[go_r], bent[go_t]])
        weight = np.concatenate([w_r[go_r], w_t[go_t]])
        sigma = np.concatenate([sigma[go_r], entered[go_t]])
        inside = np.concatenate([inside[go_r], inside[go_t]])
        in_glass = np.concatenate([in_glass[go_r], entering[go_t]])
        pixel = np.concatenate([pixel[go_r], pixel[go_t]])
        if not len(pixel):
            break
    return Leaves(*(np.concatenate(column) for column in zip(*out)))


def glass_colors(scene: Scene, origin, directions) -> np.ndarray:
    """(N, 3): each camera ray's colour, the sum of its escaping rays' weight x background
    (unclipped, float64)."""
    leaves = glass_leaves(scene, origin, directions)
    color = np.zeros((len(directions), 3))
    np.add.at(color, leaves.pixel,
              leaves.weight * background(leaves.direction, scene.render.background))
    return color
