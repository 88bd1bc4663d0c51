"""Compile generated programs in a process of their own, so a live view keeps drawing.

A structural edit (an object added, a shading mode changed) needs a new program, and a
software driver compiles one slowly: llvmpipe takes 0.4 to 0.7 s for a bundled scene's
shader, most of it LLVM compiling the fragment shader at its first draw. A live view cannot
stop for that. So the view hands the new program to a `BackgroundCompiler`, keeps drawing its
old program meanwhile, and switches when the compiler says the new one is ready.

The compiler is a second Python process (``python -m gpu_shader.background_compile``) with a
headless GL context: a thread would not do, because moderngl holds Python's global
interpreter lock while the driver compiles, so the view's thread would stop anyway. The
process compiles the program and draws it once into a tiny target of the same formats
(`Renderer.draw_planes`), which makes the driver compile everything a real draw needs. A
moderngl program cannot move between contexts, let alone processes; what carries over is the
driver's **shader cache**, which keeps compiled programs on disk under the hash of their text
and state (Mesa's ``~/.cache/mesa_shader_cache``, NVIDIA's ``GLCache``). When the view's
context compiles the same text it is served from that cache: measured on llvmpipe, a switch
that held the frame for 0.4 to 0.7 s holds it for 30 to 60 ms (docs/viewer.md). Where a
driver keeps no cache (or ``MESA_SHADER_CACHE_DISABLE`` is set), the switch costs the full
compile once, as it would without a compiler: the cache decides how fast, never what is drawn.

The protocol on the pipes: the view writes pickled `Program`s to the process's stdin, each
after its length (8 bytes, little-endian); the process answers each with one line on stdout,
the program's `digest`.
"""

from __future__ import annotations

import hashlib
import pickle
import struct
import subprocess
import sys
import threading

from scene_model.errors import MarchlabError

from .generate import Program

WARM_SIZE = (8, 8)        # the tiny target the compiler's single draw goes into
_LENGTH = struct.Struct("<Q")


def digest(program: Program) -> str:
    """What a compiled program is known by: a hash of its vertex and fragment text (the text
    is `Renderer`'s cache key too)."""
    text = program.vertex_source + "\0" + program.source
    return hashlib.sha1(text.encode("utf-8")).hexdigest()


class BackgroundCompiler:
    """Compiles programs in a worker process with a headless GL context of its own.

    Parameters
    ----------
    backend : str or None
        The worker's context: None for moderngl's default standalone one (GLX on Linux,
        the driver path a window's context takes on X11), or "egl" (headless, as the gpu
        backend's own context).

    If the worker cannot start or dies, the compiler says every program is ready, so the view
    compiles them itself, as it would without one; `problem` says why.
    """

    def __init__(self, backend: str | None = None):
        self.problem: str | None = None
        self.compiled = 0                   # programs the worker finished
        self._asked: set[str] = set()
        self._ready: set[str] = set()
        self._closing = False
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)
        self._process = subprocess.Popen(
            [sys.executable, "-m", "gpu_shader.background_compile", backend or ""],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self._reader = threading.Thread(target=self._read, name="marchlab-compile-reader",
                                        daemon=True)
        self._reader.start()

    def request(self, program: Program) -> None:
        """Ask for ``program`` to be compiled (asking again changes nothing)."""
        key = digest(program)
        with self._lock:
            if key in self._asked or self.problem is not None:
                return
            self._asked.add(key)
        message = pickle.dumps(program, protocol=pickle.HIGHEST_PROTOCOL)
        try:
            self._process.stdin.write(_LENGTH.pack(len(message)) + message)
            self._process.stdin.flush()
        except OSError as err:
            self._give_up(f"the compiler process stopped ({err})")

    def ready(self, program: Program) -> bool:
        """Whether ``program`` is compiled (or failed to: the view's own compile then says
        why, as it would have without a compiler)."""
        with self._lock:
            return self.problem is not None or digest(program) in self._ready

    def wait(self, program: Program, timeout: float | None = None) -> bool:
        """Request ``program`` and block until it is ready; whether it is."""
        self.request(program)
        with self._changed:
            return self._changed.wait_for(
                lambda: self.problem is not None or digest(program) in self._ready, timeout)

    def close(self) -> None:
        """Stop the worker after what it is compiling."""
        self._closing = True
        try:
            self._process.stdin.close()
        except OSError:
            pass
        try:
            self._process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        self._reader.join()

    def _read(self) -> None:
        for line in self._process.stdout:
            with self._changed:
                self._ready.add(line.decode().strip())
                self.compiled += 1
                self._changed.notify_all()
        if self._closing:
            return
        if self._process.wait() != 0:
            error = self._process.stderr.read().decode(errors="replace").strip()
            last = error.splitlines()[-1] if error else f"exit {self._process.returncode}"
            self._give_up(f"the compiler process failed: {last}")
        else:
            self._give_up("the compiler process has stopped")

    def _give_up(self, why: str) -> None:
        with self._changed:
            if self.problem is None:
                self.problem = why
            self._changed.notify_all()


def serve(backend: str, requests=None, answers=None) -> None:
    """The worker process: compile each program read from ``requests`` (stdin), answer its
    digest on ``answers`` (stdout), until the input ends."""
    import moderngl
    from .render import Renderer
    requests = requests or sys.stdin.buffer
    answers = answers or sys.stdout
    options = {"backend": backend} if backend else {}
    renderer = Renderer(moderngl.create_standalone_context(**options))
    while len(header := requests.read(_LENGTH.size)) == _LENGTH.size:
        program = pickle.loads(requests.read(_LENGTH.unpack(header)[0]))
        try:
            fbo = renderer.draw_planes(program, *WARM_SIZE)
            fbo.read(viewport=(0, 0, 1, 1))        # waits for the draw, and so for the
        except MarchlabError:                     # driver's compile at first draw
            pass                                  # the view's own compile will say why
        # The cache that matters is the driver's: this context's copy is not used again.
        for gl_object in reversed(renderer.programs.pop(
                (program.vertex_source, program.source), ())):
            if gl_object is not None:             # a compute program has no vertex array
                gl_object.release()
        print(digest(program), file=answers, flush=True)


if __name__ == "__main__":
    serve(sys.argv[1] if len(sys.argv) > 1 else "")
