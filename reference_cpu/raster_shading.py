"""Shading a rasterised picture with the sphere tracer's own shading functions.

After the rasteriser (`reference_cpu.rasterise`) each pixel knows the surface it shows: how
far along its ray, its interpolated normal and texture coordinates, and which object. That is
all the Phong family needs (`reference_cpu.shading`), so a raster picture is shaded by the very
functions that shade the sphere tracer's hits, with the same lights (`reference_cpu.lights`):
where the two pipelines see the same surface, they show the same colour
(tests/test_raster_shading.py). Shadows are not cast here (a rasteriser needs shadow volumes
or shadow maps for them).
"""

from __future__ import annotations

import numpy as np

from scene_model.camera import Camera, camera_rays
from scene_model.scene import LIT_SHADING, Material

from . import shading
from .lights import unshadowed
from .rasterise import Raster


def shade_raster(raster: Raster, camera: Camera, materials: list[Material], lights,
                 ambient=(0.0, 0.0, 0.0), model: str = "phong",
                 background=(0.0, 0.0, 0.0), toon_bands: int = 4) -> np.ndarray:
    """The linear colour (H, W, 3) of a raster picture.

    Parameters
    ----------
    raster : Raster
        What the rasteriser drew, as ``camera`` saw it.
    camera : Camera
    materials : list of Material
        One per object (mesh k has ``materials[k]``); its albedo, ka, kd, ks and shininess.
    lights : sequence of lights (`scene_model.scene`)
    ambient : (3,) linear RGB
        The ambient light, as a render's ``ambient`` setting.
    model : str
        A lit model ("phong", "blinn_phong", "toon", "stripes") or "normals".
    background : (3,) linear RGB
        The colour of pixels where nothing is drawn.
    """
    height, width = raster.depth.shape
    color = np.broadcast_to(np.asarray(background, np.float64), (height, width, 3)).copy()
    hit = raster.hit
    if not hit.any():
        return color
    if model == "normals":
        color[hit] = shading.shade_normals(raster.normal[hit])
        return color
    if model not in LIT_SHADING:
        raise ValueError(f"unknown shading model {model!r} (one of: "
                         f"{', '.join(LIT_SHADING)}, normals)")
    origin, directions = camera_rays(camera, width, height)
    d = directions[hit]
    ids = raster.object_id[hit]
    table = {name: np.array([getattr(m, name) for m in materials], np.float64)
             for name in ("color", "ka", "kd", "ks", "shininess")}
    surface = shading.Surface(position=origin + raster.depth[hit][:, None] * d,
                              normal=raster.normal[hit], view=-d,
                              albedo=table["color"][ids], ka=table["ka"][ids],
                              kd=table["kd"][ids], ks=table["ks"][ids],
                              shininess=table["shininess"][ids], object_id=ids)
    incoming = [(to_light, radiance, specular, light_ambient)
                for to_light, _, radiance, specular, light_ambient, _ in
                (unshadowed(light, surface.position) for light in lights)]
    ambient = np.asarray(ambient, np.float64)
    if model == "phong":
        color[hit] = shading.shade_phong(surface, incoming, ambient)
    elif model == "blinn_phong":
        color[hit] = shading.shade_blinn_phong(surface, incoming, ambient)
    elif model == "stripes":
        color[hit] = shading.shade_stripes(surface, incoming, ambient, toon_bands)
    else:
        color[hit] = shading.shade_toon(surface, incoming, ambient, toon_bands)
    return color
