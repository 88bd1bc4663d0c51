"""Shading a rasterised picture with the sphere tracer's own shading functions.

After the rasteriser (`reference_cpu.rasterise`) each pixel knows the surface it shows: how
far along its ray, its interpolated normal and texture coordinates, and which object. That is
all the Phong family needs (`reference_cpu.shading`), so a raster picture is shaded by the very
functions that shade the sphere tracer's hits, with the same lights (`reference_cpu.lights`):
where the two pipelines see the same surface, they show the same colour
(tests/test_raster_shading.py). Shadows are not found here: a rasteriser finds them with
shadow volumes or a shadow map, a ray caster with shadow rays, and each hands the result in
as ``visibility``, the fraction of each light that reaches each pixel's surface.

The albedo is the sphere tracer's as well (`surface_albedo`): the material's colour, its
checkerboard or its texture, which on a mesh may also be placed by the mesh's own texture
coordinates (`texture_uv`). gpu_shader/raster.py shades the same way on the GPU.
"""

from __future__ import annotations

import numpy as np

from scene_model.camera import Camera, camera_rays
from scene_model.scene import LIT_SHADING, Background, Material
from scene_model.textures import texture_image

from . import shading, texture
from .lights import unshadowed
from .rasterise import Raster


def shade_raster(raster: Raster, camera: Camera, materials: list[Material], lights,
                 ambient=(0.0, 0.0, 0.0), model: str = "phong",
                 background=(0.0, 0.0, 0.0), toon_bands: int = 4,
                 visibility=None) -> np.ndarray:
    """The linear colour (H, W, 3) of a raster picture.

    Parameters
    ----------
    raster : Raster
        What the rasteriser drew, as ``camera`` saw it.
    camera : Camera
    materials : list of Material
        One per object (mesh k has ``materials[k]``): its albedo (the colour, checkerboard
        or texture, `surface_albedo`), ka, kd, ks and shininess.
    lights : sequence of lights (`scene_model.scene`)
    ambient : (3,) linear RGB
        The ambient light, as a render's ``ambient`` setting.
    model : str
        A lit model ("phong", "blinn_phong", "toon", "stripes") or "normals".
    background : (3,) linear RGB or Background
        What pixels where nothing is drawn show: one colour, or a scene's background (a sky,
        a cube map: the skybox), looked up by each pixel's ray as the sphere tracer does.
    visibility : sequence of (H, W) ndarrays, optional
        One per light: how much of it reaches the surface drawn at each pixel, 0 (in shadow)
        to 1 (lit). It scales the light's diffuse and specular terms, not its ambient one
        (`reference_cpu.shading`). Absent: every light reaches everything.
    """
    height, width = raster.depth.shape
    origin, directions = camera_rays(camera, width, height)
    hit = raster.hit
    if isinstance(background, Background):
        # Looked up only where nothing is drawn: a cube map costs bilinear lookups a pixel.
        color = np.zeros((height, width, 3))
        color[~hit] = shading.background(directions[~hit], background)
    else:
        color = np.broadcast_to(np.asarray(background, np.float64), (height, width, 3)).copy()
    if not hit.any():
        return color
    if visibility is not None and len(visibility) != len(lights):
        raise ValueError(f"expected {len(lights)} visibility planes, got {len(visibility)}")
    d = directions[hit]
    seen = None if visibility is None else [
        None if plane is None else np.asarray(plane, np.float64)[hit] for plane in visibility]
    color[hit] = shade_points(origin + raster.depth[hit][:, None] * d, raster.normal[hit], -d,
                              raster.uv[hit], raster.object_id[hit], materials, lights,
                              ambient, model, toon_bands, seen)
    return color


def shade_points(position, normal, view, uv, object_id, materials: list[Material], lights,
                 ambient=(0.0, 0.0, 0.0), model: str = "phong", toon_bands: int = 4,
                 visibility=None) -> np.ndarray:
    """The linear colour (N, 3) of N surface points seen from any direction: what
    `shade_raster` gives a drawn pixel, and what a mirror's reflected rays and a ray
    caster's hits get (`reference_cpu.planar_reflection`, `reference_cpu.truth`).

    Parameters
    ----------
    position, normal : (N, 3) float64 ndarrays
        Points (m) and unit normals.
    view : (N, 3) float64 ndarray
        Unit vectors from each point back along the ray that found it.
    uv : (N, 2) float64 ndarray
        Texture coordinates, for a material textured by uv (`surface_albedo`).
    object_id : (N,) int ndarray
        Which material each point has.
    materials, lights, ambient, model, toon_bands
        As `shade_raster`'s.
    visibility : sequence of (N,) ndarrays or None, optional
        As `shade_raster`'s, one value a point.
    """
    if model == "normals":
        return shading.shade_normals(normal)
    if model not in LIT_SHADING:
        raise ValueError(f"unknown shading model {model!r} (one of: "
                         f"{', '.join(LIT_SHADING)}, normals)")
    ids = np.asarray(object_id)
    table = {name: np.array([getattr(m, name) for m in materials], np.float64)
             for name in ("ka", "kd", "ks", "shininess")}
    surface = shading.Surface(position=position, normal=normal, view=view,
                              albedo=surface_albedo(materials, ids, position, normal, uv),
                              ka=table["ka"][ids], kd=table["kd"][ids], ks=table["ks"][ids],
                              shininess=table["shininess"][ids], object_id=ids)
    incoming = []
    for light, seen in zip(lights, visibility or [None] * len(lights)):
        to_light, _, radiance, specular, light_ambient, _ = unshadowed(light, position)
        if seen is not None:
            share = np.asarray(seen, np.float64)[:, None]
            radiance = radiance * share
            specular = None if specular is None else specular * share
        incoming.append((to_light, radiance, specular, light_ambient))
    ambient = np.asarray(ambient, np.float64)
    if model == "phong":
        return shading.shade_phong(surface, incoming, ambient)
    if model == "blinn_phong":
        return shading.shade_blinn_phong(surface, incoming, ambient)
    if model == "stripes":
        return shading.shade_stripes(surface, incoming, ambient, toon_bands)
    return shading.shade_toon(surface, incoming, ambient, toon_bands)


# --- The albedo: a material's colour, its checkerboard or its texture ---------------------------

def surface_albedo(materials: list[Material], ids, p, n, uv) -> np.ndarray:
    """The albedo (N, 3) of N drawn points, as the sphere tracer's materials give it
    (`reference_cpu.render.Tracer.surface`): the colour, the checkerboard in the xz-plane
    (`shading.checker`) or the texture times its tint (`texture_albedo`).

    Parameters
    ----------
    materials : list of Material
        One per object.
    ids : (N,) int ndarray
        The object of each point.
    p, n : (N, 3) ndarrays
        Positions (m) and unit normals.
    uv : (N, 2) ndarray
        The mesh's interpolated texture coordinates (`reference_cpu.rasterise.Raster.uv`).
    """
    albedo = np.array([m.color for m in materials], np.float64)[ids]
    for k, m in enumerate(materials):
        rows = ids == k
        if m.checker is not None and rows.any():
            c = m.checker
            albedo[rows] = shading.checker(p[rows], np.asarray(c.color_a, np.float64),
                                           np.asarray(c.color_b, np.float64), c.scale)
        elif m.texture is not None and rows.any():
            albedo[rows] = texture_albedo(m.texture, p[rows], n[rows], uv[rows])
    return albedo


def texture_albedo(t, p, n, uv) -> np.ndarray:
    """(N, 3): the texture ``t`` (`scene_model.scene.Texture`) times its tint at points ``p``
    (N, 3) with unit normals ``n`` (N, 3) and mesh texture coordinates ``uv`` (N, 2).

    A mesh carries its own texture coordinates, so its ``uv`` mapping reads them
    (`texture_uv`), where an SDF primitive's projects along an axis or wraps a sphere;
    ``triplanar`` is the sphere tracer's own (`reference_cpu.texture.texture_triplanar`).
    The image repeats both ways (wrap 2), as a planar projection's does.
    """
    texels = texture_image(t).texels
    image = np.array([0.0, texels.shape[1], texels.shape[0], 2.0])
    scale = np.full(len(p), t.scale)
    if t.mapping == "uv":
        color = texture_uv(texels, image, uv, scale)
    else:
        color = texture.texture_triplanar(texels, image, p, n, scale,
                                          np.full(len(p), t.sharpness))
    return np.asarray(t.tint, np.float64) * color


def texture_uv(texels, image, uv, scale) -> np.ndarray:
    """(N, 3): a texture at a mesh's texture coordinates ``uv`` (N, 2), repeated every
    ``scale`` (N,) in u and v (`reference_cpu.texture.texture_repeat`). A mesh's (0, 0) is
    its texture's bottom left (`scene_model.meshes.TriangleMesh`), an image's (0, 0) its top
    left, so v is turned over: the image point is (u / scale, (1 - v) / scale). The twin of
    ``texture_uv`` in gpu_shader/glsl/raster/albedo.glsl."""
    return texture.texture_repeat(texels, image, uv[:, 0] / scale, (1 - uv[:, 1]) / scale)
