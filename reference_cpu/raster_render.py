"""The numpy-raster backend: a mesh scene drawn by the readable NumPy rasteriser.

A scene's ``[[meshes]]`` become world-space triangles (`scene_model.mesh_world`), the
rasteriser finds what each pixel shows (`reference_cpu.rasterise`), shadow volumes where its
lights are blocked (`reference_cpu.shadow_volumes`), the mirrored scene what a flat mirror
shows (`reference_cpu.planar_reflection`), and transparent fragments are peeled and
composited (`reference_cpu.transparency`); the sphere tracer's shading functions light it all
(`reference_cpu.raster_shading`). `draw` is that fixed pipeline, and a `SurfaceFinder` is
what plugs into it: the other mesh backends (the GPU's raster pipeline, Embree's ray casts)
plug in their own ways of finding surfaces, so the three pictures differ only there.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.frame import Frame
from scene_model.mesh_world import scene_meshes
from scene_model.meshes import TriangleMesh, smooth_groups
from scene_model.scene import LIT_SHADING, Scene

from . import shading
from .planar_reflection import reflect_through
from .rasterise import Raster, rasterise
from .raster_shading import shade_raster
from .render import path_step
from .shadow_map import shadow_map_visibility
from .shadow_volumes import neighbours, shadow_volume_visibility
from .transparency import (blend_sorted, depth_complexity, is_transparent, keep_only,
                           peel_layers, transparent_fragments)

# The shading modes a picture of triangles can show: no march, so no steps.
MESH_SHADING = LIT_SHADING + ("normals", "depth")


@dataclass(frozen=True)
class SurfaceFinder:
    """What a mesh backend plugs into the fixed pipeline (`draw`): how it finds surfaces.

    Attributes
    ----------
    name, precision : str
        The backend, and the precision its surfaces are found in.
    first_hits : callable
        ``first_hits(meshes, camera, width, height) -> Raster``: what each pixel shows.
    visibility : callable
        ``visibility(casters, raster, camera, light) -> (H, W)``: how much of ``light``
        reaches each pixel's surface, the closed meshes ``casters`` in its way.
    reflection : callable
        ``reflection(meshes, k, raster, stencil, materials, lights, camera, shade) ->
        (color (H, W, 3), object (H, W), triangle (H, W))``: what mirror mesh ``k`` shows on
        the ``stencil`` pixels, one bounce, and which object and triangle (-1: none).
    shadow_map : callable or None
        ``shadow_map(meshes, raster, camera, light, render) -> (H, W)``: visibility by a
        shadow map (``render.shadow_method = "map"``); None for a backend that has only
        exact shadows (the ray caster).
    transparency : callable
        ``transparency(meshes, materials, lights, camera, color, depth, render, shade) ->
        (color (H, W, 3), layers (H, W))``: the transparent ``meshes`` (the others emptied)
        in front of the opaque ``depth`` (H, W), composited over the opaque picture
        ``color``, and how many transparent surfaces each pixel's ray crossed.
    """
    name: str
    precision: str
    first_hits: Callable
    visibility: Callable
    reflection: Callable
    transparency: Callable
    shadow_map: Callable | None = None


def draw(scene: Scene, width: int, height: int, finder: SurfaceFinder) -> Frame:
    """A mesh scene's frame: the pipeline every mesh backend shares.

    1. the opaque meshes' first hits (``finder.first_hits``);
    2. with ``render.shadows`` on, each light's visibility, the closed opaque meshes casting
       (``finder.visibility``: shadow volumes need closed casters, and the ray-cast truth
       takes the same ones, so both find the same shadows), or with ``render.shadow_method
       = "map"`` every opaque mesh (``finder.shadow_map``);
    3. the shading (`picture`): the sphere tracer's functions, lights and background;
    4. with ``render.reflection_depth`` > 0, each flat mirror (kr > 0) adds kr times what it
       reflects (``finder.reflection``), as the sphere tracer adds it;
    5. the transparent meshes (transparency > 0) blended over the result
       (``finder.transparency``).
    """
    check_mesh_scene(scene, finder.name)
    r = scene.render
    meshes, materials = scene_meshes(scene)
    clear = is_transparent(materials)
    opaque = keep_only(meshes, ~clear)
    raster = finder.first_hits(opaque, scene.camera, width, height)
    visibility = None
    if r.shadows != "none":
        casters = [m if neighbours(m) is not None else keep_only([m], [False])[0]
                   for m in opaque]
        if r.shadow_method == "map" and finder.shadow_map is not None:
            # A map needs no closed casters: every opaque mesh is drawn into it.
            visibility = [finder.shadow_map(opaque, raster, scene.camera, light, r)
                          for light in scene.lights]
        else:
            visibility = [finder.visibility(casters, raster, scene.camera, light)
                          for light in scene.lights]
    color = picture(scene, materials, raster, visibility)
    lit = r.shading in LIT_SHADING
    shade = dict(ambient=r.ambient, model=r.shading, background=r.background,
                 toon_bands=r.toon_bands)
    label = path_labels(meshes, raster, visibility)
    if lit and r.reflection_depth > 0:
        for k, material in enumerate(materials):
            stencil = raster.object_id == k
            if material.kr > 0 and stencil.any():
                reflected, seen, triangle = finder.reflection(
                    opaque, k, raster, stencil, materials, scene.lights, scene.camera, shade)
                color[stencil] += material.kr * reflected[stencil]
                # What the mirror shows jumps where the reflected object or patch does.
                label[stencil] = path_step(label[stencil], seen[stencil],
                                           patches(meshes, seen, triangle)[stencil] & 63)
    if lit and clear.any():
        color, layers = finder.transparency(keep_only(meshes, clear), materials,
                                            scene.lights, scene.camera, color, raster.depth,
                                            r, shade)
        label = path_step(label, layers)
    return mesh_frame(scene, meshes, materials, raster, visibility, finder.name,
                      finder.precision, color, label)


def render(scene: Scene, width: int, height: int, precision: str = "float64",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Rasterise ``scene``'s meshes at ``width`` x ``height`` pixels in float64."""
    frame = draw(scene, width, height, NUMPY_RASTER)
    if progress is not None:
        progress(1, 1)
    return frame


def _mirror(meshes, k, raster, stencil, materials, lights, camera, shade):
    height, width = stencil.shape
    color, mirrored = reflect_through(meshes, k, stencil, materials, lights, camera, width,
                                      height, **shade)
    return color, mirrored.object_id, mirrored.triangle


def _blend(meshes, materials, lights, camera, color, depth, render, shade):
    height, width = depth.shape
    fragments = transparent_fragments(meshes, materials, lights, camera, width, height,
                                      **shade)
    layers = np.minimum(depth_complexity(fragments, depth), render.peel_layers)
    if render.blending == "sorted":
        return blend_sorted(fragments, color, depth), layers
    return peel_layers(fragments, color, depth, render.peel_layers), layers


def _shadow_map(meshes, raster, camera, light, render):
    return shadow_map_visibility(meshes, raster, camera, light, render.shadow_map_size,
                                 render.shadow_bias, render.shadow_slope_bias,
                                 render.shadow_pcf)


# The readable reference: the NumPy rasteriser, shadow volumes counted per pixel (or a shadow
# map), the mirrored scene drawn through the mirror's pixels, transparent fragments peeled or
# sorted.
NUMPY_RASTER = SurfaceFinder("numpy-raster", "float64", rasterise, shadow_volume_visibility,
                             _mirror, _blend, _shadow_map)


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
    if scene.render.shadows == "soft":
        raise MarchlabError(f"render.shadows = 'soft' is the sphere tracer's penumbra, which "
                            f"the {backend} backend does not draw: use 'hard' (or "
                            "shadow_method = 'map' with shadow_pcf > 1 for filtered edges)")


def mesh_frame(scene: Scene, meshes: list[TriangleMesh], materials: list, raster: Raster,
               visibility, backend: str, precision: str, color: np.ndarray | None = None,
               path: np.ndarray | None = None) -> Frame:
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
    path : (H, W) uint32 ndarray, optional
        The path labels, where reflections or transparency added to them; else `path_labels`.
    """
    r = scene.render
    if color is None:
        color = picture(scene, materials, raster, visibility)
    hit = raster.hit
    return Frame(color=np.clip(color, 0.0, 1.0).astype(np.float32), depth=raster.depth,
                 normal=raster.normal, steps=np.zeros(hit.shape, np.int32),
                 object_id=raster.object_id.astype(np.int32), hit=hit, gamma=r.gamma,
                 max_steps=1, backend=backend, precision=precision, dither=r.dither,
                 path=path if path is not None else path_labels(meshes, raster, visibility))


def path_labels(meshes: list[TriangleMesh], raster: Raster, visibility) -> np.ndarray:
    """(H, W) uint32: what each pixel saw, as the sphere tracer's path labels say it
    (`reference_cpu.render.path_step`): the object and its smooth patch
    (`scene_model.meshes.smooth_groups`: a cube's face), and which of the first six lights
    are shadowed there. Where it changes between neighbours the picture may jump (a
    silhouette, a cube's edge, a shadow's edge), and two correct backends may disagree there
    (`marchlab.compare`)."""
    hit = raster.hit
    patch = patches(meshes, raster.object_id, raster.triangle)
    shadowed = np.zeros(raster.depth.shape, np.uint32)
    for k, seen in enumerate((visibility or [])[:6]):
        if seen is not None:
            shadowed |= (np.asarray(seen) < 0.5).astype(np.uint32) << np.uint32(k)
    label = path_step(np.zeros(raster.depth.shape, np.uint32), raster.object_id)
    return path_step(label, np.where(hit, patch, -1), np.where(hit, shadowed, 0))


def patches(meshes: list[TriangleMesh], object_id: np.ndarray, triangle: np.ndarray):
    """(H, W) int64: the smooth patch (`scene_model.meshes.smooth_groups`) of the triangle
    each pixel shows, -1 where none."""
    patch = np.full(object_id.shape, -1, np.int64)
    for k, mesh in enumerate(meshes):
        drawn = object_id == k
        if drawn.any():
            groups = _smooth_groups(np.asarray(mesh.triangles, np.int64).tobytes(),
                                    np.asarray(mesh.positions, np.float64).tobytes())
            patch[drawn] = groups[triangle[drawn]]
    return patch


@functools.lru_cache(maxsize=256)
def _smooth_groups(triangles: bytes, positions: bytes) -> np.ndarray:
    """`smooth_groups` of the mesh these bytes hold, found once per mesh: every frame labels
    its paths, and the patches of a scene's meshes take tens of milliseconds to find."""
    return smooth_groups(TriangleMesh(np.frombuffer(positions).reshape(-1, 3), None, None,
                                      np.frombuffer(triangles, np.int64).reshape(-1, 3)))


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
