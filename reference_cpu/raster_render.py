"""The numpy-raster backend: a mesh scene drawn by the readable NumPy rasteriser.

A scene's ``[[meshes]]`` become world-space triangles (`scene_model.mesh_objects`), the
rasteriser finds what each pixel shows (`reference_cpu.rasterise`), and the sphere tracer's
shading functions light it (`reference_cpu.raster_shading`). `mesh_frame` packs the result
into the `Frame` every backend returns; the other mesh backends (the GPU's raster pipeline,
Embree's ray casts) share it, so the three pictures differ only in how they found the
surfaces and the shadows.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.frame import Frame
from scene_model.mesh_world import scene_meshes
from scene_model.meshes import TriangleMesh, smooth_groups
from scene_model.scene import LIT_SHADING, Scene

from . import shading
from .rasterise import Raster, rasterise
from .raster_shading import shade_raster
from .render import path_step

# The shading modes a picture of triangles can show: no march, so no steps.
MESH_SHADING = LIT_SHADING + ("normals", "depth")


def render(scene: Scene, width: int, height: int, precision: str = "float64",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Rasterise ``scene``'s meshes at ``width`` x ``height`` pixels in float64."""
    check_mesh_scene(scene, "numpy-raster")
    meshes, materials = scene_meshes(scene)
    raster = rasterise(meshes, scene.camera, width, height)
    if progress is not None:
        progress(1, 1)
    return mesh_frame(scene, meshes, materials, raster, None, "numpy-raster", "float64")


def check_mesh_scene(scene: Scene, backend: str) -> None:
    """Refuse, in one line, what a mesh backend cannot draw."""
    if scene.objects or scene.bodies:
        raise MarchlabError(f"the {backend} backend draws triangle meshes ([[meshes]]), and "
                            "this scene has SDF objects or bodies: render it with the numpy, "
                            "gpu or opencl backend")
    if scene.render.shading not in MESH_SHADING:
        raise MarchlabError(f"render.shading = {scene.render.shading!r} shows the sphere "
                            f"tracer's march, which the {backend} backend does not take (one "
                            f"of: {', '.join(MESH_SHADING)})")


def mesh_frame(scene: Scene, meshes: list[TriangleMesh], materials: list, raster: Raster,
               visibility, backend: str, precision: str,
               color: np.ndarray | None = None) -> Frame:
    """The `Frame` of a mesh picture.

    Parameters
    ----------
    scene : Scene
    meshes : list of TriangleMesh
        The scene's meshes in world coordinates, mesh k object k.
    materials : list of Material
        One per mesh (`scene_model.mesh_objects.scene_meshes`).
    raster : Raster
        What each pixel shows.
    visibility : sequence of (H, W) ndarrays or None
        Each light's share reaching each pixel's surface (`shade_raster`).
    backend, precision : str
        Which renderer found the surfaces, in which precision.
    color : (H, W, 3) ndarray, optional
        The picture, where the backend shaded it itself (the GPU); else it is shaded here.
    """
    r = scene.render
    if color is None:
        color = picture(scene, materials, raster, visibility)
    hit = raster.hit
    return Frame(color=np.clip(color, 0.0, 1.0).astype(np.float32), depth=raster.depth,
                 normal=raster.normal, steps=np.zeros(hit.shape, np.int32),
                 object_id=raster.object_id.astype(np.int32), hit=hit, gamma=r.gamma,
                 max_steps=1, backend=backend, precision=precision, dither=r.dither,
                 path=path_labels(meshes, raster, visibility))


def path_labels(meshes: list[TriangleMesh], raster: Raster, visibility) -> np.ndarray:
    """(H, W) uint32: what each pixel saw, as the sphere tracer's path labels say it
    (`reference_cpu.render.path_step`): the object and its smooth patch
    (`scene_model.meshes.smooth_groups`: a cube's face), and which of the first six lights
    are shadowed there. Where it changes between neighbours the picture may jump (a
    silhouette, a cube's edge, a shadow's edge), and two correct backends may disagree there
    (`marchlab.compare`)."""
    hit = raster.hit
    patch = np.zeros(raster.depth.shape, np.int64)
    for k, mesh in enumerate(meshes):
        drawn = raster.object_id == k
        patch[drawn] = smooth_groups(mesh)[raster.triangle[drawn]]
    shadowed = np.zeros(raster.depth.shape, np.uint32)
    for k, seen in enumerate((visibility or [])[:6]):
        if seen is not None:
            shadowed |= (np.asarray(seen) < 0.5).astype(np.uint32) << np.uint32(k)
    label = path_step(np.zeros(raster.depth.shape, np.uint32), raster.object_id)
    return path_step(label, np.where(hit, patch, -1), np.where(hit, shadowed, 0))


def picture(scene: Scene, materials: list, raster: Raster, visibility) -> np.ndarray:
    """The linear colour (H, W, 3) of a raster picture under the scene's render settings:
    the shading model, the lights, the background and the fog."""
    r = scene.render
    if r.shading == "depth":
        color = np.zeros(raster.depth.shape + (3,))
        color[raster.hit] = shading.shade_depth(raster.depth[raster.hit], r.max_distance)
        return color
    color = shade_raster(raster, scene.camera, materials, scene.lights, r.ambient, r.shading,
                         r.background, r.toon_bands, visibility)
    if r.fog.density > 0 and r.shading in LIT_SHADING:
        hit = raster.hit
        color[hit] = shading.apply_fog(color[hit], raster.depth[hit],
                                       np.asarray(r.fog.color), r.fog.density)
    return color


def check() -> None:
    """The NumPy rasteriser needs only NumPy: it can always run."""
