"""Lights that light nothing: a point or spot light placed inside a solid.

A light inside a closed object is hidden from every surface outside it (each shadow ray
starts outside and ends inside, so it is blocked), and the surfaces inside face away from
the marcher: the light adds nothing to the image, silently. `lights_inside` finds them by the
scene's own SDF at each light's position (negative inside, Hart 1996), and `render` warns in
one line for each (`marchlab.render.render`).
"""

from __future__ import annotations

import numpy as np

from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.editing import object_path
from scene_model.scene import Scene, rendered_scene


def lights_inside(scene: Scene) -> list[str]:
    """One line for each point or spot light of ``scene`` whose position is inside a solid
    (the SDF there is below zero), naming the light and the object; empty if none is."""
    placed = [(index, light) for index, light in enumerate(scene.lights)
              if hasattr(light, "position")]
    drawn = rendered_scene(scene)
    if not placed or not drawn.objects:
        return []
    sdf = build_scene_sdf(drawn.objects, np.float64, with_ids=True)
    points = np.array([light.position for _, light in placed], np.float64)
    distance, ids = sdf(points)
    lines = []
    for (index, light), d, object_id in zip(placed, distance, ids):
        if d < 0:
            path = object_path(scene, int(object_id))
            where = (f"bodies[{path[1]}]" if path and path[0] == "body"
                     else f"objects[{path[0]}]" if path else "a solid")
            lines.append(f"lights[{index}] ({light.kind} at "
                         f"({', '.join(f'{c:g}' for c in light.position)})) is inside {where}, "
                         f"{-d:.3g} m below its surface: it lights nothing")
    return lines
