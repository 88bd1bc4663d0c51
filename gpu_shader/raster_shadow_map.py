"""Shadow maps on the GPU: the NumPy shadow map (`reference_cpu.shadow_map`) drawn by OpenGL.

The same map, seen the same way: `reference_cpu.shadow_map.light_views` fits the light's
view (an orthographic box along a directional light, one perspective frustum from a point
or spot light, or a cube of six for one among the objects) and both versions take their
matrices from it. Two passes per light:

1. **Depth from the light** (glsl/raster/shadow_map_depth.vert, .frag): every mesh drawn
   into a float32 texture of size x size texels, each holding the depth along the light's
   axis in metres, the quantity the NumPy map stores. Instead of a depth buffer (24-bit,
   and rounded) the texels blend with MIN, so each keeps the nearest of its fragments'
   float32 depths exactly, as `depth_map` keeps ``np.minimum`` of them; +inf where nothing
   is drawn.
2. **The lookup from the camera** (glsl/raster/mesh.vert, glsl/raster/shadow_map_lookup.frag):
   the scene drawn again from the camera; each pixel's surface point, p = eye + t d as the
   lit pipeline reconstructs it, is projected into the map and tested against the stored
   depth plus ``bias`` and a slope bias, over pcf x pcf texels. The result is a visibility
   texture per light, drawn upside down like the raster pipeline's planes (GL row r is
   image row r from the top), which `gpu_shader.raster_lit.draw(..., visibility=...)` takes
   as it is.

Checked against NumPy pixel by pixel in tests/gpu/test_raster_shadow_map.py.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from reference_cpu.rasterise import NEAR
from reference_cpu.shadow_map import CUBE_FACES, MAX_TILT, LightView, light_views
from scene_model.camera import Camera, camera_basis
from scene_model.meshes import TriangleMesh

from .context import gl_context
from .dialects import GLSL
from .library import fill_template, glsl_file, load_library
from .raster import FAR, _set_camera

MAP_UNIT = 0            # the texture unit the lookup reads the map from (a cube's faces
                        # from this unit and the five after it)


def shadow_map_textures(ctx, meshes: list[TriangleMesh], lights, camera: Camera, width: int,
                        height: int, size: int, bias: float, slope_bias: float = 0.0,
                        pcf: int = 1) -> list:
    """Each light's visibility by a shadow map, left on the GPU for a lit pass to sample.

    Parameters
    ----------
    ctx : moderngl.Context
    meshes : list of TriangleMesh
        Every mesh casts (open ones too) and receives.
    lights : sequence of PointLight, SpotLight or DirectionalLight
    camera : Camera
    width, height : int
        The image's size in pixels.
    size, bias, slope_bias, pcf
        As `reference_cpu.shadow_map.shadow_map_visibility`'s: the map's side in texels,
        the bias (m), the slope bias (texels of slope) and the filter's side (odd).

    Returns
    -------
    list of moderngl.Texture
        One W x H single-channel float32 texture per light: 1 lit, 0 shadowed, between with
        PCF, 1 where nothing is drawn; GL row r is the image's row r from the top. The
        caller releases them.
    """
    if pcf < 1 or pcf % 2 == 0:
        raise ValueError(f"pcf must be an odd number of texels (got {pcf})")
    views = [light_views(meshes, light, size) for light in lights]  # refuses a bad light early
    visibilities = [ctx.texture((width, height), 1, dtype="f4") for _ in lights]
    made = []
    try:
        depth_program, lookup_program = _programs(ctx)
        vertex_arrays = []
        for mesh in meshes:
            vertices = np.concatenate([mesh.positions, mesh.normals], axis=1)
            vbo = ctx.buffer(vertices.astype(np.float32).tobytes())
            ibo = ctx.buffer(mesh.triangles.astype(np.int32).tobytes())
            pair = (ctx.vertex_array(depth_program, [(vbo, "3f 12x", "position")],
                                     index_buffer=ibo, index_element_size=4),
                    ctx.vertex_array(lookup_program, [(vbo, "3f 3f", "position", "normal")],
                                     index_buffer=ibo, index_element_size=4))
            made += [vbo, ibo, *pair]
            vertex_arrays.append(pair)
        # One map per light, or a cube's six; every unit the lookup names gets a texture.
        stored = [ctx.texture((size, size), 1, dtype="f4")
                  for _ in range(max(len(faces) for faces in views))]
        depth = ctx.depth_texture((width, height))
        made += [*stored, depth]
        map_fbos = [ctx.framebuffer(color_attachments=[texture]) for texture in stored]
        made += map_fbos
        _set_camera(lookup_program, camera, width, height)
        settings = {"map_size": float(size), "bias": bias, "slope_bias": slope_bias,
                    "max_tilt": MAX_TILT, "reach": pcf // 2, "shadow_map": MAP_UNIT,
                    **{f"shadow_face{k}": MAP_UNIT + k for k in range(1, CUBE_FACES)}}
        for name, value in settings.items():
            _set_uniform(lookup_program, name, value)
        for faces, visibility in zip(views, visibilities):
            for k, view in enumerate(faces):
                draw_depth(ctx, depth_program, [a for a, _ in vertex_arrays], view, map_fbos[k])
            _set_light_view(lookup_program, faces)
            for k in range(CUBE_FACES):
                stored[min(k, len(stored) - 1)].use(location=MAP_UNIT + k)
            screen = ctx.framebuffer(color_attachments=[visibility], depth_attachment=depth)
            made.append(screen)
            screen.use()
            screen.viewport = (0, 0, width, height)
            screen.clear(1.0, 1.0, 1.0, 1.0, depth=1.0)      # 1: lit where nothing is
            ctx.enable(ctx.DEPTH_TEST)
            for _, lookup in vertex_arrays:
                lookup.render()
            ctx.disable(ctx.DEPTH_TEST)
    except BaseException:
        for texture in visibilities:
            texture.release()
        raise
    finally:
        ctx.disable(ctx.DEPTH_TEST | ctx.BLEND)
        ctx.blend_equation = ctx.FUNC_ADD
        for gl_object in reversed(made):
            gl_object.release()
    return visibilities


def draw_depth(ctx, program, vertex_arrays, view: LightView, fbo) -> None:
    """Draw the light's depth map into ``fbo`` (one S x S float32 attachment): the nearest
    depth along the light's axis (m) at each texel centre, +inf where nothing is."""
    _set_light_view(program, [view])
    program["near"].value, program["far"].value = NEAR, FAR
    fbo.use()
    fbo.viewport = (0, 0, view.size, view.size)
    fbo.color_attachments[0].write(np.full((view.size, view.size), np.inf, np.float32))
    ctx.enable(ctx.BLEND)
    ctx.blend_equation = ctx.MIN          # keep the nearest depth: np.minimum, no depth buffer
    try:
        for vertex_array in vertex_arrays:
            vertex_array.render()
    finally:
        ctx.disable(ctx.BLEND)
        ctx.blend_equation = ctx.FUNC_ADD


def depth_map(meshes: list[TriangleMesh], view: LightView) -> np.ndarray:
    """The shadow map (S, S) float32 drawn by OpenGL, row 0 at the top: the twin of
    `reference_cpu.shadow_map.depth_map` (+inf where nothing is)."""
    ctx = gl_context()
    with ctx:
        program, _ = _programs(ctx)
        stored = ctx.texture((view.size, view.size), 1, dtype="f4")
        fbo = ctx.framebuffer(color_attachments=[stored])
        made = [stored, fbo]
        try:
            vertex_arrays = []
            for mesh in meshes:
                vbo = ctx.buffer(mesh.positions.astype(np.float32).tobytes())
                ibo = ctx.buffer(mesh.triangles.astype(np.int32).tobytes())
                vertex_arrays.append(ctx.vertex_array(program, [(vbo, "3f", "position")],
                                                      index_buffer=ibo, index_element_size=4))
                made += [vbo, ibo, vertex_arrays[-1]]
            draw_depth(ctx, program, vertex_arrays, view, fbo)
            texels = np.frombuffer(stored.read(), np.float32).reshape(view.size, view.size)
        finally:
            for gl_object in reversed(made):
                gl_object.release()
    return texels.copy()


def shadow_map_visibility(meshes: list[TriangleMesh], lights, camera: Camera, width: int,
                          height: int, size: int, bias: float, slope_bias: float = 0.0,
                          pcf: int = 1) -> list[np.ndarray]:
    """The visibility (H, W) float32 of each light by a shadow map, read back:
    `reference_cpu.shadow_map.shadow_map_visibility` done by OpenGL for every light
    (arguments as `shadow_map_textures`')."""
    ctx = gl_context()
    with ctx:
        textures = shadow_map_textures(ctx, meshes, lights, camera, width, height, size, bias,
                                       slope_bias, pcf)
        try:
            return [np.frombuffer(t.read(), np.float32).reshape(height, width).copy()
                    for t in textures]
        finally:
            for texture in textures:
                texture.release()


def _set_light_view(program, views: list[LightView]) -> None:
    """The light's frame and projection, as glsl/raster/shadow_map_depth.vert reads them:
    a perspective map looks from the light through tan(fov / 2); an orthographic one from
    the origin along its frame, centred on the map's middle, half its side wide. For a cube
    (six views), the first face's, and each face's frame in the lookup's face arrays."""
    view = views[0]
    if len(views) == CUBE_FACES:
        bases = [camera_basis(v.camera) for v in views]
        for name, k in (("face_forward", 0), ("face_right", 1), ("face_up", 2)):
            _set_uniform(program, name, [tuple(float(x) for x in b[k]) for b in bases])
    _set_uniform(program, "cube", len(views) == CUBE_FACES)
    if view.camera is not None:
        forward, right, up = camera_basis(view.camera)
        eye, center = view.camera.position, (0.0, 0.0)
        half = math.tan(math.radians(view.camera.fov) / 2)
    else:
        right, up, forward = view.frame
        half = view.texel * view.size / 2
        eye, center = (0.0, 0.0, 0.0), tuple(view.low + half)
    values = {"light_eye": tuple(eye), "light_right": tuple(right), "light_up": tuple(up),
              "light_forward": tuple(forward), "light_center": center, "light_half": half,
              "perspective": view.camera is not None}
    for name, value in values.items():
        program[name].value = value


def _set_uniform(program, name: str, value) -> None:
    """Set a uniform the program has; the depth pass's program has no lookup's uniforms."""
    uniform = program.get(name, None)
    if uniform is not None:
        uniform.value = value


_compiled: dict[int, tuple] = {}


def _programs(ctx) -> tuple:
    """The depth and lookup programs on ``ctx``, compiled on first use and kept."""
    if id(ctx) not in _compiled:
        _compiled[id(ctx)] = (
            ctx.program(vertex_shader=glsl_file("raster/shadow_map_depth.vert"),
                        fragment_shader=glsl_file("raster/shadow_map_depth.frag")),
            ctx.program(vertex_shader=glsl_file("raster/mesh.vert"),
                        fragment_shader=lookup_source()))
    return _compiled[id(ctx)]


@cache
def lookup_source() -> str:
    """glsl/raster/shadow_map_lookup.frag filled in with the camera's ray (glsl/camera.glsl)."""
    return fill_template("raster/shadow_map_lookup.frag", prelude=GLSL.prelude,
                         camera_ray=load_library("camera").select(["camera_ray"]))
