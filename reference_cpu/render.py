"""The NumPy reference renderer: the whole pipeline, from camera rays to a `Frame`.

For each pixel: march the primary ray; at a hit, estimate the normal, look up the material,
gather the light from every light (with shadow rays), shade, add fog; then, while the surface
is a mirror and bounces remain, reflect the ray and repeat, weighting each bounce's colour by
the product of the kr seen so far (Whitted 1980's mirror rays, as a loop). A ray that hits
nothing sees the background. With anti-aliasing (``render.samples``), a pixel is the mean of
n x n such rays (`scene_model.sampling`).

Rays are processed in blocks of whole rows, so memory stays bounded and progress can be shown.
"""

from __future__ import annotations

import typing
from typing import Callable

import numpy as np

from scene_model.camera import camera_rays
from scene_model.frame import Frame
from scene_model.sampling import centre_sample, pixel_max_steps, ray_offsets
from scene_model.scene import LIT_SHADING, Checker, Scene, Shading, shading_modes
from scene_model.shapes import primitives
from scene_model.textures import (MAPPING_CODES, surface_mapping, texture_atlas, texture_image,
                                  texture_wrap)

from . import refraction, shading, texture
from .cone_prepass import start_distances
from .culling import BoundingSpheres, object_bits, own_objects
from .lights import unshadowed
from .march import march
from .normals import estimate_normal
from .scene_sdf import build_scene_sdf
from .shadows import hard_shadow, own_object_mask, soft_shadow

BLOCK_RAYS = 1 << 16     # rays per block: large enough to amortise NumPy's per-call overhead

AOV_MODES = ("normals", "depth", "steps")
LIT_MODES = LIT_SHADING
SHADING = typing.get_args(Shading)


def render(scene: Scene, width: int, height: int, precision: str = "float64",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Render ``scene`` at ``width`` x ``height`` pixels in float32 or float64.

    ``progress(done, total)`` is called after each block of rays, if given; with
    ``path_labels`` the frame holds each pixel's path label (`Frame.path`), else None. With
    ``render.prepass = "cone"``, each primary ray starts where its tile's cone got to
    (`reference_cpu.cone_prepass`). With ``render.samples = n`` > 1 every pixel is traced
    along each of its rays (`scene_model.sampling.ray_offsets`) in turn, and `add_ray`
    folds them into the pixel's buffers.
    """
    dtype = np.dtype(precision)
    r = scene.render
    tracer = Tracer(scene, dtype, path_labels)
    n = width * height
    starts = prepass_starts(scene, width, height, tracer.sdf, dtype).reshape(-1)
    out = {
        "color": np.zeros((n, 3), np.float32), "depth": np.full(n, np.inf, dtype),
        "normal": np.zeros((n, 3), dtype), "steps": np.zeros(n, np.int32),
        "object_id": np.full(n, -1, np.int32), "hit": np.zeros(n, bool),
    }
    if path_labels:
        out["path"] = np.zeros(n, np.uint32)
    if r.samples > 1:                       # the samples' colours, summed in `dtype`
        out["color_sum"] = np.zeros((n, 3), dtype)
    offsets = ray_offsets(r.samples, r.sample_pattern)
    block = max(1, BLOCK_RAYS // width) * width
    for k, offset in enumerate(offsets):
        origin, directions = camera_rays(scene.camera, width, height, dtype, offset)
        directions = directions.reshape(-1, 3)
        for start in range(0, n, block):
            rows = slice(start, min(start + block, n))
            add_ray(out, rows, tracer.trace(origin, directions[rows], starts[rows]), k,
                    r.samples)
            if progress is not None:
                progress(k * n + rows.stop, len(offsets) * n)
    if r.samples > 1:
        out["color"][:] = out.pop("color_sum") / dtype.type(r.samples ** 2)
    shape = {"color": (height, width, 3), "normal": (height, width, 3)}
    arrays = {k: v.reshape(shape.get(k, (height, width))) for k, v in out.items()}
    return Frame(**arrays, gamma=r.gamma, max_steps=pixel_max_steps(r.max_steps, r.samples),
                 dither=r.dither, backend="numpy", precision=dtype.name)


def add_ray(out: dict, rows: slice, ray: dict, k: int, n: int) -> None:
    """Fold ray ``k`` (in `scene_model.sampling.ray_offsets` order) of the pixels ``rows``,
    traced by `Tracer.trace`, into the frame's buffers ``out``.

    With one ray a pixel (n = 1) its buffers are the pixel's. With n x n samples, as every
    backend does it (glsl/pipeline/samples.glsl):

    - colour: the samples' colours, each already clipped to [0, 1], summed in order into
      ``out["color_sum"]`` (`render` divides by n^2 at the end);
    - depth, normal, object id and hit: the ray through the centre's
      (`scene_model.sampling.centre_sample`), so they mean what they mean without samples;
    - steps: the sum over all the pixel's rays, what the pixel cost;
    - path label: the samples' labels folded in order with `path_step`, so that a pixel
      whose samples saw different things has a label its neighbours do not share.
    """
    if n == 1:
        for name, values in ray.items():
            out[name][rows] = values
        return
    if k == centre_sample(n):
        for name in ("depth", "normal", "object_id", "hit"):
            out[name][rows] = ray[name]
    out["steps"][rows] += ray["steps"]
    if k < n * n:
        out["color_sum"][rows] += ray["color"]
        if "path" in ray:
            out["path"][rows] = path_step(out["path"][rows], ray["path"])


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
        # Hard shadow rays leave out the convex object they start on (reference_cpu/
        # shadows.py): the object each primitive's rays leave out, or -1.
        skip = r.shadow_skip_own and r.shadows == "hard"
        self.own_object = own_objects(scene.objects, object_bits(
            scene.objects, r.epsilon, r.bounding_spheres, skip)) if skip else None
        # Material parameters per primitive, indexed by object id (like a shader's UBO).
        prims = list(primitives(scene.objects))
        mats = [scene.materials[p.material] for p in prims]
        table = lambda values: np.asarray(values, dtype=np.float64).astype(dtype)
        self.color = table([m.color for m in mats]).reshape(-1, 3)
        self.ka, self.kd, self.ks, self.kr = (table([getattr(m, k) for m in mats])
                                              for k in ("ka", "kd", "ks", "kr"))
        self.shininess = table([m.shininess for m in mats])
        self.transparency, self.ior = (table([getattr(m, k) for m in mats])
                                       for k in ("transparency", "ior"))
        self.absorption = table([m.absorption for m in mats]).reshape(-1, 3)
        # Glass needs the ray tree's refracted branch and absorption (`lit_color`).
        self.glass = bool((self.transparency > 0).any()) and r.shading in LIT_MODES
        # Each object's shading model, as an index into SHADING.
        self.mode = np.array([SHADING.index(m) for m in shading_modes(scene)] or [0], np.int8)
        self.min_weight = self.dtype.type(refraction.MIN_RAY_WEIGHT)
        self.label_weight = self.dtype.type(refraction.LABEL_WEIGHT)
        self.has_checker = np.array([m.checker is not None for m in mats], dtype=bool)
        checkers = [m.checker or Checker() for m in mats]    # unused where has_checker is False
        self.checker_a = table([c.color_a for c in checkers]).reshape(-1, 3)
        self.checker_b = table([c.color_b for c in checkers]).reshape(-1, 3)
        self.checker_scale = table([c.scale for c in checkers])
        self.texture_tables(prims, mats, table)

    def texture_tables(self, prims, mats, table) -> None:
        """Each object's texture, as a shader's material rows hold it: its mapping's code
        (`MAPPING_CODES`, 0 without a texture), its image in an atlas of the scene's textures
        (first row, width, height, wrap), tint, scale and sharpness."""
        lit = self.settings.shading in LIT_MODES       # only lit surfaces show an albedo
        mappings = [surface_mapping(m.texture, p.kind) if m.texture is not None and lit
                    else None for p, m in zip(prims, mats)]
        self.texture_mapping = np.array([MAPPING_CODES.get(k, 0) for k in mappings] or [0])
        textures = [m.texture if k else None for m, k in zip(mats, mappings)]
        images = [texture_image(t) if t is not None else None for t in textures]
        distinct = list(dict.fromkeys(i for i in images if i is not None))
        atlas = texture_atlas(tuple(distinct)) if distinct else None
        self.texture_texels = atlas.texels if atlas else None
        self.texture_image = table([atlas.image(distinct.index(i), texture_wrap(k))
                                    if i is not None else (0, 1, 1, 0)
                                    for i, k in zip(images, mappings)]).reshape(-1, 4)
        self.texture_tint = table([t.tint if t else (1, 1, 1) for t in textures]).reshape(-1, 3)
        self.texture_scale = table([t.scale if t else 1 for t in textures])
        self.texture_sharpness = table([t.sharpness if t else 1 for t in textures])

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
            color, path = self.lit_color(origin, directions, t, steps, hit, normal, object_id)
        out = {"color": np.clip(color, 0, 1), "depth": t, "normal": normal, "steps": steps,
               "object_id": object_id, "hit": hit}
        if self.path_labels:
            out["path"] = path
        return out

    def lit_color(self, origin, directions, t, steps, hit, normal, object_id):
        """Shaded colour with fog, mirrors and glass: Whitted's ray tree (1980), traced a
        generation at a time.

        Every ray of a generation is marched, its hit shaded and the colour added to its
        pixel, weighted by what the surfaces along its branch passed on (an RGB weight: glass
        absorbs by colour, `refraction.beer_lambert`). A hit spawns a reflected ray (weight
        kr, plus transparency x F on glass) and, on glass, a refracted one (transparency x
        (1 - F)); the next generation traces them all. The tree ends at reflection_depth
        generations after the camera ray, and a ray whose weight is at most MIN_RAY_WEIGHT
        in every channel is not traced. A ray that hits glass from inside adds no Phong term
        (the lights are outside); it only divides.

        Also returns each pixel's path label (see `scene_model.frame.Frame.path`), or None
        without ``path_labels``: each branch folds in the object id hit (-1 for the
        background), the checker cell's parity and which lights are hard-shadowed at every
        hit, so that it changes exactly where the colour may jump; the pixel's label is the
        sum of the labels of its rays (weighing more than LABEL_WEIGHT), which does not
        depend on the order the tree is walked in (the gpu walks it depth first).
        """
        s = self.settings
        labels = self.path_labels
        n = len(directions)
        color = np.zeros((n, 3), dtype=self.dtype)
        path = np.zeros(n, dtype=np.uint32) if labels else None
        ray = np.arange(n)                                    # which pixel each ray serves
        o = np.broadcast_to(origin, directions.shape)
        d = directions
        weight = np.ones((n, 3), dtype=self.dtype)
        absorption = np.broadcast_to(self.absorption_at(origin), (n, 3))
        label = np.zeros(n, dtype=np.uint32) if labels else None
        offset = self.dtype.type(s.surface_offset)
        for bounce in range(s.reflection_depth + 1):
            if bounce == 0:                                   # the primary ray, traced
                normal, ids = normal[hit], object_id[hit]
            else:
                t, steps, hit = march(o, d, self.sdf, s.max_steps, s.epsilon, s.max_distance,
                                      **self.marching)
                normal, ids = self.hit_info(o[hit] + t[hit, None] * d[hit])
            if self.glass:
                # What a ray inside glass lost on its way (a miss went max_distance).
                travelled = np.where(hit, t, self.dtype.type(s.max_distance))
                weight = weight * refraction.beer_lambert(absorption, travelled)
            miss = ~hit
            np.add.at(color, ray[miss], weight[miss] * shading.background(d[miss], s.background))
            if labels:
                seen = miss & (weight.max(axis=1) > self.label_weight)
                np.add.at(path, ray[seen], path_step(label[seen], -1))

            d, weight, absorption, ray = d[hit], weight[hit], absorption[hit], ray[hit]
            p = o[hit] + t[hit, None] * d
            entering, n_facing, cos_i = refraction.facing(d, normal)
            tau = self.transparency[ids]
            lit = entering | (tau == 0)                       # not glass seen from inside
            surface = self.surface(p[lit], normal[lit], -d[lit], ids[lit])
            shaded, features = self.shade(surface, t[hit][lit], steps[hit][lit])
            if s.fog.density > 0:
                shaded = shading.apply_fog(shaded, t[hit][lit],
                                           np.asarray(s.fog.color, self.dtype),
                                           self.dtype.type(s.fog.density))
            np.add.at(color, ray[lit], weight[lit] * shaded)
            if labels:
                codes = np.zeros(len(ids), dtype=np.uint32)
                codes[lit] = features
                label = path_step(label[hit], ids, codes)
                seen = weight.max(axis=1) > self.label_weight
                np.add.at(path, ray[seen], label[seen])

            # The children: reflected (kr, and tau F on glass), refracted (tau (1 - F)).
            reflected = self.kr[ids]
            transmitted = np.zeros_like(reflected)
            bent = np.zeros_like(d)
            total = np.zeros(len(ids), dtype=bool)
            glass = tau > 0
            if glass.any():
                ior = self.ior[ids[glass]]
                one = np.ones_like(ior)
                n1 = np.where(entering[glass], one, ior)
                n2 = np.where(entering[glass], ior, one)
                bent[glass], cos_t, total[glass] = refraction.refract(
                    d[glass], n_facing[glass], cos_i[glass], n1 / n2)
                f = refraction.fresnel(s.fresnel, cos_i[glass], cos_t, n1, n2, total[glass])
                reflected[glass] = reflected[glass] + tau[glass] * f
                transmitted[glass] = tau[glass] * (1 - f)
            w_reflected = weight * reflected[:, None]
            w_transmitted = weight * transmitted[:, None]
            deeper = bounce < s.reflection_depth
            go_r = deeper & (w_reflected.max(axis=1) > self.min_weight)
            go_t = deeper & ~total & (w_transmitted.max(axis=1) > self.min_weight)
            if not (go_r.any() or go_t.any()):
                break
            # The reflected ray starts just off the surface on the ray's side, the refracted
            # one just beyond it, inside the solid it enters (or outside the one it leaves).
            inside = np.where(entering[:, None], self.absorption[ids], 0)
            o = np.concatenate([p[go_r] + offset * n_facing[go_r],
                                p[go_t] - offset * n_facing[go_t]])
            d = np.concatenate([shading.reflect(d[go_r], n_facing[go_r]), bent[go_t]])
            weight = np.concatenate([w_reflected[go_r], w_transmitted[go_t]])
            absorption = np.concatenate([absorption[go_r], inside[go_t]])
            ray = np.concatenate([ray[go_r], ray[go_t]])
            if labels:
                label = np.concatenate([label[go_r], label[go_t]])
        return color, (path & np.uint32(0xFFFFFF) if labels else None)

    def absorption_at(self, origin) -> np.ndarray:
        """(3,): the absorption of the glass the camera is in (zero outside any solid, or
        inside an opaque one): a camera ray from inside glass fades until it leaves."""
        if not self.glass:
            return np.zeros(3, self.dtype)
        p = np.asarray(origin, self.dtype).reshape(1, 3)
        distance, ids = self.sdf_ids(p)
        inside = distance[0] < 0 and self.transparency[ids[0]] > 0
        return self.absorption[ids[0]] if inside else np.zeros(3, self.dtype)

    def hit_info(self, p):
        """The normal (N, 3) and object id (N,) at hit points ``p`` (N, 3)."""
        s = self.settings
        normal = estimate_normal(self.sdf, p, self.dtype.type(s.normal_step), s.normal_method)
        return normal, self.sdf_ids(p)[1]

    def surface(self, p, normal, view, ids) -> shading.Surface:
        """Gather the material of each hit point by its object id: the albedo is the colour,
        the checker pattern or the texture times its tint (`texture_albedo`)."""
        albedo = self.color[ids]
        checkered = self.has_checker[ids]
        if checkered.any():
            albedo[checkered] = shading.checker(
                p[checkered], self.checker_a[ids[checkered]], self.checker_b[ids[checkered]],
                self.checker_scale[ids[checkered]])
        mapping = self.texture_mapping[ids]
        for code in np.unique(mapping[mapping > 0]):
            rows = mapping == code
            albedo[rows] = self.texture_albedo(code, p[rows], normal[rows], ids[rows])
        return shading.Surface(p, normal, view, albedo, self.ka[ids], self.kd[ids],
                               self.ks[ids], self.shininess[ids], ids)

    def texture_albedo(self, code, p, n, ids):
        """(N, 3): the textures times their tints at points ``p`` (N, 3) with normals ``n``
        of objects ``ids`` (N,) that all have the mapping ``code``."""
        texels, image, scale = self.texture_texels, self.texture_image[ids], self.texture_scale[ids]
        if code == MAPPING_CODES["triplanar"]:
            color = texture.texture_triplanar(texels, image, p, n, scale,
                                              self.texture_sharpness[ids])
        elif code == MAPPING_CODES["cube"]:
            color = texture.texture_cube(texels, image, p, n, scale)
        else:
            color = texture.texture_sphere(texels, image, n)
        return self.texture_tint[ids] * color

    def shade(self, surface: shading.Surface, t, steps):
        """Each point's colour by its object's shading model (`shading_modes`), given the
        light reaching it; ``t`` (N,) and ``steps`` (N,) of the rays that hit are what the
        depth and steps models show.

        Returns the colour (N, 3) and, with path labels, a code (N,) of the discontinuous
        features seen at each point: for a lit model the checker parity plus the face of a
        cube-mapped texture, then one bit per light blocked by a hard shadow; for the steps
        model the step count (None without).
        """
        mode = self.mode[surface.object_id]
        if len(mode) == 0 or (mode == mode[0]).all():          # one model: no gathering
            return self.shade_model(SHADING[mode[0] if len(mode) else self.mode[0]], surface,
                                    t, steps)
        color = np.zeros(surface.position.shape, dtype=self.dtype)
        features = np.zeros(len(mode), dtype=np.uint32) if self.path_labels else None
        for code in np.unique(mode):
            rows = mode == code
            c, f = self.shade_model(SHADING[code], surface.select(rows), t[rows], steps[rows])
            color[rows] = c
            if features is not None:
                features[rows] = f
        return color, features

    def shade_model(self, model: str, surface: shading.Surface, t, steps):
        """`shade` of points that all have the one shading ``model``."""
        s = self.settings
        labels = self.path_labels
        if model == "normals":
            return shading.shade_normals(surface.normal), np.zeros(len(t), np.uint32)
        if model == "depth":
            return shading.shade_depth(t, s.max_distance), np.zeros(len(t), np.uint32)
        if model == "steps":
            return shading.shade_steps(steps, s.max_steps), steps.astype(np.uint32)
        ambient = np.asarray(s.ambient, dtype=self.dtype)
        arriving = [self.light_arriving(light, surface) for light in self.scene.lights]
        incoming = [terms[:-1] for terms in arriving]
        features = None
        if labels:
            features = self.checker_parity(surface) + self.texture_face(surface)
            for *_, blocked in arriving:
                features = 2 * features + blocked
        if model == "phong":
            return shading.shade_phong(surface, incoming, ambient), features
        if model == "blinn_phong":
            return shading.shade_blinn_phong(surface, incoming, ambient), features
        if model == "stripes":
            return shading.shade_stripes(surface, incoming, ambient, s.toon_bands), features
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

    def texture_face(self, surface: shading.Surface) -> np.ndarray:
        """The face (`texture.major_face` of the normal) where the object's texture is
        cube-mapped, else 0 (N,) uint32: its texture may jump where the face changes."""
        face = np.zeros(len(surface.position), dtype=np.uint32)
        cube = self.texture_mapping[surface.object_id] == MAPPING_CODES["cube"]
        if cube.any():
            face[cube] = texture.major_face(surface.normal[cube])
        return face

    def light_arriving(self, light, surface):
        """``(L, diffuse, specular, ambient, blocked)`` of one light at every surface point,
        shadows included (the first four are what `shading.shade_phong` takes per light).

        ``diffuse`` is the radiance the diffuse term takes (N, 3); a light with its own
        colours (`scene_model.scene.Light.term_colors`) also gives ``specular`` (N, 3) and
        ``ambient`` (N, 3), else they are None. ``blocked`` (N,) bool is True where a hard
        shadow ray hit something on its way. Points facing away from the light (or that it
        does not reach) need no shadow ray: their diffuse and specular terms are zero
        whatever the visibility, taken as 1.
        """
        s = self.settings
        to_light, distance, radiance, specular, ambient, reach = unshadowed(light,
                                                                            surface.position)
        if s.shadows == "none":
            return to_light, radiance, specular, ambient, np.zeros(len(to_light), dtype=bool)
        # Only points facing the light can receive any; skip the others' shadow rays.
        facing = (shading.dot(surface.normal, to_light) > 0) & (reach.max(axis=1) > 0)
        visible = np.ones(len(to_light), dtype=self.dtype)
        origins = surface.position[facing] + \
            self.dtype.type(s.surface_offset) * surface.normal[facing]
        args = (self.sdf, origins, to_light[facing], distance[facing], s.max_steps,
                s.epsilon, s.max_distance)
        if s.shadows == "hard":
            own = (None if self.own_object is None else own_object_mask(
                self.own_object[surface.object_id[facing]], len(self.scene.objects)))
            visible[facing] = hard_shadow(*args, objects=own, **self.marching)
        else:
            visible[facing] = soft_shadow(*args, self.dtype.type(s.penumbra_k))
        if specular is not None:
            specular = specular * visible[:, None]
        return (to_light, radiance * visible[:, None], specular, ambient,
                (visible == 0) & (s.shadows == "hard"))


def check() -> None:
    """The reference needs only NumPy: it can always run."""
