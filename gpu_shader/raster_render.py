"""The raster backend: a mesh scene drawn by OpenGL's own rasteriser (`gpu_shader.raster`).

The GPU finds what each pixel shows, and the picture is lit as the NumPy rasteriser's is
(`reference_cpu.raster_render.mesh_frame`).
"""

from __future__ import annotations

from typing import Callable

from reference_cpu.raster_render import check_mesh_scene, mesh_frame
from scene_model.frame import Frame
from scene_model.mesh_world import scene_meshes
from scene_model.scene import Scene

from .context import gl_context
from .raster import rasterise


def render(scene: Scene, width: int, height: int, precision: str = "float32",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Rasterise ``scene``'s meshes on the GPU at ``width`` x ``height`` pixels."""
    check_mesh_scene(scene, "raster")
    meshes, materials = scene_meshes(scene)
    raster = rasterise(meshes, scene.camera, width, height)
    if progress is not None:
        progress(1, 1)
    return mesh_frame(scene, meshes, materials, raster, None, "raster", "float32")


def check() -> None:
    """Raise MarchlabError, saying what is missing, if OpenGL cannot run here."""
    gl_context()
