"""`render`: one entry point for every backend, each imported only when it is asked for.

A user without OpenGL or OpenCL can still import marchlab and render with the NumPy reference;
a backend's dependencies are loaded the first time that backend is used.
"""

from __future__ import annotations

import importlib
from typing import Callable

from .errors import MarchlabError
from .frame import Frame
from .scene import Scene

# backend name -> module with render(scene, width, height, precision, progress) -> Frame
BACKENDS = {
    "numpy": "reference_cpu.render",
}

PRECISIONS = ("float32", "float64")
MAX_SIDE = 16384      # the usual largest GPU texture; far beyond what a lesson needs


def render(scene: Scene, width: int, height: int, backend: str = "numpy",
           precision: str = "float64",
           progress: Callable[[int, int], None] | None = None) -> Frame:
    """Render ``scene`` to a `Frame` of ``width`` x ``height`` pixels.

    Parameters
    ----------
    scene : Scene
        From `marchlab.load_scene` or built in Python.
    width, height : int
        Image size in pixels.
    backend : str
        One of `BACKENDS` (``"numpy"``: the reference).
    precision : {"float32", "float64"}
    progress : callable, optional
        Called as ``progress(done, total)`` while rendering.
    """
    if backend not in BACKENDS:
        raise MarchlabError(f"unknown backend {backend!r} (available: {', '.join(BACKENDS)})")
    if precision not in PRECISIONS:
        raise MarchlabError(f"unknown precision {precision!r} (one of: {', '.join(PRECISIONS)})")
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_SIDE:
            raise MarchlabError(f"{name} must be an integer from 1 to {MAX_SIDE} (got {value!r})")
    if not isinstance(scene, Scene):
        raise MarchlabError(f"scene must be a marchlab.Scene (got {type(scene).__name__}); "
                            "use marchlab.load_scene(name_or_path)")
    module = importlib.import_module(BACKENDS[backend])
    return module.render(scene, width, height, precision=precision, progress=progress)
