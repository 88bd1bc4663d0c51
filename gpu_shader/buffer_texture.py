"""Buffer textures: a storage buffer read as a 1-D texture of 16-byte texels.

A shader may read the same buffer object two ways: as a storage buffer (``buffer`` block,
read and written) and as a buffer texture (``samplerBuffer``, ``texelFetch``, read only;
OpenGL 4.3 core, section 8.9), and gets the same words. On Mesa's llvmpipe the second is
much cheaper: it loads a storage buffer at an address that differs between invocations one
4-byte word and one invocation at a time (a loop over the 8 invocations it runs in step, for
every word), and fetches a texel of a buffer texture for all 8 in one gather, about three
times as fast per word (``benchmarks/bench_buffer_reads.py``, docs/performance.md). The GPU
physics step reads its contacts, velocities, bodies and grid entries this way
(glsl/physics_step.glsl, TEXEL_READS).

moderngl has no buffer textures, so the few GL calls are made through ctypes on the context
that is current (moderngl's ``with ctx:``), as GL's own dispatch (libglvnd) routes them.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import weakref

import numpy as np

GL_TEXTURE_BUFFER = 0x8C2A
GL_RGBA32I = 0x8D82
GL_TEXTURE0 = 0x84C0
GL_ACTIVE_TEXTURE = 0x84E0
GL_MAX_TEXTURE_BUFFER_SIZE = 0x8C2B
TEXEL_BYTES = 16             # one RGBA32I texel

_gl = None


def _library():
    """libglvnd's OpenGL entry points (Linux), or None where there are none to load."""
    global _gl
    if _gl is None:
        for name in ("libOpenGL.so.0", "libGL.so.1", ctypes.util.find_library("OpenGL")):
            if not name:
                continue
            try:
                _gl = ctypes.CDLL(name)
                break
            except OSError:
                continue
        else:
            _gl = False
    return _gl or None


def available(ctx) -> bool:
    """Whether buffer textures work on ``ctx`` from here: GL 4.3, a GL library that ctypes can
    load, and a probe (once per context) that reads known words back through one. Call it
    with ``ctx`` current."""
    if ctx.version_code < 430 or _library() is None:
        return False
    if ctx not in _probed:
        _probed[ctx] = _probe(ctx)
    return _probed[ctx]


_probed: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
PROBE_WORDS = np.array([0x7FC00001, 0x00000001, -1, 0x3F800000], np.int32)  # NaN, subnormal..


def _probe(ctx) -> bool:
    """Fetch PROBE_WORDS through a buffer texture in a compute shader: the same words back?"""
    import moderngl
    made = []
    try:
        source = ctx.buffer(PROBE_WORDS.tobytes())
        made.append(source)
        out = ctx.buffer(reserve=PROBE_WORDS.nbytes)
        made.append(out)
        program = ctx.compute_shader("""#version 430
            layout(local_size_x = 1) in;
            layout(binding = 0) uniform isamplerBuffer texels;
            layout(std430, binding = 0) buffer Out { ivec4 words; };
            void main() { words = texelFetch(texels, 0); }""")
        made.append(program)
        texture = BufferTexture(source)
        made.append(texture)
        texture.use(0)
        out.bind_to_storage_buffer(0)
        program.run(1)
        ctx.memory_barrier()
        return bool(np.array_equal(np.frombuffer(out.read(), np.int32), PROBE_WORDS))
    except (moderngl.Error, OSError, AttributeError):    # then the storage buffers are read
        return False
    finally:
        for gl_object in made:
            gl_object.release()


def max_texels(ctx) -> int:
    """GL_MAX_TEXTURE_BUFFER_SIZE: the most texels a buffer texture may have. Call it with
    ``ctx`` current."""
    value = ctypes.c_int(0)
    _library().glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, ctypes.byref(value))
    return value.value


class BufferTexture:
    """A moderngl buffer read as RGBA32I texels (4 ints, 16 bytes each, in the buffer's order);
    a shader declares it ``layout(binding = unit) uniform isamplerBuffer``.

    Make, `use` and `release` it with its context current (``with ctx:``).
    """

    def __init__(self, buffer):
        gl = _library()
        name = ctypes.c_uint(0)
        gl.glGenTextures(1, ctypes.byref(name))
        self.glo = name.value
        self.buffer = buffer
        gl.glBindTexture(GL_TEXTURE_BUFFER, self.glo)          # on the active unit, briefly
        gl.glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32I, ctypes.c_uint(buffer.glo))
        gl.glBindTexture(GL_TEXTURE_BUFFER, 0)

    def use(self, unit: int) -> None:
        """Bind it to texture unit ``unit``, leaving the active unit as it was (moderngl
        assumes its own)."""
        gl = _library()
        with _unit_kept(gl):
            gl.glActiveTexture(GL_TEXTURE0 + unit)
            gl.glBindTexture(GL_TEXTURE_BUFFER, self.glo)

    def release(self) -> None:
        if self.glo:
            name = ctypes.c_uint(self.glo)
            _library().glDeleteTextures(1, ctypes.byref(name))
            self.glo = 0


class _unit_kept:
    """Restore GL_ACTIVE_TEXTURE on leaving."""

    def __init__(self, gl):
        self.gl, self.unit = gl, ctypes.c_int(GL_TEXTURE0)

    def __enter__(self):
        self.gl.glGetIntegerv(GL_ACTIVE_TEXTURE, ctypes.byref(self.unit))

    def __exit__(self, *exc):
        self.gl.glActiveTexture(self.unit.value)
