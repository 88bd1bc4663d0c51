"""A mesh picture shown by the live view's display pass: the raster planes as display planes.

The raster backend (`gpu_shader.raster_render.MeshRenderer.draw`) leaves four planes on the
GPU: normal and depth, uv, ids (object, triangle) and the colour. The display pass
(`gpu_shader.display.Display`) reads the sphere tracer's three (`gpu_shader.planes`). One
full-screen draw of ``glsl/raster/display_planes.frag`` turns the first into the second, on
the GPU, so that a mesh scene is shown with the same overlays, gamma and selection outline:

    0  colour, clipped to [0, 1]; 1 on a hit       (as `reference_cpu.raster_render.mesh_frame`)
    1  normal; depth t, inf on a miss              (as `gpu_shader.raster.read_planes`)
    2  steps 0 (a rasteriser marches nothing); object id, -1 on a miss; path label 0; 0

`display_planes_numpy` is the pass in NumPy, its twin for the tests.
"""

from __future__ import annotations

import numpy as np

from .library import glsl_file

NORMAL_DEPTH, IDS, COLOUR = 0, 2, 3     # the raster framebuffer's attachments read here


def display_planes_numpy(normal_depth: np.ndarray, ids: np.ndarray, colour: np.ndarray):
    """The display planes of a raster frame, in NumPy (what the shader writes).

    Parameters
    ----------
    normal_depth, colour : (H, W, 4) float32 ndarrays
        The raster planes 0 (normal xyz, depth t) and 3 (linear rgb, alpha 1 where drawn).
    ids : (H, W, 4) int32 ndarray
        The raster plane 2 (x object, y triangle).

    Returns
    -------
    (color_hit, normal_depth, steps_id) : (H, W, 4) float32, float32 and int32 ndarrays
    """
    hit = colour[..., 3] > 0.0
    color_hit = np.concatenate([np.clip(colour[..., :3], 0.0, 1.0), hit[..., None]], axis=-1)
    depth = np.where(hit, normal_depth[..., 3], np.inf)
    normal = np.where(hit[..., None], normal_depth[..., :3], 0.0)
    steps_id = np.zeros(ids.shape, np.int32)
    steps_id[..., 1] = np.where(hit, ids[..., 0], -1)
    return (color_hit.astype(np.float32), np.concatenate(
        [normal, depth[..., None]], axis=-1).astype(np.float32), steps_id)


class RasterDisplayPlanes:
    """The conversion pass on one moderngl context, and its targets (one per size, kept).

    Like `MeshRenderer`, its methods make the context current themselves: call them outside
    a ``with ctx`` block.
    """

    def __init__(self, ctx):
        self.ctx = ctx
        with ctx:
            self.program = ctx.program(vertex_shader=glsl_file("fullscreen.vert"),
                                       fragment_shader=glsl_file("raster/display_planes.frag"))
            for unit, name in enumerate(("normal_depth", "ids", "colour")):
                self.program[name].value = unit
            self.vao = ctx.vertex_array(self.program, [])
        self.targets: dict[tuple[int, int], object] = {}

    def convert(self, raster_fbo, width: int, height: int):
        """Draw the display planes of ``raster_fbo`` (a `MeshRenderer.draw` framebuffer of
        width x height) and return their framebuffer, three attachments as
        `gpu_shader.render.Renderer` leaves them (`Display.draw` reads it)."""
        target = self._target(width, height)
        planes = raster_fbo.color_attachments
        with self.ctx:
            for unit, k in enumerate((NORMAL_DEPTH, IDS, COLOUR)):
                planes[k].use(location=unit)
            target.use()
            target.viewport = (0, 0, width, height)
            self.ctx.disable(self.ctx.BLEND | self.ctx.DEPTH_TEST)
            self.vao.render(vertices=3)
        return target

    def read(self, target) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The three planes of ``target`` read back, (H, W, 4) each, row 0 the top."""
        width, height = target.size
        floats = np.empty((2, height, width, 4), np.float32)
        integers = np.empty((height, width, 4), np.int32)
        with self.ctx:
            for i in range(2):
                target.read_into(floats[i], components=4, attachment=i, dtype="f4")
            target.read_into(integers, components=4, attachment=2, dtype="i4")
        return floats[0], floats[1], integers

    def release(self) -> None:
        """Free the program, its vertex array and the targets."""
        with self.ctx:
            for fbo in self.targets.values():
                for texture in fbo.color_attachments:
                    texture.release()
                fbo.release()
            self.vao.release()
            self.program.release()
        self.targets = {}

    def _target(self, width: int, height: int):
        key = (width, height)
        if key not in self.targets:
            with self.ctx:
                planes = [self.ctx.texture((width, height), 4, dtype=dtype)
                          for dtype in ("f4", "f4", "i4")]
                self.targets[key] = self.ctx.framebuffer(color_attachments=planes)
        return self.targets[key]
