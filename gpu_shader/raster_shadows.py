"""Shadow volumes on the GPU: depth-fail with caps, counted by additive blending.

The same volumes as the NumPy reference (`reference_cpu.shadow_volumes`, whose silhouette
edges and light-facing triangles it reuses), drawn by OpenGL as Everitt and Kilgard draw
them ("Practical and Robust Stenciled Shadow Volumes", 2002): extruded vertices are points
at infinity (w = 0) and the projection has its far plane at infinity
(glsl/raster/shadow_volume.vert), so nothing of a volume is ever clipped away behind.

**The count.** Their algorithm counts in the stencil buffer: with the depth test as usual
and depth writes off, a back face's fragment that *fails* the depth test adds 1, a front
face's subtracts 1. moderngl 5 has no stencil state in its Python interface (no stencil
function or operations, and its depth textures have no stencil bits), so the count is kept
in a float texture instead: additive blending (ONE, ONE) sums +1 (back face) and -1 (front
face) from the fragment shader, and the depth test is set to pass exactly the fragments a
stencil test would count, those not in front of the surface drawn (GEQUAL: LESS fails).
The sum is the stencil value, without its 8-bit wrap-around; small integers are exact in
float32.

**Drawing order.** The scene's depth is drawn first, by the volume program itself, from the
same vertex buffers that hold the volumes: a front cap triangle is the very triangle the
scene pass drew, so it lands on the same depth to the last bit and is counted where it is
the surface drawn, as the depth-fail rule asks. Then, per light, the volumes of every
closed mesh (open ones cast none) into that light's count texture. A directional light's
extruded vertices are all one point at infinity, so its back cap has no area (their
section 5.3): it is drawn, and covers nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reference_cpu.shadow_volumes import facing_light, light_source, neighbours, silhouette_edges
from scene_model.camera import Camera
from scene_model.meshes import TriangleMesh

from .context import gl_context
from .library import glsl_file
from .raster import _set_camera

DEPTH_SCALE = 1.0       # m: depth is stored as z / (z + DEPTH_SCALE) (shadow_volume.frag)


@dataclass
class ShadowCounts:
    """What `draw_shadow_counts` leaves on the GPU, rows as image rows (top first).

    Attributes
    ----------
    depth : moderngl.Texture
        The scene's depth, z / (z + `DEPTH_SCALE`) for view depth z; 1.0 where nothing is.
    counts : list of moderngl.Texture
        One single-channel float32 texture per light: the depth-fail stencil count, 0 where
        the surface drawn is lit by that light (and meaningless where nothing is drawn).
    """
    depth: object
    counts: list

    def release(self) -> None:
        for texture in [self.depth, *self.counts]:
            texture.release()


def volume_vertices(mesh: TriangleMesh, light) -> np.ndarray:
    """(2V, 4) float32 homogeneous vertices: the mesh's own (w = 1), then each extruded to
    infinity away from the light (w = 0): p - L for a point light, its direction for a
    directional one."""
    position, direction = light_source(light)
    at_infinity = (mesh.positions - position if position is not None
                   else np.broadcast_to(direction, mesh.positions.shape))
    return np.concatenate([np.c_[mesh.positions, np.ones(len(mesh.positions))],
                           np.c_[at_infinity, np.zeros(len(mesh.positions))]]).astype(np.float32)


def volume_triangles(mesh: TriangleMesh, light) -> np.ndarray:
    """(T', 3) int32 indices into `volume_vertices`: the front cap (light-facing triangles),
    the sides (each silhouette edge a -> b as the quad b, a, a', b') and the back cap
    (light-averted triangles at infinity), all wound outward, as in the NumPy reference."""
    count = len(mesh.positions)
    lit = facing_light(mesh, light)
    a, b = silhouette_edges(mesh, light).T
    sides = np.concatenate([np.stack([b, a, a + count], 1),
                            np.stack([b, a + count, b + count], 1)])
    return np.concatenate([mesh.triangles[lit], sides,
                           mesh.triangles[~lit] + count]).astype(np.int32)


class ShadowVolumes:
    """The shadow volumes of one list of meshes on one context, kept on the GPU between
    frames: the meshes' depth buffers uploaded once, each light's volumes built again only
    when the light changes (a moved camera needs none: the volumes are in world space), the
    depth and count textures made once per size. `draw` draws a frame's counts.

    Parameters
    ----------
    meshes : list of TriangleMesh
        Every opaque mesh, in world coordinates: all of them write depth, the closed ones
        (`reference_cpu.shadow_volumes.neighbours`) cast.
    ctx : moderngl.Context
    """

    def __init__(self, meshes: list[TriangleMesh], ctx):
        self.ctx = ctx
        self.meshes = [m for m in meshes if len(m.triangles)]
        self.closed = [neighbours(m) is not None for m in self.meshes]
        self.program = _program(ctx)
        self.scene = [_upload(ctx, self.program, np.c_[m.positions, np.ones(len(m.positions))],
                              m.triangles) for m in self.meshes]
        self.volumes: dict = {}             # (mesh index, light): its volume's GL objects
        self.targets: dict = {}             # (W, H, lights): depth, counts, framebuffers

    def draw(self, lights, camera: Camera, width: int, height: int) -> ShadowCounts:
        """Draw the scene's depth and every light's shadow volumes (the textures returned
        belong to this object: drawn again next frame, released by `release`)."""
        ctx, program = self.ctx, self.program
        depth, counts, scene, fbos = self._target(width, height, len(lights))
        try:
            _set_camera(program, camera, width, height)
            program["depth_scale"].value = DEPTH_SCALE
            scene.use()
            scene.viewport = (0, 0, width, height)
            scene.clear(depth=1.0)
            ctx.enable(ctx.DEPTH_TEST)
            ctx.front_face = "cw"                  # drawn upside down (gpu_shader/raster.py)
            for _, _, vao in self.scene:           # every mesh writes depth, closed or not
                vao.render()
            ctx.depth_func = ">="                  # depth-fail: count where LESS fails
            ctx.enable(ctx.BLEND)
            ctx.blend_func = ctx.ONE, ctx.ONE
            ctx.blend_equation = ctx.FUNC_ADD
            for light, fbo in zip(lights, fbos):
                fbo.use()
                fbo.viewport = (0, 0, width, height)
                fbo.depth_mask = False
                fbo.clear(0.0, 0.0, 0.0, 0.0)
                for k, mesh in enumerate(self.meshes):
                    if self.closed[k]:
                        self._volume(k, light).render()
                fbo.depth_mask = True
        finally:
            ctx.disable(ctx.DEPTH_TEST | ctx.BLEND)
            ctx.depth_func = "<"
            ctx.blend_func = ctx.DEFAULT_BLENDING
            ctx.front_face = "ccw"
        return ShadowCounts(depth, counts)

    def release(self, keep=()) -> None:
        """Free every GL object made here but the textures in ``keep``."""
        made = [o for objects in [*self.scene, *self.volumes.values()] for o in objects]
        for depth, counts, scene, fbos in self.targets.values():
            made += [*fbos, scene] + [t for t in [depth, *counts] if t not in keep]
        for gl_object in made:
            gl_object.release()
        self.scene, self.volumes, self.targets = [], {}, {}

    def _volume(self, k: int, light):
        """The vertex array of mesh k's volume for ``light``, built when the light is new."""
        key = (k, repr(light))
        if key not in self.volumes:
            for old in [old for old in self.volumes if old[0] == k]:
                for gl_object in self.volumes.pop(old):
                    gl_object.release()
            mesh = self.meshes[k]
            self.volumes[key] = _upload(self.ctx, self.program, volume_vertices(mesh, light),
                                        volume_triangles(mesh, light))
        return self.volumes[key][2]

    def _target(self, width: int, height: int, lights: int):
        key = (width, height, lights)
        if key not in self.targets:
            depth = self.ctx.depth_texture((width, height))
            counts = [self.ctx.texture((width, height), 1, dtype="f4") for _ in range(lights)]
            self.targets[key] = (depth, counts, self.ctx.framebuffer(depth_attachment=depth),
                                 [self.ctx.framebuffer(color_attachments=[c],
                                                       depth_attachment=depth) for c in counts])
        return self.targets[key]


def draw_shadow_counts(ctx, meshes: list[TriangleMesh], lights, camera: Camera, width: int,
                       height: int) -> ShadowCounts:
    """Draw the scene's depth and every light's shadow volumes; leave the counts on the GPU
    (for a lit pass to sample). The caller releases the returned textures."""
    volumes = ShadowVolumes(meshes, ctx)
    drawn = None
    try:
        drawn = volumes.draw(lights, camera, width, height)
    finally:
        volumes.release(keep=[drawn.depth, *drawn.counts] if drawn else ())
    return drawn


def shadow_volume_visibility(meshes: list[TriangleMesh], lights, camera: Camera, width: int,
                             height: int) -> list[np.ndarray]:
    """The visibility (H, W) of each light, 0 in shadow and 1 lit or where nothing is drawn:
    `reference_cpu.shadow_volumes.shadow_volume_visibility` done by OpenGL for every light."""
    ctx = gl_context()
    with ctx:
        drawn = draw_shadow_counts(ctx, meshes, lights, camera, width, height)
        try:
            depth = np.frombuffer(drawn.depth.read(), np.float32).reshape(height, width)
            counts = [np.frombuffer(c.read(), np.float32).reshape(height, width)
                      for c in drawn.counts]
        finally:
            drawn.release()
    hit = depth < 1.0
    return [np.where(hit & (c != 0), 0.0, 1.0) for c in counts]


_programs: dict[int, object] = {}


def _program(ctx):
    """The shadow volume program on ``ctx``, compiled on first use and kept."""
    if id(ctx) not in _programs:
        _programs[id(ctx)] = ctx.program(
            vertex_shader=glsl_file("raster/shadow_volume.vert"),
            fragment_shader=glsl_file("raster/shadow_volume.frag"))
    return _programs[id(ctx)]


def _upload(ctx, program, vertices: np.ndarray, triangles: np.ndarray) -> tuple:
    """Indexed triangles of homogeneous vertices (N, 4) on the GPU: (vbo, ibo, vao)."""
    vbo = ctx.buffer(np.ascontiguousarray(vertices, np.float32).tobytes())
    ibo = ctx.buffer(np.ascontiguousarray(triangles, np.int32).tobytes())
    vao = ctx.vertex_array(program, [(vbo, "4f", "position")], index_buffer=ibo,
                           index_element_size=4)
    return vbo, ibo, vao
