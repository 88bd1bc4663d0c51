"""The raster pipeline on the GPU: triangle meshes drawn by OpenGL's own rasteriser.

The same steps as the NumPy rasteriser (`reference_cpu.rasterise`), done by the driver: the
vertex shader (glsl/raster/mesh.vert) puts each vertex through marchlab's camera, OpenGL
clips at the near plane, snaps corners to its sub-pixel grid, applies its fill rule and
interpolates perspective-correctly, and the fragment shader (glsl/raster/mesh.frag) writes
what the depth buffer keeps: the normal and ray distance t, the texture coordinates, and the
object and triangle (gl_PrimitiveID). Reading the planes back gives a `Raster`, so the two
rasterisers compare pixel by pixel (tests/gpu/test_raster_pipeline.py).

The picture is drawn upside down in GL's window (its y grows upwards, the image's rows
downwards), which leaves GL row r holding image row r from the top, as the sphere tracer's
planes do, and makes GL's fill rule, applied in window coordinates, the image's top-left rule.

The lit pipeline, which shades its pixels in the same draw, is `gpu_shader.raster_lit`; the
raster backend's whole frame (shadows, mirrors, transparency) is `gpu_shader.raster_render`.
"""

from __future__ import annotations

import math

import numpy as np

from reference_cpu.rasterise import NEAR, Raster
from scene_model.camera import Camera, camera_basis
from scene_model.meshes import TriangleMesh

from .context import gl_context
from .library import glsl_file

FAR = 1e5            # the far clipping plane (m); depth is tested on view depth / FAR


def rasterise(meshes: list[TriangleMesh], camera: Camera, width: int, height: int,
              cull_back_faces: bool = False) -> Raster:
    """Draw ``meshes`` on the GPU: `reference_cpu.rasterise.rasterise` done by OpenGL.

    Returns
    -------
    Raster
        With ``coverage`` None: the GPU does not count the triangles behind the one kept.
    """
    ctx = gl_context()
    with ctx:
        program = _program(ctx)
        planes = [ctx.texture((width, height), 4, dtype=dtype) for dtype in ("f4", "f4", "i4")]
        depth = ctx.depth_texture((width, height))
        fbo = ctx.framebuffer(color_attachments=planes, depth_attachment=depth)
        made = [*planes, depth, fbo]
        try:
            _set_camera(program, camera, width, height)
            fbo.use()
            fbo.viewport = (0, 0, width, height)
            fbo.clear(depth=1.0)
            fbo.color_attachments[2].write(np.full((height, width, 4), -1, np.int32).tobytes())
            ctx.enable(ctx.DEPTH_TEST)
            if cull_back_faces:
                ctx.enable(ctx.CULL_FACE)
                # Drawn upside down, a face wound outward turns clockwise in GL's window.
                ctx.front_face = "cw"
            for k, mesh in enumerate(meshes):
                program["object_id"].value = k
                made += _draw(ctx, program, mesh)
            normal_depth = np.empty((height, width, 4), np.float32)
            uv = np.empty((height, width, 4), np.float32)
            ids = np.empty((height, width, 4), np.int32)
            fbo.read_into(normal_depth, components=4, attachment=0, dtype="f4")
            fbo.read_into(uv, components=4, attachment=1, dtype="f4")
            fbo.read_into(ids, components=4, attachment=2, dtype="i4")
        finally:
            ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)
            ctx.front_face = "ccw"
            for gl_object in reversed(made):
                gl_object.release()
    return _raster(normal_depth, uv, ids, ids[..., 0] >= 0)


def _raster(normal_depth, uv, ids, hit) -> Raster:
    """The `Raster` of the planes read back (H, W, 4 each), where ``hit`` (H, W)."""
    return Raster(depth=np.where(hit, normal_depth[..., 3].astype(np.float64), np.inf),
                  normal=np.where(hit[..., None], normal_depth[..., :3], 0.0).astype(np.float64),
                  uv=np.where(hit[..., None], uv[..., :2], 0.0).astype(np.float64),
                  object_id=np.where(hit, ids[..., 0], -1).astype(np.int64),
                  triangle=np.where(hit, ids[..., 1], -1).astype(np.int64),
                  coverage=None)


_programs: dict[int, object] = {}


def _program(ctx):
    """The mesh program on ``ctx``, compiled on first use and kept (one per context)."""
    if id(ctx) not in _programs:
        _programs[id(ctx)] = ctx.program(vertex_shader=glsl_file("raster/mesh.vert"),
                                         fragment_shader=glsl_file("raster/mesh.frag"))
    return _programs[id(ctx)]


def _set_camera(program, camera: Camera, width: int, height: int) -> None:
    forward, right, up = camera_basis(camera)
    half_height = math.tan(math.radians(camera.fov) / 2)
    values = {"eye": tuple(camera.position), "right": tuple(right), "up": tuple(up),
              "forward": tuple(forward), "half_height": half_height,
              "half_width": half_height * width / height,       # as camera_rays rounds it
              "aspect": width / height, "near": NEAR, "far": FAR, "size": (width, height)}
    for name, value in values.items():
        if name in program:
            program[name].value = value


def _draw(ctx, program, mesh: TriangleMesh) -> list:
    """Draw one mesh with ``program``; the GL objects made, for the caller to release."""
    vertices = np.concatenate([mesh.positions, mesh.normals, mesh.uvs], axis=1)
    vbo = ctx.buffer(vertices.astype(np.float32).tobytes())
    ibo = ctx.buffer(mesh.triangles.astype(np.int32).tobytes())
    vao = ctx.vertex_array(program, [(vbo, "3f 3f 2f", "position", "normal", "uv")],
                           index_buffer=ibo, index_element_size=4)
    vao.render()
    return [vbo, ibo, vao]
