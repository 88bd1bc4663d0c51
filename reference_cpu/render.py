"""The NumPy reference renderer: the whole pipeline, from camera rays to a `Frame`.

For each pixel: march the primary ray; at a hit, estimate the normal, look up the material,
gather the light from every light (with shadow rays), shade, add fog; then, while the surface
is a mirror and bounces remain, reflect the ray and repeat, weighting each bounce's colour by
the product of the kr seen so far (Whitted 1980's mirror rays, as a loop). A ray that hits
nothing sees the background.

Rays are processed in blocks of whole rows, so memory stays bounded and progress can be shown.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from scene_model.camera import camera_rays
from scene_model.frame import Frame
from scene_model.scene import Checker, Scene
from scene_model.shapes import primitives

from . import shading
from .cone_prepass import start_distances
from .culling import BoundingSpheres
from .lights import light_at
from .march import march
from .normals import estimate_normal
from .scene_sdf import build_scene_sdf
from .shadows import hard_shadow, soft_shadow

BLOCK_RAYS = 1 << 16     # rays per block: large enough to amortise NumPy's per-call overhead

AOV_MODES = ("normals", "depth", "steps")


def render(scene: Scene, width: int, height: int, precision: str = "float64",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Render ``scene`` at ``width`` x ``height`` pixels in float32 or float64.

    ``progress(done, total)`` is called after each block of rays, if given; with
    ``path_labels`` the frame holds each pixel's path label (`Frame.path`), else None. With
    ``render.prepass = "cone"``, each primary ray starts where its tile's cone got to
    (`reference_cpu.cone_prepass`).
    """
    dtype = np.dtype(precision)
    tracer = Tracer(scene, dtype, path_labels)
    origin, directions = camera_rays(scene.camera, width, height, dtype)
    directions = directions.reshape(-1, 3)
    n = len(directions)
    starts = prepass_starts(scene, width, height, tracer.sdf, dtype).reshape(-1)
    out = {
        "color": np.zeros((n, 3), np.float32), "depth": np.full(n, np.inf, dtype),
        "normal": np.zeros((n, 3), dtype), "steps": np.zeros(n, np.int32),
        "object_id": np.full(n, -1, np.int32), "hit": np.zeros(n, bool),
    }
    if path_labels:
        out["path"] = np.zeros(n, np.uint32)
    block = max(1, BLOCK_RAYS // width) * width
    for start in range(0, n, block):
        rows = slice(start, min(start + block, n))
        for name, values in tracer.trace(origin, directions[rows], starts[rows]).items():
            out[name][rows] = values
        if progress is not None:
            progress(rows.stop, n)
    shape = {"color": (height, width, 3), "normal": (height, width, 3)}
    arrays = {k: v.reshape(shape.get(k, (height, width))) for k, v in out.items()}
    return Frame(**arrays, gamma=scene.render.gamma, max_steps=scene.render.max_steps,
                 dither=scene.render.dither,
                 backend="numpy", precision=dtype.name)


def prepass_starts(scene: Scene, width: int, height: int, sdf, dtype) -> np.ndarray:
    """(H, W) ``dtype``: where each primary ray starts, 0 without a pre-pass; with
    ``render.prepass = "cone"``, its tile's cone distance (`cone_prepass.start_distances`,
    the margin the hit threshold epsilon)."""
    r = scene.render
    if r.prepass == "none":
        return np.zeros((height, width), dtype)
    start, _ = start_distances(scene.camera, width, height, sdf, r.prepass_tile, r.max_steps,
                               r.epsilon, r.max_distance, dtype)
    return start


def path_step(path, ids, features=0):
    """Fold one bounce (object ids, feature codes) into the path labels.

    A hash in uint32 arithmetic kept to 24 bits, so that a float32 render target holds it
    exactly; the GPU backend computes the same numbers (glsl/shading.glsl, ``path_step``).
    """
    ids = np.asarray(ids, np.int64) + 1
    step = (path * np.uint32(1009) + ids.astype(np.uint32)) * np.uint32(64)
    return (step + np.asarray(features, np.uint32)) & np.uint32(0xFFFFFF)


class Tracer:
    """A scene prepared for tracing in one precision: its SDFs and per-primitive material tables.

    With ``path_labels``, `trace` also returns each ray's path label (`path_step`).
    """

    def __init__(self, scene: Scene, dtype: np.dtype, path_labels: bool = False):
        self.scene, self.settings, self.dtype = scene, scene.render, dtype
        self.path_labels = path_labels
        self.sdf = build_scene_sdf(scene.objects, dtype)
        self.sdf_ids = build_scene_sdf(scene.objects, dtype, with_ids=True)
        # How far each step of a march goes (relaxation, culling): the same for primary,
        # mirror and hard-shadow rays. Soft shadows keep plain steps: their penumbra is
        # read from the distances along the way, which both would change.
        r = self.settings
        self.marching = {"relaxation": r.relaxation, "omega": r.omega, "bounds": (
            BoundingSpheres.of(scene.objects, r.epsilon, dtype) if r.bounding_spheres else None)}
        # Material parameters per primitive, indexed by object id (like a shader's UBO).
        mats = [scene.materials[p.material] for p in primitives(scene.objects)]
        table = lambda values: np.asarray(values, dtype=np.float64).astype(dtype)
        self.color = table([m.color for m in mats]).reshape(-1, 3)
        self.ka, self.kd, self.ks, self.kr = (table([getattr(m, k) for m in mats])
                                              for k in ("ka", "kd", "ks", "kr"))
        self.shininess = table([m.shininess for m in mats])
        self.has_checker = np.array([m.checker is not None for m in mats], dtype=bool)
        checkers = [m.checker or Checker() for m in mats]    # unused where has_checker is False
        self.checker_a = table([c.color_a for c in checkers]).reshape(-1, 3)
        self.checker_b = table([c.color_b for c in checkers]).reshape(-1, 3)
        self.checker_scale = table([c.scale for c in checkers])

    # --- one block of primary rays --------------------------------------------------------

    def trace(self, origin, directions, start=None) -> dict[str, np.ndarray]:
        s = self.settings
        t, steps, hit = march(origin, directions, self.sdf, s.max_steps, s.epsilon,
                              s.max_distance, start=start, **self.marching)
        normal = np.zeros_like(directions)
        object_id = np.full(len(directions), -1, np.int32)
        normal[hit], object_id[hit] = self.hit_info(origin + t[hit, None] * directions[hit])

        # The path label (Frame.path) of the AOV modes: the object hit, and for the steps
        # mode the step count too, as its colour jumps with every step.
        counted = steps if s.shading == "steps" else np.zeros_like(steps)
        path = path_step(counted.astype(np.uint32), object_id) if self.path_labels else None
        if s.shading == "steps":
            color = shading.shade_steps(steps, s.max_steps)
        elif s.shading in AOV_MODES:
            color = np.array(shading.background(directions, s.background))
            color[hit] = (shading.shade_normals(normal[hit]) if s.shading == "normals"
                          else shading.shade_depth(t[hit], s.max_distance))
        else:
            color, path = self.lit_color(origin, directions, t, hit, normal, object_id)
        out = {"color": np.clip(color, 0, 1), "depth": t, "normal": normal, "steps": steps,
               "object_id": object_id, "hit": hit}
        if self.path_labels:
            out["path"] = path
        return out

    def lit_color(self, origin, directions, t, hit, normal, object_id):
        """Shaded colour with fog and mirror bounces (Whitted 1980, iterated instead of recursed).

        Also returns each pixel's path label (see `scene_model.frame.Frame.path`), or None
        without ``path_labels``: at every bounce it takes in the object id hit (-1 for the
        background), the checker cell's parity and which lights are hard-shadowed, so that
        it changes exactly where the colour may jump.
        """
        s = self.settings
        labels = self.path_labels
        color = np.zeros(directions.shape, dtype=self.dtype)
        path = np.zeros(len(directions), dtype=np.uint32) if labels else None
        weight = np.ones(len(directions), dtype=self.dtype)   # product of kr so far
        ray = np.arange(len(directions))                      # which pixel each ray serves
        o = np.broadcast_to(origin, directions.shape)
        d = directions
        for bounce in range(s.reflection_depth + 1):
            if bounce == 0:                                   # the primary ray, traced
                normal, ids = normal[hit], object_id[hit]
            else:
                t, _, hit = march(o, d, self.sdf, s.max_steps, s.epsilon, s.max_distance,
                                  **self.marching)
                normal, ids = self.hit_info(o[hit] + t[hit, None] * d[hit])
            p = o[hit] + t[hit, None] * d[hit]
            miss = ~hit
            color[ray[miss]] += weight[miss, None] * shading.background(d[miss], s.background)
            if labels:
                path[ray[miss]] = path_step(path[ray[miss]], -1)

            surface = self.surface(p, normal, -d[hit], ids)
            shaded, features = self.shade(surface)
            if labels:
                path[ray[hit]] = path_step(path[ray[hit]], ids, features)
            if s.fog.density > 0:
                shaded = shading.apply_fog(shaded, t[hit], np.asarray(s.fog.color, self.dtype),
                                           self.dtype.type(s.fog.density))
            color[ray[hit]] += weight[hit, None] * shaded

            # Continue only the rays that hit a mirror: start just off the surface.
            weight = weight[hit] * self.kr[ids]
            go = weight > 0
            if bounce == s.reflection_depth or not go.any():
                break
            ray, weight = ray[hit][go], weight[go]
            o = p[go] + self.dtype.type(s.surface_offset) * normal[go]
            d = shading.reflect(d[hit][go], normal[go])
        return color, path

    def hit_info(self, p):
        """The normal (N, 3) and object id (N,) at hit points ``p`` (N, 3)."""
        s = self.settings
        normal = estimate_normal(self.sdf, p, self.dtype.type(s.normal_step), s.normal_method)
        return normal, self.sdf_ids(p)[1]

    def surface(self, p, normal, view, ids) -> shading.Surface:
        """Gather the material of each hit point by its object id."""
        albedo = self.color[ids]
        checkered = self.has_checker[ids]
        if checkered.any():
            albedo[checkered] = shading.checker(
                p[checkered], self.checker_a[ids[checkered]], self.checker_b[ids[checkered]],
                self.checker_scale[ids[checkered]])
        return shading.Surface(p, normal, view, albedo, self.ka[ids], self.kd[ids],
                               self.ks[ids], self.shininess[ids], ids)

    def shade(self, surface: shading.Surface):
        """The shading model of the render settings, given the light reaching each point.

        Returns the colour (N, 3) and, with path labels, a code (N,) of the discontinuous
        features seen at each point: the checker parity, then one bit per light blocked by a
        hard shadow (None without).
        """
        s = self.settings
        ambient = np.asarray(s.ambient, dtype=self.dtype)
        arriving = [self.light_arriving(light, surface) for light in self.scene.lights]
        incoming = [(to_light, radiance) for to_light, radiance, _ in arriving]
        features = None
        if self.path_labels:
            features = self.checker_parity(surface)
            for _, _, blocked in arriving:
                features = 2 * features + blocked
        if s.shading == "phong":
            return shading.shade_phong(surface, incoming, ambient), features
        if s.shading == "blinn_phong":
            return shading.shade_blinn_phong(surface, incoming, ambient), features
        return shading.shade_toon(surface, incoming, ambient, s.toon_bands), features

    def checker_parity(self, surface: shading.Surface) -> np.ndarray:
        """0 or 1 by checker cell where the material is checkered, else 0 (N,) uint32."""
        parity = np.zeros(len(surface.position), dtype=np.uint32)
        ids = surface.object_id
        checkered = self.has_checker[ids]
        if checkered.any():
            parity[checkered] = shading.checker_parity(surface.position[checkered],
                                                       self.checker_scale[ids[checkered]])
        return parity

    def light_arriving(self, light, surface):
        """``(L, radiance, blocked)`` of one light at every surface point, shadows included.

        ``blocked`` (N,) bool is True where a hard shadow ray hit something on its way.
        Points facing away from the light (or that it does not reach) need no shadow ray:
        their diffuse and specular terms are zero whatever the visibility, taken as 1.
        """
        s = self.settings
        to_light, distance, radiance = light_at(light, surface.position)
        if s.shadows == "none":
            return to_light, radiance, np.zeros(len(to_light), dtype=bool)
        # Only points facing the light can receive any; skip the others' shadow rays.
        facing = (shading.dot(surface.normal, to_light) > 0) & (radiance.max(axis=1) > 0)
        visible = np.ones(len(to_light), dtype=self.dtype)
        origins = surface.position[facing] + \
            self.dtype.type(s.surface_offset) * surface.normal[facing]
        args = (self.sdf, origins, to_light[facing], distance[facing], s.max_steps,
                s.epsilon, s.max_distance)
        visible[facing] = (hard_shadow(*args, **self.marching) if s.shadows == "hard"
                           else soft_shadow(*args, self.dtype.type(s.penumbra_k)))
        return to_light, radiance * visible[:, None], (visible == 0) & (s.shadows == "hard")


def check() -> None:
    """The reference needs only NumPy: it can always run."""
