"""The embree backend: a mesh scene drawn by casting rays at its triangles with Embree.

The independent truth of the raster backends. It plugs ray casting into the mesh pipeline
(`reference_cpu.raster_render.draw`): each pixel's ray finds its first triangle
(`reference_cpu.truth.mesh_cast`), shadow rays find what blocks each light
(`reference_cpu.truth.mesh_rays`), a mirror's reflected rays what it shows, and every
surface along a ray is composited front to back (`reference_cpu.truth.mesh_compositing`).
Where a raster picture and this one differ, one of them found a different surface.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from scene_model.camera import camera_rays
from scene_model.frame import Frame
from scene_model.scene import Scene

from ..raster_render import SurfaceFinder, draw
from .embree import import_embreex
from .mesh_cast import cast_raster
from .mesh_compositing import composite_over, mirror_rays
from .mesh_rays import shadow_rays


def render(scene: Scene, width: int, height: int, precision: str = "float32",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Ray-cast ``scene``'s meshes at ``width`` x ``height`` pixels (Embree's float32 hits,
    attributes interpolated in float64)."""
    frame = draw(scene, width, height, EMBREE)
    if progress is not None:
        progress(1, 1)
    return frame


def _points(raster, camera):
    """Each hit pixel's surface point (N, 3) and its ray direction (N, 3)."""
    height, width = raster.depth.shape
    origin, directions = camera_rays(camera, width, height)
    d = directions[raster.hit]
    return origin + raster.depth[raster.hit][:, None] * d, d


def _visibility(casters, raster, camera, light):
    seen = np.ones(raster.depth.shape)
    if raster.hit.any():
        points, d = _points(raster, camera)
        normal = raster.normal[raster.hit]
        # Start each shadow ray on the side of the surface the eye sees.
        facing = np.where(np.sum(normal * d, axis=1, keepdims=True) > 0, -normal, normal)
        seen[raster.hit] = shadow_rays(casters, points, facing, light)
    return seen


def _mirror(meshes, k, raster, stencil, materials, lights, camera, shade):
    points, d = _points(raster, camera)
    on = stencil[raster.hit]
    color = np.zeros(raster.depth.shape + (3,))
    seen = np.full(raster.depth.shape, -1)
    triangle = np.full(raster.depth.shape, -1)
    color[stencil], seen[stencil], triangle[stencil] = mirror_rays(
        meshes, k, raster.triangle[stencil], points[on], d[on], materials, lights, **shade)
    return color, seen, triangle


def _blend(meshes, materials, lights, camera, color, depth, render, shade):
    # Every surface along the ray, nearest first: what depth peeling converges to.
    shade = {key: value for key, value in shade.items() if key != "background"}
    return composite_over(meshes, materials, lights, camera, color, depth,
                          max_hits=render.peel_layers, **shade)


EMBREE = SurfaceFinder("embree", "float32", cast_raster, _visibility, _mirror, _blend)


def check() -> None:
    """Raise MarchlabError if embreex is missing."""
    import_embreex()
