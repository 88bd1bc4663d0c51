"""`render`: one entry point for every backend, each imported only when it is asked for.

A user without OpenGL or OpenCL can still import marchlab and render with the NumPy reference;
a backend's dependencies are loaded the first time that backend is used.
"""

from __future__ import annotations

import functools
import importlib
import warnings
from dataclasses import dataclass
from typing import Callable

from scene_model.camera import check_image_size
from scene_model.errors import MarchlabError
from scene_model.frame import Frame
from scene_model.scene import Scene, rendered_scene

from .budget import check_render


@dataclass(frozen=True)
class Backend:
    """Where a backend lives and which precisions it computes in (the first is its default).

    The module has ``render(scene, width, height, precision, progress, path_labels) -> Frame``
    and ``check()``, which raises `MarchlabError` saying what is missing if it cannot run here.
    """
    module: str
    precisions: tuple[str, ...]
    description: str


BACKENDS = {
    "numpy": Backend("reference_cpu.render", ("float64", "float32"),
                     "the NumPy reference sphere tracer (CPU)"),
    "gpu": Backend("gpu_shader.render", ("float32",),
                   "the generated fragment shader, through moderngl and EGL"),
    "opencl": Backend("gpu_shader.opencl", ("float32", "float64"),
                      "the same generated code as an OpenCL kernel, on a CPU device (PoCL)"),
    "numpy-raster": Backend("reference_cpu.raster_render", ("float64",),
                            "the readable NumPy rasteriser, for triangle meshes (CPU)"),
    "raster": Backend("gpu_shader.raster_render", ("float32",),
                      "OpenGL's raster pipeline, for triangle meshes, through moderngl"),
    "embree": Backend("reference_cpu.truth.embree_render", ("float32",),
                      "Embree's ray casts of triangle meshes: the raster backends' truth"),
}

# The backends that draw a scene's triangle meshes; the others sphere-trace its SDF objects.
MESH_BACKENDS = ("numpy-raster", "raster", "embree")

PRECISIONS = ("float32", "float64")


def render(scene: Scene, width: int, height: int, backend: str = "numpy",
           precision: str | None = None,
           progress: Callable[[int, int], None] | None = None,
           path_labels: bool = False, allow_large: bool = False) -> Frame:
    """Render ``scene`` to a `Frame` of ``width`` x ``height`` pixels.

    Parameters
    ----------
    scene : Scene
        From `marchlab.load_scene` or built in Python. Its bodies are drawn as spheres at
        their positions (`scene_model.scene.scene_objects`).
    width, height : int
        Image size in pixels.
    backend : str
        One of `BACKENDS`: ``"numpy"`` (the reference), ``"gpu"`` or ``"opencl"``.
    precision : {"float32", "float64"}, optional
        Default: the backend's own (float64 for numpy, float32 for gpu and opencl).
    progress : callable, optional
        Called as ``progress(done, total)`` while rendering.
    path_labels : bool
        Also compute each pixel's path label (`scene_model.frame.Frame.path`), which tells
        two renderers' frames apart only where the image may jump (`marchlab.compare`).
        Off by default: it is bookkeeping for the equivalence suite, not rendering.
    allow_large : bool
        Go ahead with an image or an amount of work beyond the budget (`marchlab.budget`:
        more than `scene_model.camera.MAX_PIXELS` pixels, or more than
        `marchlab.budget.MAX_RAY_STEPS` ray steps at worst), which is otherwise refused.

    Raises
    ------
    MarchlabError
        An unknown backend or precision, a bad size, a job over the budget (`BudgetError`).
    """
    precision = check_backend(scene, backend, precision)
    check_image_size(width, height, allow_large)
    check_render(scene, width, height, allow_large=allow_large)
    from .light_check import lights_inside
    for line in lights_inside(scene):               # the image would hide it: say so
        warnings.warn(line, stacklevel=2)
    module = importlib.import_module(BACKENDS[backend].module)
    # Backends draw objects only: the bodies become spheres after the scene's objects.
    return module.render(rendered_scene(scene), width, height, precision=precision,
                         progress=progress, path_labels=path_labels)


def check_backend(scene: Scene, backend: str, precision: str | None = None) -> str:
    """The precision ``backend`` draws ``scene`` in (its first where ``precision`` is None);
    a `MarchlabError` where the backend or precision is unknown, the backend does not
    render in that precision, or it cannot draw this scene (triangle meshes on a sphere
    tracer, SDF objects on a rasteriser).

    The command line calls it before anything runs, to begin the refusal with the scene file."""
    if backend not in BACKENDS:
        raise MarchlabError(f"unknown backend {backend!r} (available: {', '.join(BACKENDS)})")
    precision = precision or BACKENDS[backend].precisions[0]
    if precision not in PRECISIONS:
        raise MarchlabError(f"unknown precision {precision!r} (one of: {', '.join(PRECISIONS)})")
    if precision not in BACKENDS[backend].precisions:
        raise MarchlabError(f"the {backend} backend renders in "
                            f"{' or '.join(BACKENDS[backend].precisions)} only "
                            f"(asked for {precision})")
    if not isinstance(scene, Scene):
        raise MarchlabError(f"scene must be a marchlab.Scene (got {type(scene).__name__}); "
                            "use marchlab.load_scene(name_or_path)")
    if scene.meshes and backend not in MESH_BACKENDS:
        raise MarchlabError(f"this scene is made of triangle meshes, which the {backend} "
                            f"backend does not draw: draw it with {', '.join(MESH_BACKENDS)}")
    if backend in MESH_BACKENDS:        # SDF objects, or the sphere tracer's own settings
        from reference_cpu.raster_render import check_mesh_scene
        check_mesh_scene(scene, backend)
    return precision


def reference_backend(scene: Scene) -> str:
    """The reference renderer of ``scene``: the NumPy sphere tracer, or for a scene of
    triangle meshes the NumPy rasteriser."""
    return "numpy-raster" if scene.meshes else "numpy"


def scene_backends(scene: Scene) -> list[str]:
    """The backends that draw ``scene``: the mesh backends for a scene of triangle meshes,
    the sphere tracers for the others."""
    meshes = bool(scene.meshes)
    return [name for name in BACKENDS if (name in MESH_BACKENDS) == meshes]


def fastest_backend_for(scene: Scene) -> str:
    """The fastest backend that can draw ``scene`` here: `fastest_backend` for an SDF
    scene; for a scene of meshes the GPU's raster pipeline, else the NumPy rasteriser."""
    if not scene.meshes:
        return fastest_backend()
    return "raster" if backend_problem("raster") is None else "numpy-raster"


def backend_problem(backend: str) -> str | None:
    """None if ``backend`` can render on this machine, else one line saying why not."""
    try:
        importlib.import_module(BACKENDS[backend].module).check()
    except MarchlabError as err:
        return str(err)
    return None


@functools.lru_cache(maxsize=None)
def fastest_backend() -> str:
    """The fastest backend that can render on this machine: "gpu", else "opencl", else "numpy".

    Each candidate is asked once (`backend_problem`) and the answer is kept for the process,
    so a lesson can call this before every render at no cost.
    """
    for backend in ("gpu", "opencl"):
        if backend_problem(backend) is None:
            return backend
    return "numpy"
