"""The raster backend: a mesh scene drawn by OpenGL's own raster pipeline, all on the GPU.

The same steps as the NumPy pipeline (`reference_cpu.raster_render.draw`), each a pass on the
GPU; only the finished picture and its planes are read back:

1. **Shadows** (render.shadows != "none"): each light's shadow-volume counts
   (`gpu_shader.raster_shadows.ShadowVolumes`), the closed opaque meshes casting; or with
   render.shadow_method = "map", each light's shadow map, every opaque mesh casting
   (`gpu_shader.raster_shadow_map.shadow_map_textures`).
2. **The opaque meshes**, lit in one draw (`gpu_shader.raster_lit`), each light's count
   texture (lit where 0) or map lookup as its visibility, fog on the first hit.
3. **Flat mirrors** (kr > 0, render.reflection_depth > 0), the classic planar reflection
   (Kilgard 1999; Real-Time Rendering 3rd ed., 9.3.1): the scene mirrored about the mirror's
   plane and clipped at it (glsl/raster/mirror.vert), shaded at the real points under the
   real lights, only on the pixels whose object id is the mirror's (the ids plane stands in
   for a stencil, which moderngl does not expose), then added as kr times the reflection.
4. **Transparent meshes**, by depth peeling (Everitt 2001): each pass draws them again, keeps
   per pixel the nearest fragment in front of the opaque surface and farther than the last
   layer, and the layers are composited front to back; or, with render.blending =
   "sorted", their triangles drawn from the farthest to the nearest, blended "over".

`MeshRenderer` keeps a scene's buffers, shadow volumes and textures on the GPU, so a live
view only draws (`MeshRenderer.draw`); `render` reads the frame back and labels its paths as
`reference_cpu.raster_render.draw` does, so that ``marchlab compare`` can excuse its edges.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from reference_cpu.back_faces import bounds_a_solid, culled_meshes
from reference_cpu.planar_reflection import eye_side_normal, mirror_matrix, mirror_plane
from reference_cpu.rasterise import NEAR
from reference_cpu.raster_render import check_mesh_scene, mesh_frame, patches, path_labels
from reference_cpu.render import path_step
from reference_cpu.transparency import is_transparent, keep_only
from scene_model.camera import Camera, camera_basis
from scene_model.frame import Frame
from scene_model.mesh_world import scene_meshes
from scene_model.scene import LIT_SHADING, Scene

from .context import gl_context, subpixel_shift
from .library import glsl_file
from .raster import _set_camera
from .raster_lit import RasterRenderer, read_planes
from .raster_shaders import ShadowCount, _compile
from .raster_shadow_map import shadow_map_textures
from .raster_shadows import ShadowVolumes

CLIP_DISTANCE0 = 0x3000          # GL_CLIP_DISTANCE0: moderngl has no name for it
NOTHING_PEELED = 1e30            # a layer's t where it drew nothing: nothing lies beyond


class MeshRenderer:
    """The raster backend's passes for one scene's meshes, kept on the GPU between frames.

    The meshes (in world coordinates, `scene_model.mesh_world.scene_meshes`) are uploaded
    once; a frame takes its camera, lights and settings from the scene handed to `draw`, so
    a viewer that moves the camera or a light re-uploads nothing but the volumes of a light
    that moved.
    """

    def __init__(self, scene: Scene, ctx=None):
        check_mesh_scene(scene, "raster")
        self.ctx = ctx or gl_context()
        self.meshes, self.materials = scene_meshes(scene)
        self.clear = is_transparent(self.materials)
        self.opaque = keep_only(self.meshes, ~self.clear)
        self.lit = RasterRenderer(self.meshes, self.ctx)
        with self.ctx:
            self.volumes = ShadowVolumes(self.opaque, self.ctx)
        self.mirrors = {k: mirror_plane(self.meshes[k]) for k, m in enumerate(self.materials)
                        if m.kr > 0 and not self.clear[k]}
        # The closed meshes' back faces are culled in the opaque pass whenever the camera is
        # outside their boxes (`reference_cpu.back_faces`): the same picture, and a museum's
        # lit pass 12% faster on llvmpipe (docs/performance.md).
        self.solid = [bounds_a_solid(m) for m in self.meshes]
        self.boxes = [(m.positions.min(axis=0), m.positions.max(axis=0)) if len(m.positions)
                      else (np.zeros(3), np.zeros(3)) for m in self.meshes]
        self.extra: dict = {}        # textures and framebuffers of the compositing steps

    def draw(self, scene: Scene, width: int, height: int, read: bool = False):
        """Draw one frame and leave it on the GPU; return its framebuffer (attachments as
        `RasterRenderer.draw_planes`'). With ``read``, return ``(fbo, found)`` instead,
        ``found`` what the path labels need: each light's counts or map visibility (H, W),
        each mirror's reflected (object, triangle) planes, the transparent layers per
        pixel."""
        r, camera, lights = scene.render, scene.camera, scene.lights
        lit = r.shading in LIT_SHADING
        # A depth image is black where nothing is (reference_cpu/raster_render.py, picture).
        background = (0.0, 0.0, 0.0) if r.shading == "depth" else r.background
        shade = dict(ambient=r.ambient, model=r.shading, background=background,
                     toon_bands=r.toon_bands)
        found = {"counts": None, "maps": None, "mirrors": [], "layers": None}
        ctx = self.ctx
        visibility, maps, reads = None, [], {}
        if r.shadows != "none" and lights and r.shadow_method == "map":
            # A shadow map per light, every opaque mesh drawn into it (open ones too), as
            # the NumPy pipeline's (reference_cpu/raster_render.py, draw).
            with ctx:
                maps = shadow_map_textures(ctx, [m for m in self.opaque if len(m.triangles)],
                                           lights, camera, width, height, r.shadow_map_size,
                                           r.shadow_bias, r.shadow_slope_bias, r.shadow_pcf)
            visibility = maps
            if read:
                found["maps"] = [_read(ctx, v, width, height, 1) for v in maps]
        elif r.shadows != "none" and lights:
            with ctx:
                drawn = self.volumes.draw(lights, camera, width, height)
            counts, reads = drawn.counts, {"scene_depth": drawn.depth}
            visibility = [ShadowCount(c) for c in counts]
            if read:
                found["counts"] = [_read(ctx, c, width, height, 1) for c in counts]
        shaders = self.lit.shaders(self.materials, lights, **shade, visibility=visibility,
                                   fog=r.fog, depth_range=r.max_distance,
                                   prepass=bool(reads))
        with ctx:
            ids = self.lit.target("frame", width, height)[0].color_attachments[2]
        # The ids plane is the mirrors' stencil: last frame's ids must not stay on pixels
        # nothing covers now. A float clear of -1 leaves a negative integer, no object's id.
        clear_ids = self._framebuffer("ids", ids)
        with ctx:
            clear_ids.clear(-1.0, -1.0, -1.0, -1.0)
        fbo = self.lit.draw_pass(shaders, camera, width, height, objects=~self.clear,
                                 visibility=visibility, reads=reads,
                                 cull_back_faces=culled_meshes(self.solid, self.boxes, camera,
                                                               width, height))
        with ctx:
            for texture in maps:             # read by the lit pass alone
                texture.release()
        planes = fbo.color_attachments
        if lit and r.reflection_depth > 0:
            for k in self.mirrors:
                seen = self._reflect(k, scene, shade, planes, width, height, read)
                found["mirrors"].append((k, seen))
        if lit and self.clear.any():
            if r.blending == "sorted":
                self._blend_sorted(scene, shade, planes, width, height)
            else:
                self._peel(scene, shade, planes, width, height)
            if read:
                found["layers"] = self._layer_count(scene, planes, width, height)
        with ctx:
            ctx.finish()                 # the frame is drawn, not only queued
        return (fbo, found) if read else fbo

    def frame(self, scene: Scene, width: int, height: int) -> Frame:
        """Draw one frame, read it back and label its paths: the `Frame` of `render`."""
        fbo, found = self.draw(scene, width, height, read=True)
        color, raster = read_planes(self.ctx, fbo, width, height)
        visibility = None
        if found["counts"] is not None:
            visibility = [np.where(raster.hit & (c != 0), 0.0, 1.0) for c in found["counts"]]
        if found["maps"] is not None:
            visibility = [np.where(raster.hit, v, 1.0) for v in found["maps"]]
        label = path_labels(self.meshes, raster, visibility)
        for k, (seen, triangle) in found["mirrors"]:
            stencil = raster.object_id == k
            # What the mirror shows jumps where the reflected object or patch does.
            label[stencil] = path_step(label[stencil], seen[stencil],
                                       patches(self.meshes, seen, triangle)[stencil] & 63)
        if found["layers"] is not None:
            label = path_step(label, found["layers"])
        frame = mesh_frame(scene, self.meshes, self.materials, raster, visibility, "raster",
                           "float32", color=color, path=label)
        # A hardware rasteriser samples off the pixel centres (docs/equivalence.md).
        return dataclasses.replace(frame, subpixel=subpixel_shift(self.ctx))

    def release(self) -> None:
        """Free every GL object this renderer made."""
        with self.ctx:
            self.lit.release()
            self.volumes.release()
            for gl_object in self.extra.values():
                if hasattr(gl_object, "release"):      # a query has nothing to release
                    gl_object.release()
        self.extra = {}

    # --- The passes -------------------------------------------------------------------------

    def _reflect(self, k, scene, shade, planes, width, height, read):
        """Mirror k's planar reflection, added to the picture (``planes``: the opaque
        pass's); with ``read``, the reflected object and triangle planes (H, W) (-1: none)."""
        ctx, camera = self.ctx, scene.camera
        point, normal = self.mirrors[k]
        normal = eye_side_normal(point, normal, camera)
        m = mirror_matrix(point, normal)
        shaders = self.lit.shaders(self.materials, scene.lights, **shade, variant="mirror")
        objects = ~self.clear & (np.arange(len(self.meshes)) != k)
        uniforms = {"mirror": m.T, "plane": (*normal, -float(np.dot(normal, point))),
                    "mask_id": k}
        # Only the mirror's own pixels show its reflection: the mirrored scene, its skybox
        # and the compositing are drawn in the mirror's rectangle on the screen alone.
        rectangle = screen_rectangle([self.meshes[k]], camera, width, height)
        with ctx:
            ctx.enable_direct(CLIP_DISTANCE0)
        try:
            mirrored = self.lit.draw_pass(shaders, camera, width, height, target="mirror",
                                          objects=objects, reads={"mask_ids": planes[2]},
                                          uniforms=uniforms, vertex="raster/mirror.vert",
                                          scissor=rectangle)
        finally:
            with ctx:
                ctx.disable_direct(CLIP_DISTANCE0)
        self._composite(0, mirrored.color_attachments[3], planes[3], width, height,
                        {"ids": planes[2]}, {"mask_id": k, "kr": self.materials[k].kr},
                        scissor=rectangle)
        if not read:
            return None
        ids = _read(ctx, mirrored.color_attachments[2], width, height, 4, "i4")
        drawn = _read(ctx, mirrored.color_attachments[3], width, height, 4)[..., 3] > 0
        return np.where(drawn, ids[..., 0], -1), np.where(drawn, ids[..., 1], -1)

    def _peel(self, scene, shade, planes, width, height):
        """Depth peeling: render.peel_layers passes at most, each layer composited under
        the ones before it, then all of them over the picture; every pass, clear and step
        only in the transparent meshes' rectangle on the screen (nothing changes outside)."""
        ctx = self.ctx
        shaders = self.lit.shaders(self.materials, scene.lights, **shade, variant="peel")
        rectangle = screen_rectangle(keep_only(self.meshes, self.clear), scene.camera, width,
                                     height)
        accumulator = self._texture("accumulator", width, height, 4)
        into_accumulator = self._framebuffer("accumulator", accumulator)
        with ctx:
            previous = self.lit.target("layer b", width, height)[0]
            try:
                for fbo, value in ((into_accumulator, 1.0), (previous, -1.0)):
                    fbo.scissor = rectangle      # the first pass peels from t > -1
                    fbo.clear(0.0, 0.0, 0.0, value)
            finally:
                into_accumulator.scissor = previous.scissor = None
            query = self.extra.setdefault("query", ctx.query(samples=True))
        for layer in range(scene.render.peel_layers):
            name = "layer a" if layer % 2 == 0 else "layer b"
            with ctx:
                current = self.lit.target(name, width, height)[0]
                current.scissor = rectangle
                current.clear(0.0, 0.0, 0.0, NOTHING_PEELED)
                current.scissor = None
            self.lit.draw_pass(shaders, scene.camera, width, height, target=name,
                               objects=self.clear, sky=False, query=query, scissor=rectangle,
                               reads={"opaque_planes": planes[0], "opaque_color": planes[3],
                                      "previous_layer": previous.color_attachments[0]})
            with ctx:
                peeled = query.samples
            if peeled == 0:
                break                    # every pixel's layers are peeled
            self._composite(1, current.color_attachments[3], accumulator, width, height,
                            scissor=rectangle)
            previous = current
        self._composite(2, accumulator, planes[3], width, height, scissor=rectangle)

    def _blend_sorted(self, scene, shade, planes, width, height):
        """Sorted blending: the transparent triangles from the farthest to the nearest (by
        their centroids' distance from the eye, as `reference_cpu.transparency`), each
        blended "over" the picture where it is in front of the opaque surface."""
        ctx = self.ctx
        shaders = self.lit.shaders(self.materials, scene.lights, **shade, variant="sorted")
        with ctx:
            scratch = self.lit.target("layer a", width, height)[0].color_attachments[:3]
        fbo = self._framebuffer(("sorted", id(planes[3])), *scratch, planes[3])
        eye = np.asarray(scene.camera.position, np.float64)
        triangles = [(k, i) for k in np.flatnonzero(self.clear)
                     for i in range(len(self.meshes[k].triangles))]
        distance = [np.linalg.norm(self.meshes[k].positions[self.meshes[k].triangles[i]]
                                   .mean(axis=0) - eye) for k, i in triangles]
        order = [triangles[j] for j in np.argsort(distance, kind="stable")[::-1]]
        with ctx:
            program = self.lit.program(shaders, scene.camera, width, height, reads={
                "opaque_planes": planes[0], "opaque_color": planes[3]})
            fbo.use()
            fbo.viewport = (0, 0, width, height)
            ctx.enable(ctx.BLEND)
            ctx.blend_func = ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA, ctx.ZERO, ctx.ONE
            try:
                start = 0
                while start < len(order):   # runs of one mesh's triangles: one draw each
                    k = order[start][0]
                    end = start
                    while end < len(order) and order[end][0] == k:
                        end += 1
                    program["object_id"].value = int(k)
                    program["material"].write(shaders.materials[k].tobytes())
                    rows = [i for _, i in order[start:end]]
                    vao, ibo = self.lit.vertex_array(program, k, self.meshes[k].triangles[rows])
                    vao.render()
                    vao.release()
                    ibo.release()
                    start = end
            finally:
                ctx.disable(ctx.BLEND)
                ctx.blend_func = ctx.DEFAULT_BLENDING

    def _layer_count(self, scene, planes, width, height) -> np.ndarray:
        """(H, W) int: the transparent surfaces in front of the opaque one, at most
        render.peel_layers (`reference_cpu.transparency.depth_complexity`)."""
        ctx = self.ctx
        counts = self._texture("layer count", width, height, 1)
        fbo = self._framebuffer("layer count", counts)
        with ctx:
            program = _compile(ctx, glsl_file("raster/mesh.vert"),
                               glsl_file("raster/layer_count.frag"))
            _set_camera(program, scene.camera, width, height)
            self.lit._bind(program, {"opaque_planes": planes[0], "opaque_color": planes[3]}, {})
            fbo.use()
            fbo.viewport = (0, 0, width, height)
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            ctx.enable(ctx.BLEND)
            ctx.blend_func = ctx.ONE, ctx.ONE
            try:
                for k in np.flatnonzero(self.clear):
                    self.lit._vertex_array(program, int(k)).render()
            finally:
                ctx.disable(ctx.BLEND)
                ctx.blend_func = ctx.DEFAULT_BLENDING
        layers = _read(ctx, counts, width, height, 1)
        return np.minimum(layers, scene.render.peel_layers).astype(np.int64)

    def _composite(self, step, source, target, width, height, reads=None, uniforms=None,
                   scissor=None):
        """One step of glsl/raster/composite.frag over ``target`` (within ``scissor``, if
        given): 0 adds a mirror's reflection, 1 puts a peeled layer under the accumulator,
        2 the accumulator over the picture. The picture's alpha (1 where drawn) is kept."""
        ctx = self.ctx
        blending = {0: (ctx.ONE, ctx.ONE, ctx.ZERO, ctx.ONE),
                    1: (ctx.DST_ALPHA, ctx.ONE, ctx.ZERO, ctx.ONE_MINUS_SRC_ALPHA),
                    2: (ctx.ONE, ctx.SRC_ALPHA, ctx.ZERO, ctx.ONE)}[step]
        fbo = self._framebuffer(("composite", id(target)), target)
        with ctx:
            program = _compile(ctx, glsl_file("raster/sky.vert"),
                               glsl_file("raster/composite.frag"))
            program["stage"].value = step
            self.lit._bind(program, {"source": source, **(reads or {})}, uniforms or {})
            fbo.use()
            fbo.viewport = (0, 0, width, height)
            fbo.scissor = scissor
            ctx.enable(ctx.BLEND)
            ctx.blend_func = blending
            try:
                vao = self.extra.get(("vao", program))
                if vao is None:
                    vao = self.extra[("vao", program)] = ctx.vertex_array(program, [])
                vao.render(vertices=3)
            finally:
                fbo.scissor = None
                ctx.disable(ctx.BLEND)
                ctx.blend_func = ctx.DEFAULT_BLENDING

    def _texture(self, name, width, height, components):
        key = (name, width, height)
        if key not in self.extra:
            with self.ctx:
                self.extra[key] = self.ctx.texture((width, height), components, dtype="f4")
        return self.extra[key]

    def _framebuffer(self, name, *attachments):
        key = ("fbo", name, *(id(a) for a in attachments))
        if key not in self.extra:
            with self.ctx:
                self.extra[key] = self.ctx.framebuffer(color_attachments=list(attachments))
        return self.extra[key]


def screen_rectangle(meshes, camera: Camera, width: int, height: int):
    """The pixels (x, y, w, h) that ``meshes`` can cover, as a scissor rectangle (x the
    column, y the image's row: GL's window, the picture being drawn upside down): their
    vertices that triangles use, projected as glsl/raster/mesh.vert projects them, with a
    pixel to spare. None
    (the whole screen) if a vertex lies at or behind the near plane, where the projection
    turns over; (0, 0, 0, 0) if they have no vertex on the screen."""
    points = np.concatenate([np.zeros((0, 3))] + [m.positions[np.unique(m.triangles)]
                                                  for m in meshes])   # vertices drawn only
    forward, right, up = camera_basis(camera)
    offset = points - np.asarray(camera.position, np.float64)
    z = offset @ forward
    if np.any(z <= NEAR):
        return None
    if len(points) == 0:
        return (0, 0, 0, 0)
    half_height = np.tan(np.radians(camera.fov) / 2)
    x = ((offset @ right) / (z * half_height * width / height) + 1) * width / 2
    y = (1 - (offset @ up) / (z * half_height)) * height / 2
    low = np.maximum(np.floor([x.min(), y.min()]) - 1, 0).astype(int)
    high = np.minimum(np.ceil([x.max(), y.max()]) + 1, [width, height]).astype(int)
    size = np.maximum(high - low, 0)
    return (int(low[0]), int(low[1]), int(size[0]), int(size[1]))


def _read(ctx, texture, width, height, components, dtype="f4") -> np.ndarray:
    """A texture read back: (H, W) for one component, else (H, W, components)."""
    with ctx:
        data = np.frombuffer(texture.read(), np.int32 if dtype == "i4" else np.float32)
    return data.reshape((height, width) if components == 1 else (height, width, components))


def render(scene: Scene, width: int, height: int, precision: str = "float32",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Draw ``scene``'s meshes on the GPU at ``width`` x ``height`` pixels (float32)."""
    renderer = MeshRenderer(scene)
    try:
        frame = renderer.frame(scene, width, height)
    finally:
        renderer.release()
    if progress is not None:
        progress(1, 1)
    return frame


def check() -> None:
    """Raise MarchlabError, saying what is missing, if OpenGL cannot run here."""
    gl_context()
