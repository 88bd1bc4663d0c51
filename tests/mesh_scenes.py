"""Mesh scenes that the rasteriser tests share: the NumPy rasteriser against Embree
(tests/truth) and the GPU's raster pipeline against the NumPy rasteriser (tests/gpu)."""

from __future__ import annotations

import numpy as np

from scene_model.camera import Camera
from scene_model.meshes import cone, cube, plane, torus, transformed, uv_sphere

CAMERA = Camera(position=(0.3, 1.6, 4.2), look_at=(0.0, 0.2, 0.0), fov=45.0)
WIDTH, HEIGHT = 96, 72


def turned(mesh, degrees, offset):
    """``mesh`` turned about y by ``degrees``, then moved by ``offset``."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    m = np.array([[c, 0, s, offset[0]], [0, 1, 0, offset[1]], [-s, 0, c, offset[2]],
                  [0, 0, 0, 1.0]])
    return transformed(mesh, m)


SCENES = {
    "sphere": [uv_sphere(1.0, 32, 16)],
    "torus": [turned(torus(1.0, 0.35, 32, 16), 30, (0, 0.3, 0))],
    "cube and cone on a floor": [turned(cube(1.0), 25, (-0.8, 0.5, 0.0)),
                                 turned(cone(0.5, 1.2, 24), 0, (0.9, 0.0, 0.2)),
                                 plane(6.0, 6.0, subdivisions=4)],
}
