"""`probe`: one pixel's march, step by step, on the NumPy reference.

The front door of reference_cpu/probe.py: it draws the scene's bodies as spheres, as every
renderer does, and checks the size and the pixel first. A viewer's probe mode and a lesson's
plot of t and distance per step both call it.
"""

from __future__ import annotations

from scene_model.camera import check_image_size
from scene_model.errors import MarchlabError
from scene_model.scene import Scene, rendered_scene


def probe(scene: Scene, x: int, y: int, width: int, height: int,
          precision: str = "float64"):
    """The march of pixel (column ``x``, row ``y``; row 0 at the top) of a ``width`` x
    ``height`` render of ``scene``: a `reference_cpu.probe.MarchProbe` whose ``t`` and
    ``distance`` hold every step, and whose ``steps`` and ``depth`` are the reference
    frame's at that pixel."""
    if not isinstance(scene, Scene):
        raise MarchlabError(f"scene must be a marchlab.Scene (got {type(scene).__name__})")
    check_image_size(width, height)
    for name, value, size in (("x", x, width), ("y", y, height)):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < size:
            raise MarchlabError(f"{name} must be a pixel index from 0 to {size - 1} "
                                f"(got {value!r})")
    if precision not in ("float32", "float64"):
        raise MarchlabError(f"precision must be float32 or float64 (got {precision!r})")
    from reference_cpu.probe import probe_pixel
    return probe_pixel(rendered_scene(scene), x, y, width, height, precision)
