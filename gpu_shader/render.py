"""The GPU backend: draw the generated fragment shader and read every buffer back.

One full-screen draw writes three render targets (colour and hit, normal and depth in RGBA32F;
steps, object id and path label in RGBA32I); reading them back gives the same `Frame` the
NumPy reference returns. With the cone pre-pass (``render.prepass = "cone"``) a first draw
writes each tile's start into a small R32F texture, which the frame's draw reads.
GL row r holds image row r counted from the top, so the read-back needs no flip.

The same program runs in one of two shader stages (`STAGES`): as a fragment shader drawn over
the frame (OpenGL 3.3), or as a compute shader dispatched one invocation per pixel that
stores into the same textures (OpenGL 4.3; the "glsl-compute" dialect). They compute the same
pixels with the same code (tests/gpu/test_compute_stage.py). Which is faster depends on the
device: an NVIDIA H100 shades fragments on a few of its multiprocessors only, so it computes
far faster; llvmpipe runs its fragment stage faster (docs/performance.md, "Fragment or
compute"). ``MARCHLAB_GPU_STAGE`` chooses; by default `default_stage`.
Programs are cached by their text, which depends only on the scene's structure: a new
camera or a moved object only rewrites the parameter buffer.
"""

from __future__ import annotations

import math
import os
import re
from collections import OrderedDict
from typing import Callable

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.frame import Frame
from scene_model.scene import Scene

from .context import gl_context, is_software, renderer_name
from .dialects import GROUP_SIZE, MAX_FLAT_ROWS
from .generate import Program, generate
from .library import glsl_file
from .planes import frame_from_planes, row_bands

PROGRAM_CACHE_SIZE = 32
TARGET_CACHE_SIZE = 8       # sizes kept (a live view draws at a few reduced ones)
ATLAS_CACHE_SIZE = 4        # texture atlases kept (environments recently drawn)
ATLAS_UNIT = 1              # the texture unit of the atlas (the cone pre-pass's starts use 0)
STAGES = ("fragment", "compute")
ENV_STAGE = "MARCHLAB_GPU_STAGE"


class ShaderCompileError(MarchlabError):
    """The driver rejected a generated shader; the message quotes the offending lines."""


def check() -> None:
    """Raise MarchlabError, saying what is missing, if this backend cannot run here."""
    gl_context()


def device_name() -> str:
    """The OpenGL renderer the backend draws with, and its shader stage (`default_stage`),
    e.g. 'llvmpipe (LLVM 15.0.6, 256 bits), fragment shader'."""
    return f"{renderer_name(gl_context())}, {_renderer().stage} shader"


def render(scene: Scene, width: int, height: int, precision: str = "float32",
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False) -> Frame:
    """Render ``scene`` on the GPU in float32 (see `marchlab.render`)."""
    if precision != "float32":
        raise MarchlabError(f"the gpu backend renders in float32 only (asked for {precision})")
    return _renderer().render(scene, width, height, progress, path_labels)


def render_program(scene: Scene, program: Program, width: int, height: int) -> Frame:
    """Draw an already made ``program`` for ``scene`` (e.g. `gpu_shader.uber.uber_program`)."""
    return _renderer().render_program(scene, program, width, height)


def default_stage(ctx) -> str:
    """The shader stage the gpu backend draws with on ``ctx``: ``MARCHLAB_GPU_STAGE`` where
    set; else "compute" on a hardware device with OpenGL 4.3, "fragment" otherwise
    (llvmpipe, and OpenGL 4.1 on macOS). Measured in docs/performance.md."""
    chosen = os.environ.get(ENV_STAGE, "").strip()
    if chosen:
        if chosen not in STAGES:
            raise MarchlabError(f"{ENV_STAGE}={chosen!r}: expected one of {', '.join(STAGES)}")
        if chosen == "compute" and ctx.version_code < 430:
            raise MarchlabError(f"{ENV_STAGE}=compute: compute shaders need OpenGL 4.3; "
                                f"{renderer_name(ctx)} has {ctx.version_code / 100:.1f}")
        return chosen
    return "compute" if ctx.version_code >= 430 and not is_software(ctx) else "fragment"


_renderers: dict[int, "Renderer"] = {}


def _renderer() -> "Renderer":
    ctx = gl_context()
    if id(ctx) not in _renderers:
        _renderers[id(ctx)] = Renderer(ctx)
    return _renderers[id(ctx)]


class Renderer:
    """Compiled programs and render targets on one context."""

    def __init__(self, ctx, stage: str | None = None):
        self.ctx = ctx
        self.stage = stage or default_stage(ctx)
        self.programs: OrderedDict[tuple[str, str], tuple] = OrderedDict()
        self.targets: OrderedDict[tuple[int, int], object] = OrderedDict()
        self.start_targets: OrderedDict[tuple[int, int], object] = OrderedDict()
        self.atlases: OrderedDict[int, tuple] = OrderedDict()    # id(texels): (texels, texture)
        self.max_block = int(ctx.info["GL_MAX_UNIFORM_BLOCK_SIZE"])
        self.flat_rows = min(MAX_FLAT_ROWS, int(ctx.info.get("GL_MAX_VARYING_VECTORS", 0)))

    def render(self, scene: Scene, width: int, height: int, progress=None,
               path_labels: bool = False) -> Frame:
        program = self.generate(scene, width, height, path_labels)
        return self.render_program(scene, program, width, height, progress)

    def generate(self, scene: Scene, width: int, height: int,
                 path_labels: bool = False) -> Program:
        """`gpu_shader.generate.generate` of ``scene`` for this renderer's `stage`."""
        return generate(scene, width, height,
                        dialect="glsl-compute" if self.stage == "compute" else "glsl",
                        flat_rows=self.flat_rows, path_labels=path_labels)

    def render_program(self, scene: Scene, generated: Program, width: int, height: int,
                       progress=None) -> Frame:
        """Draw a program made for ``scene`` at this size: `generate`'s, or another with the
        same outputs (`gpu_shader.uber.uber_program`)."""
        with self.ctx:           # make our context current: the process may hold others
            fbo = self._draw_planes(generated, width, height, progress)
            frame = self.read_frame(fbo, scene, width, height)
        if not generated.path_labels:
            frame.path = None
        return frame

    def draw_planes(self, generated: Program, width: int, height: int):
        """Draw ``generated`` into `target` (width, height) and leave the planes there, read
        back nothing: a live view shows them straight from the GPU (`gpu_shader.display`)."""
        with self.ctx:
            return self._draw_planes(generated, width, height, None)

    def _draw_planes(self, generated: Program, width: int, height: int, progress):
        parameters = generated.parameters.astype(np.float32)
        if parameters.nbytes > self.max_block:
            raise MarchlabError(
                f"the scene needs {parameters.nbytes} bytes of shader parameters; this OpenGL "
                f"allows {self.max_block} in a uniform block (fewer objects or lights)")
        program, vao = self._program(generated.source, generated.vertex_source,
                                     generated.compute)
        fbo = self.target(width, height)
        buffer = self.ctx.buffer(parameters.tobytes())
        try:
            buffer.bind_to_uniform_block(0)
            program["Parameters"].binding = 0
            if generated.prepass_tile:
                starts = self._draw_starts(generated, width, height)
                starts.color_attachments[0].use(location=0)
                program["cone_starts"].value = 0
            sampler = program.get("texels", None)
            if generated.texels is not None and sampler is not None:
                self.atlas(generated.texels).use(location=ATLAS_UNIT)
                sampler.value = ATLAS_UNIT
            if generated.compute:
                for unit, texture in enumerate(fbo.color_attachments):
                    texture.bind_to_image(unit, read=False, write=True)
                program["frame_size"].value = (width, height)
                self.dispatch(program, width, height, progress)
            else:
                fbo.use()
                fbo.viewport = (0, 0, width, height)
                self.draw(vao, width, height, progress)
        finally:
            buffer.release()
        return fbo

    def _draw_starts(self, generated: Program, width: int, height: int):
        """Draw the cone pre-pass of ``generated`` (its parameter block already bound) into
        the tile-start target of a width x height frame; return that framebuffer."""
        program, vao = self._program(generated.prepass_source, generated.vertex_source,
                                     generated.compute)
        program["Parameters"].binding = 0
        columns, rows = generated.tiles(width, height)
        starts = self._cached(self.start_targets, (columns, rows), lambda: [
            self.ctx.texture((columns, rows), 1, dtype="f4")])
        if generated.compute:
            starts.color_attachments[0].bind_to_image(0, read=False, write=True)
            program["tiles"].value = (columns, rows)
            program.run(math.ceil(columns / GROUP_SIZE), math.ceil(rows / GROUP_SIZE))
            # The frame's dispatch reads the starts with texelFetch.
            self.ctx.memory_barrier(self.ctx.TEXTURE_FETCH_BARRIER_BIT)
            return starts
        starts.use()
        starts.viewport = (0, 0, columns, rows)
        vao.render(vertices=3)
        return starts

    def atlas(self, texels: np.ndarray):
        """The RGBA32F texture holding a program's texture atlas (R, W, 4), uploaded once and
        kept while the same array is drawn again (an environment's texels are read once,
        `scene_model.environment.environment_map`, and shared by every frame)."""
        key = id(texels)
        if key in self.atlases:
            self.atlases.move_to_end(key)
            return self.atlases[key][1]
        rows, width, _ = texels.shape
        largest = int(self.ctx.info["GL_MAX_TEXTURE_SIZE"])
        if max(rows, width) > largest:
            raise MarchlabError(f"the scene's images need a texture of {width} x {rows} "
                                f"texels; this OpenGL allows {largest} a side (use smaller "
                                "images, or --backend opencl)")
        texture = self.ctx.texture((width, rows), 4, np.ascontiguousarray(texels).tobytes(),
                                   dtype="f4")
        # texelFetch reads texels exactly, whatever the filter; nearest says so to a reader.
        texture.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        self.atlases[key] = (texels, texture)       # the array is kept, so its id is not reused
        if len(self.atlases) > ATLAS_CACHE_SIZE:
            _, (_, old) = self.atlases.popitem(last=False)
            old.release()
        return texture

    def read_frame(self, fbo, scene: Scene, width: int, height: int) -> Frame:
        """The `Frame` held by the planes of ``fbo`` (a `target` that ``scene`` was drawn
        into at width x height)."""
        floats = np.empty((2, height, width, 4), np.float32)
        integers = np.empty((height, width, 4), np.int32)
        for i in range(2):
            fbo.read_into(floats[i], components=4, attachment=i, dtype="f4")
        fbo.read_into(integers, components=4, attachment=2, dtype="i4")
        return frame_from_planes((*floats, integers), scene, "gpu", "float32")

    def draw(self, vao, width, height, progress):
        if progress is None:
            vao.render(vertices=3)
            return
        for start, stop in row_bands(height, progress):
            self.ctx.scissor = (0, start, width, stop - start)
            vao.render(vertices=3)
            self.ctx.finish()
            progress(stop * width, height * width)
        self.ctx.scissor = None

    def dispatch(self, program, width, height, progress):
        """Run the compute ``program`` over a width x height frame, in bands of rows with
        ``progress`` as `draw` does; the images it stored are then ready to be sampled,
        drawn from and read back."""
        first = program.get("first_row", None)
        bands = [(0, height)] if progress is None else row_bands(height, progress)
        for start, stop in bands:
            if first is not None:
                first.value = start
            program.run(math.ceil(width / GROUP_SIZE), math.ceil((stop - start) / GROUP_SIZE))
            if progress is not None:
                self.ctx.finish()
                progress(stop * width, height * width)
        self.ctx.memory_barrier(self.ctx.ALL_BARRIER_BITS)

    def program(self, source: str, vertex: str = "", compute: bool = False):
        """The compiled program for a fragment shader ``source`` and its ``vertex`` shader
        ("" for the plain full-screen triangle), or for a ``compute`` shader ``source``
        (its vertex array None), from the cache when seen before."""
        with self.ctx:           # a `with` does not nest: exiting restores the previous one
            return self._program(source, vertex, compute)

    def _program(self, source: str, vertex: str = "", compute: bool = False):
        key = (vertex, source)
        if key in self.programs:
            self.programs.move_to_end(key)
            return self.programs[key]
        try:
            if compute:
                program, vao = self.ctx.compute_shader(source), None
            else:
                program = self.ctx.program(vertex_shader=vertex or glsl_file("fullscreen.vert"),
                                           fragment_shader=source)
                vao = self.ctx.vertex_array(program, [])
        except Exception as err:
            raise ShaderCompileError(compile_message(str(err), source)) from None
        self.programs[key] = (program, vao)
        if len(self.programs) > PROGRAM_CACHE_SIZE:
            _, (old, old_vao) = self.programs.popitem(last=False)
            if old_vao is not None:
                old_vao.release()
            old.release()
        return program, vao

    def target(self, width: int, height: int):
        """A framebuffer of the given size (kept for reuse): two RGBA32F textures and one
        RGBA32I, the planes of `gpu_shader.planes`."""
        return self._cached(self.targets, (width, height), lambda: [
            self.ctx.texture((width, height), 4, dtype=dtype) for dtype in ("f4", "f4", "i4")])

    def _cached(self, cache: OrderedDict, key, textures):
        """The framebuffer of ``cache`` at ``key``, made on first use from the list of
        textures that ``textures()`` returns; the least recently used beyond
        `TARGET_CACHE_SIZE` is released."""
        if key in cache:
            cache.move_to_end(key)
            return cache[key]
        cache[key] = self.ctx.framebuffer(color_attachments=textures())
        if len(cache) > TARGET_CACHE_SIZE:
            _, old = cache.popitem(last=False)
            for texture in old.color_attachments:
                texture.release()
            old.release()
        return cache[key]


# Driver messages name lines as "0:123(4): error" (Mesa) or "0(123) : error" (NVIDIA).
_LINE = re.compile(r"\b0[:(](\d+)[(): ]")
_END = re.compile(r"\$end|<EOF>|end of file", re.IGNORECASE)


def compile_message(log: str, source: str) -> str:
    """The compiler's first error, with the generated source lines it names."""
    lines = source.splitlines()
    errors = [line.strip() for line in log.splitlines() if "error" in line.lower()]
    first = errors[0] if errors else log.strip().splitlines()[-1]
    quoted = []
    for match in _LINE.finditer(first):
        number = int(match.group(1))
        if 1 <= number <= len(lines):
            quoted.append(f"  line {number}: {lines[number - 1].strip()}")
    if not quoted and _END.search(first) and lines:
        # An error at the end of the text: NVIDIA's compiler names no line ("(0) : error
        # C0000: syntax error, unexpected $end ... at token "<EOF>""); quote the last one.
        number = max(i for i, line in enumerate(lines, 1) if line.strip() or i == 1)
        quoted.append(f"  line {number}: {lines[number - 1].strip()}")
    return ("generated shader failed to compile: " + first
            + ("\n" + "\n".join(quoted) if quoted else "")
            + "\n(`marchlab shader SCENE --numbered` prints the source with line numbers)")
