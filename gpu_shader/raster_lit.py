"""The lit raster pipeline on the GPU: triangle meshes drawn and shaded in one draw.

`gpu_shader.raster` finds what each pixel shows; here a fragment shader generated for the
scene (glsl/raster/lit.frag) writes those planes, then the colour, with the sphere tracer's
own GLSL (glsl/lights.glsl, shading.glsl, texture.glsl and the shading template
glsl/pipeline/shade.glsl), so that it equals `reference_cpu.raster_shading.shade_raster`
(tests/gpu/test_raster_lit.py). Pixels no triangle covers show the background, drawn last as
a skybox (glsl/raster/sky.frag).

The shaders are generated in `gpu_shader.raster_shaders` (`lit_shaders`); here is what draws
with them: `RasterRenderer` (the meshes' buffers uploaded once), `read_planes` and `draw`.
"""

from __future__ import annotations

import contextlib

import numpy as np

from reference_cpu.rasterise import Raster
from scene_model.camera import Camera
from scene_model.meshes import TriangleMesh

from .context import gl_context
from .library import glsl_file
from .raster import _raster, _set_camera
from .raster_shaders import LitShaders, _compile, _light_reads, lit_shaders


# --- Drawing: buffers uploaded once, a frame sets uniforms and draws -------------------------

ATLAS_UNIT, PLANES_UNIT, FIRST_PLANE_UNIT = 1, 2, 3        # texture units
PASS_UNIT = 12          # the first of the textures a pass reads (`RasterRenderer.draw_pass`)
KEPT_SHADERS = 16       # `RasterRenderer.shaders` keeps this many generated sets at most


def _set_uniforms(program, values: dict) -> None:
    """Write ``values`` (by uniform name, numbers or arrays) into those of ``program`` that
    it reads. The compiler drops the rest, and the end of an array after the last element
    read (a light array of lights 0 and 1 that only light 0 needs has one element)."""
    for name, value in values.items():
        if name in program:
            uniform = program[name]
            if uniform.gl_type in (0x1404, 0x8B56):      # GL_INT, GL_BOOL
                uniform.value = int(value)
                continue
            value = np.asarray(value, np.float32).ravel()
            program[name].write(value[:uniform.array_length * uniform.dimension].tobytes())


class RasterRenderer:
    """The lit raster pipeline on one context, for one list of meshes: their vertex and index
    buffers uploaded once, so that a frame sets uniforms, draws and (`draw`) reads back.

    Parameters
    ----------
    meshes : list of TriangleMesh
        Mesh k is object k, drawn with ``materials[k]`` (a mesh without triangles is skipped).
    ctx : moderngl.Context, optional
        Default: the process's (`gpu_shader.context.gl_context`).
    """

    def __init__(self, meshes: list[TriangleMesh], ctx=None):
        self.ctx = ctx or gl_context()
        self.meshes = list(meshes)
        with self.ctx:
            self.buffers = [(self.ctx.buffer(np.concatenate(
                [m.positions, m.normals, m.uvs], axis=1).astype(np.float32).tobytes()),
                self.ctx.buffer(m.triangles.astype(np.int32).tobytes()))
                if len(m.triangles) else None for m in self.meshes]
        self.vertex_arrays: dict = {}       # (program, mesh index or "sky"): vertex array
        self.targets: dict = {}             # (name, W, H): (all planes, colour and depth only)
        self.textures: dict = {}            # "atlas" / "planes": (key, texture)
        self.generated: dict = {}           # what `shaders` was asked for: its LitShaders

    def draw(self, materials, lights, camera: Camera, width: int, height: int,
             **settings) -> tuple[np.ndarray, Raster]:
        """Draw one frame and read it back (arguments as the module's `draw`)."""
        fbo = self.draw_planes(materials, lights, camera, width, height, **settings)
        color, raster = read_planes(self.ctx, fbo, width, height)
        return color, raster

    def draw_planes(self, materials, lights, camera: Camera, width: int, height: int, *,
                    ambient=(0.0, 0.0, 0.0), model: str = "phong", background=(0.0, 0.0, 0.0),
                    toon_bands: int = 4, visibility=None, cull_back_faces: bool = False,
                    fog=None, depth_range: float = 100.0, objects=None):
        """Draw one frame and leave it on the GPU; return its framebuffer: attachments 0 to
        3 hold normal and depth, uv, ids (as `rasterise`'s) and the colour (alpha 1 where
        a triangle is drawn, 0 on the background). ``fog`` and ``depth_range`` as
        `lit_shaders`'; ``objects`` (K,) bool, which meshes to draw (default all)."""
        shaders = self.shaders(materials, lights, ambient=ambient, model=model,
                               background=background, toon_bands=toon_bands,
                               visibility=visibility, fog=fog, depth_range=depth_range)
        return self.draw_pass(shaders, camera, width, height, objects=objects,
                              visibility=visibility, cull_back_faces=cull_back_faces)

    def shaders(self, materials, lights, **settings) -> LitShaders:
        """`lit_shaders` for these meshes, after checking there is a material for each."""
        if len(materials) != len(self.meshes):
            raise ValueError(f"expected a material for each of the {len(self.meshes)} meshes, "
                             f"got {len(materials)}")
        # A frame's passes ask again for the same shaders every frame: generating them (a
        # template filled in, the material rows) costs milliseconds, so they are kept by
        # what they are made of (of the visibility, only its kinds: the textures are bound
        # by `draw_pass`).
        planes = settings.get("visibility")
        kinds = None if planes is None else tuple(_light_reads(p) for p in planes)
        key = repr((materials, lights, kinds, sorted((k, v) for k, v in settings.items()
                                                     if k != "visibility")))
        if key not in self.generated:
            if len(self.generated) >= KEPT_SHADERS:
                self.generated.clear()
            self.generated[key] = lit_shaders(materials, lights, **settings)
        return self.generated[key]

    def draw_pass(self, shaders: LitShaders, camera: Camera, width: int, height: int, *,
                  target: str = "frame", objects=None, visibility=None, reads=None,
                  uniforms=None, vertex: str = "raster/mesh.vert", clear: bool = True,
                  sky: bool = True, cull_back_faces=False, front_face: str = "cw",
                  query=None, scissor=None):
        """Draw ``objects`` with ``shaders`` into the planes of ``target`` (one set of
        framebuffers per name and size) and return its framebuffer.

        ``reads`` maps sampler names to textures the pass reads (bound from `PASS_UNIT`),
        ``uniforms`` holds the pass's other numbers; ``vertex`` is the vertex shader's file.
        With ``clear``, the colour is cleared to the background's and the depth to 1 first;
        with ``sky``, the skybox fills what no triangle covers. ``cull_back_faces``, one bool
        or (K,) bools, one per mesh, skips the back faces of those meshes
        (`reference_cpu.back_faces` says when that changes nothing); ``front_face`` is the
        winding of a front face in GL's window ("cw" drawn upside down; "ccw" mirrored as
        well).
        A ``query`` (moderngl.Query) counts the samples of the meshes' fragments that pass.
        A ``scissor`` (x, y, w, h) in pixels (GL's window: y is the image's row) limits the
        clear, the meshes and the skybox to that rectangle
        (`gpu_shader.raster_render.screen_rectangle`).
        Like every method here it makes the context current itself: call it outside a
        ``with ctx`` block (moderngl's are not reentrant: the inner one's end releases it).
        """
        ctx = self.ctx
        with ctx:
            fbo, sky_fbo = self.target(target, width, height)
            program = self.program(shaders, camera, width, height, vertex=vertex,
                                   visibility=visibility, reads=reads, uniforms=uniforms)
            try:
                if clear:
                    sky_fbo.use()
                    sky_fbo.viewport = (0, 0, width, height)
                    sky_fbo.scissor = scissor
                    sky_fbo.clear(*shaders.clear, 0.0, depth=1.0)
                fbo.use()
                fbo.viewport = (0, 0, width, height)
                fbo.scissor = scissor
                ctx.enable(ctx.DEPTH_TEST)
                ctx.front_face = front_face
                cull = np.broadcast_to(cull_back_faces, (len(self.meshes),))
                culling = None                  # GL's CULL_FACE as last set in this pass
                with query or contextlib.nullcontext():
                    for k, rows in enumerate(shaders.materials):
                        if self.buffers[k] is None or (objects is not None and not objects[k]):
                            continue
                        if cull[k] != culling:
                            culling = bool(cull[k])
                            (ctx.enable if culling else ctx.disable)(ctx.CULL_FACE)
                        program["object_id"].value = k
                        if "material" in program:
                            program["material"].write(rows.tobytes())
                        self._vertex_array(program, k).render()
                ctx.disable(ctx.CULL_FACE)          # the skybox's one triangle faces any way
                if sky and shaders.sky_source:
                    program = self.program(shaders, camera, width, height, sky=True,
                                           uniforms=uniforms)
                    sky_fbo.use()
                    sky_fbo.scissor = scissor
                    ctx.depth_func = "<="       # only where the depth is still the clear's 1
                    self._vertex_array(program, "sky").render(vertices=3)
            finally:
                fbo.scissor = sky_fbo.scissor = None
                ctx.depth_func = "<"
                ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)
                ctx.front_face = "ccw"
        return fbo

    def release(self) -> None:
        """Free every GL object this renderer made (its programs stay compiled)."""
        with self.ctx:
            made = [*self.vertex_arrays.values(),
                    *(b for pair in self.buffers if pair for b in pair),
                    *(t for _, t in self.textures.values())]
            for fbo, sky_fbo in self.targets.values():
                made += [sky_fbo, fbo, *fbo.color_attachments, fbo.depth_attachment]
            for gl_object in made:
                gl_object.release()
        self.vertex_arrays, self.buffers, self.targets, self.textures = {}, [], {}, {}

    def program(self, shaders: LitShaders, camera: Camera, width: int, height: int, *,
                vertex: str = "raster/mesh.vert", sky: bool = False, visibility=None,
                reads=None, uniforms=None):
        """The meshes' program of ``shaders`` (the skybox's with ``sky``), compiled on first
        use, with this frame's camera, numbers and textures set (as `draw_pass` takes them)."""
        program = (_compile(self.ctx, glsl_file("raster/sky.vert"), shaders.sky_source) if sky
                   else _compile(self.ctx, glsl_file(vertex), shaders.source))
        self._prepare(program, shaders, camera, width, height, visibility)
        self._bind(program, reads, uniforms)
        return program

    def vertex_array(self, program, k: int, triangles: np.ndarray):
        """A vertex array of mesh k's vertices with its own ``triangles`` (T, 3) (the caller
        releases it and the index buffer it returns): part of a mesh, in an order."""
        ibo = self.ctx.buffer(np.ascontiguousarray(triangles, np.int32).tobytes())
        vao = self.ctx.vertex_array(program, [(self.buffers[k][0], *_layout(program))],
                                    index_buffer=ibo, index_element_size=4)
        return vao, ibo

    def _bind(self, program, reads, uniforms) -> None:
        """Bind the textures a pass reads, from `PASS_UNIT` on, and set its other uniforms."""
        for unit, (name, texture) in enumerate((reads or {}).items(), PASS_UNIT):
            if name in program:
                texture.use(location=unit)
                program[name].value = unit
        _set_uniforms(program, uniforms or {})

    def _prepare(self, program, shaders: LitShaders, camera, width, height, visibility):
        """Set a program's camera, numbers and textures for this frame."""
        _set_camera(program, camera, width, height)
        _set_uniforms(program, shaders.uniforms)
        if shaders.texels is not None and "texels" in program:
            self._texture("atlas", id(shaders.texels), lambda: self._atlas(shaders.texels)
                          ).use(location=ATLAS_UNIT)
            program["texels"].value = ATLAS_UNIT
        arrays = [p for p in visibility or [] if isinstance(p, np.ndarray)]
        if arrays and "visibility_planes" in program:
            if any(p.shape != (height, width) for p in arrays):
                raise ValueError(f"visibility planes must be ({height}, {width}) arrays, got "
                                 f"{', '.join(str(p.shape) for p in arrays)}")
            size = (width, height, len(arrays))
            planes = self._texture("planes", size, lambda: self.ctx.texture_array(
                size, 1, dtype="f4"))
            planes.write(np.ascontiguousarray(arrays, np.float32).tobytes())
            planes.use(location=PLANES_UNIT)
            program["visibility_planes"].value = PLANES_UNIT
        for i, plane in enumerate(visibility or []):
            if plane is not None and not isinstance(plane, np.ndarray):
                # A texture drawn on the GPU (a ShadowCount holds one).
                if f"visibility{i}" in program:   # none read by "normals" or "depth"
                    getattr(plane, "texture", plane).use(location=FIRST_PLANE_UNIT + i)
                    program[f"visibility{i}"].value = FIRST_PLANE_UNIT + i

    def _texture(self, slot: str, key, make):
        """The texture kept in ``slot`` if made for ``key``, else a new one from ``make``."""
        if slot in self.textures and self.textures[slot][0] == key:
            return self.textures[slot][1]
        if slot in self.textures:
            self.textures[slot][1].release()
        self.textures[slot] = (key, make())
        return self.textures[slot][1]

    def _atlas(self, texels: np.ndarray):
        """The atlas (R, W, 4) as an RGBA32F texture, read texel by texel with texelFetch."""
        rows, width, _ = texels.shape
        texture = self.ctx.texture((width, rows), 4, np.ascontiguousarray(texels).tobytes(),
                                   dtype="f4")
        texture.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        return texture

    def target(self, name: str, width: int, height: int):
        """The framebuffers ``name`` at this size, made on first use: the four planes with
        a depth buffer, and the colour plane alone with the same depth buffer (the clear
        and the skybox write only colour)."""
        if (name, width, height) not in self.targets:
            planes = [self.ctx.texture((width, height), 4, dtype=dtype)
                      for dtype in ("f4", "f4", "i4", "f4")]
            depth = self.ctx.depth_texture((width, height))
            self.targets[(name, width, height)] = (
                self.ctx.framebuffer(color_attachments=planes, depth_attachment=depth),
                self.ctx.framebuffer(color_attachments=planes[3:], depth_attachment=depth))
        return self.targets[(name, width, height)]

    def _vertex_array(self, program, part):
        """The vertex array of mesh ``part`` (or the skybox's triangle) for ``program``."""
        key = (program, part)
        if key not in self.vertex_arrays:
            if part == "sky":
                self.vertex_arrays[key] = self.ctx.vertex_array(program, [])
            else:
                vbo, ibo = self.buffers[part]
                self.vertex_arrays[key] = self.ctx.vertex_array(
                    program, [(vbo, *_layout(program))],
                    index_buffer=ibo, index_element_size=4)
        return self.vertex_arrays[key]


def _layout(program) -> tuple:
    """The vertex buffer's layout "3f 3f 2f" (position, normal, uv) as ``program`` reads it:
    (format, *names), an attribute it does not read (the compiler dropped it) skipped."""
    parts, names = [], []
    for name, count in (("position", 3), ("normal", 3), ("uv", 2)):
        parts.append(f"{count}f" if name in program else f"{count}x4")
        names += [name] * (name in program)
    return (" ".join(parts), *names)


def read_planes(ctx, fbo, width: int, height: int) -> tuple[np.ndarray, Raster]:
    """A frame's colour (H, W, 3) and `Raster`, read back from the planes of ``fbo``."""
    planes = [np.empty((height, width, 4), dtype) for dtype in
              (np.float32, np.float32, np.int32, np.float32)]
    with ctx:
        for k, plane in enumerate(planes):
            fbo.read_into(plane, components=4, attachment=k, dtype=plane.dtype.str[1:])
    normal_depth, uv, ids, color = planes
    return color[..., :3].copy(), _raster(normal_depth, uv, ids, color[..., 3] > 0)


def draw(meshes: list[TriangleMesh], materials, lights, camera: Camera, width: int,
         height: int, *, ambient=(0.0, 0.0, 0.0), model: str = "phong",
         background=(0.0, 0.0, 0.0), toon_bands: int = 4, visibility=None,
         cull_back_faces: bool = False) -> tuple[np.ndarray, Raster]:
    """Draw and shade ``meshes`` on the GPU: `rasterise`, then
    `reference_cpu.raster_shading.shade_raster`, in one draw.

    Parameters
    ----------
    meshes : list of TriangleMesh
    materials : list of Material
        One per mesh: its colour, checkerboard or texture, ka, kd, ks and shininess.
    lights : sequence of lights (`scene_model.scene`)
    camera : Camera
    width, height : int
    ambient, model, background, toon_bands
        As `shade_raster`'s: the ambient light (linear RGB), "phong", "blinn_phong", "toon",
        "stripes" or "normals", a colour or a `Background` (the skybox), the toon bands.
    visibility : sequence, optional
        One entry per light, how much of it reaches the surface at each pixel (0 to 1):
        None (all of it), an (H, W) array, or a moderngl texture of W x H texels whose red
        channel holds it (GL row r the image's row r from the top, as the planes here), e.g.
        a shadow mask drawn on the GPU. It scales the light's diffuse and specular terms.
    cull_back_faces : bool
        As `rasterise`'s.

    Returns
    -------
    color : (H, W, 3) float32 ndarray
        Linear RGB, unclamped, as `shade_raster`'s.
    raster : Raster
        The planes the colour was shaded from (``coverage`` None).
    """
    renderer = RasterRenderer(meshes)
    try:
        return renderer.draw(materials, lights, camera, width, height, ambient=ambient,
                             model=model, background=background, toon_bands=toon_bands,
                             visibility=visibility, cull_back_faces=cull_back_faces)
    finally:
        renderer.release()
