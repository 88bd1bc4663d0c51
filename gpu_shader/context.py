"""The OpenGL context: headless through EGL, on the best device the machine has.

A context is made the first time the GPU backend is used, never at import, and kept for the
process. With several EGL devices (a machine with an NVIDIA GPU also has Mesa's software
llvmpipe), a hardware renderer is preferred; ``MARCHLAB_GL_DEVICE=<index>`` picks an EGL
device by its index instead.
"""

from __future__ import annotations

import os

from scene_model.errors import MarchlabError

ENV_DEVICE = "MARCHLAB_GL_DEVICE"
MAX_DEVICES = 16
SOFTWARE = ("llvmpipe", "softpipe", "swrast", "software")
INSTALL_HINT = ("on Debian/Ubuntu: apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri "
                "(or run `make system-packages`)")

_context = None


def gl_context():
    """The process's moderngl context (OpenGL 3.3 or newer), made on first use."""
    global _context
    if _context is None:
        _context = _make_context()
    return _context


def renderer_name(ctx) -> str:
    """The GL_RENDERER string, e.g. 'llvmpipe (LLVM 15.0.6, 256 bits)'."""
    return ctx.info["GL_RENDERER"]


def is_software(ctx) -> bool:
    return any(word in renderer_name(ctx).lower() for word in SOFTWARE)


def subpixel_shift(ctx) -> float:
    """How far from a pixel's centre, in pixels along each axis, the context's rasteriser may
    sample a triangle's interpolated values (`scene_model.frame.Frame.subpixel`).

    A hardware rasteriser snaps each vertex's window position to GL_SUBPIXEL_BITS bits (8 on
    an NVIDIA H100) and interpolates from the snapped triangle, so a value at a pixel centre
    is the exact one at a point up to half a step, 2^-(bits + 1) pixels, away along each
    axis: a convex combination of the three vertices' moves (measured on an H100 at 96 x 72:
    depths, normals and uvs of the NumPy rasteriser's planes moved by up to 1.7e-3 of their
    change across a pixel, against 2^-9 = 1.95e-3). llvmpipe interpolates from the unsnapped
    positions (measured: depths within 2.1e-6 relative of the NumPy rasteriser's), so 0
    there; its snapping decides only which triangle covers a pixel near an edge."""
    if is_software(ctx):
        return 0.0
    return 2.0 ** -(int(ctx.info["GL_SUBPIXEL_BITS"]) + 1)


def _import_moderngl():
    try:
        import moderngl
    except ImportError:
        raise MarchlabError("the gpu backend needs moderngl: pip install 'marchlab[gpu]'") from None
    return moderngl


def _make_context():
    moderngl = _import_moderngl()
    chosen = os.environ.get(ENV_DEVICE, "").strip()
    if chosen:
        if not chosen.isdigit():
            raise MarchlabError(
                f"{ENV_DEVICE}={chosen!r}: expected an EGL device index (0, 1, ...)")
        try:
            return _checked(_standalone(moderngl, int(chosen)))
        except MarchlabError:
            raise
        except Exception as err:
            raise MarchlabError(f"{ENV_DEVICE}={chosen}: cannot make an OpenGL context on that "
                                f"EGL device ({_one_line(err)})") from None
    tried, contexts = [], []
    for index in range(MAX_DEVICES):
        try:
            ctx = _standalone(moderngl, index)
        except Exception as err:
            tried.append(f"device {index}: {_one_line(err)}")
            break                                 # indices past the last device all fail
        if ctx.version_code < 330:
            tried.append(f"device {index}: OpenGL {ctx.version_code / 100:.1f} is too old")
            ctx.release()
            continue
        if not is_software(ctx):
            for other in contexts:
                other.release()
            return ctx
        contexts.append(ctx)
    if contexts:                                   # only software renderers: take the first
        for other in contexts[1:]:
            other.release()
        return contexts[0]
    raise MarchlabError("the gpu backend cannot make an OpenGL 3.3+ context through EGL ("
                        + "; ".join(tried) + f"); {INSTALL_HINT}")


def _standalone(moderngl, index: int):
    """A headless context on EGL device ``index``: OpenGL 4.3 where the driver has it (the
    compute stage, `gpu_shader.render.default_stage`; NVIDIA's driver makes exactly the
    version asked for, 3.3 unless asked for more), else whatever it makes."""
    try:
        return moderngl.create_standalone_context(backend="egl", device_index=index,
                                                  require=430)
    except Exception:
        return moderngl.create_standalone_context(backend="egl", device_index=index)


def _checked(ctx):
    if ctx.version_code < 330:
        raise MarchlabError(f"OpenGL {ctx.version_code / 100:.1f} on {renderer_name(ctx)}: "
                            "the gpu backend needs 3.3 or newer")
    return ctx


def _one_line(err: Exception) -> str:
    text = str(err).strip().splitlines()
    return text[0] if text else type(err).__name__
