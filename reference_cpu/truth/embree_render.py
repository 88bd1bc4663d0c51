"""The embree backend: a mesh scene drawn by casting rays at its triangles with Embree.

The independent truth of the raster backends. Each pixel's ray finds its first triangle
(`reference_cpu.truth.mesh_cast`), and the picture is then lit by the same shading as the
rasterisers' (`reference_cpu.raster_render.mesh_frame`): where a raster picture and this one
differ, one of them found a different surface.
"""

from __future__ import annotations

from typing import Callable

from scene_model.frame import Frame
from scene_model.mesh_world import scene_meshes
from scene_model.scene import Scene

from ..raster_render import check_mesh_scene, mesh_frame
from .embree import import_embreex
from .mesh_cast import cast_raster


def render(scene: Scene, width: int, height: int, precision: str = "float32",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Ray-cast ``scene``'s meshes at ``width`` x ``height`` pixels (Embree's float32 hits,
    attributes interpolated in float64)."""
    check_mesh_scene(scene, "embree")
    meshes, materials = scene_meshes(scene)
    raster = cast_raster(meshes, scene.camera, width, height)
    if progress is not None:
        progress(1, 1)
    return mesh_frame(scene, meshes, materials, raster, None, "embree", "float32")


def check() -> None:
    """Raise MarchlabError if embreex is missing."""
    import_embreex()
