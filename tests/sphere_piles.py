"""The pile of spheres in a box that the GPU physics tests share: the grid against every pair
and the CPU (tests/equivalence), the buffer-texture reads against storage-buffer reads
(tests/gpu)."""

from __future__ import annotations

import numpy as np

import physics


def box_pile(count: int = 500, height: float = 1.5, seed: int = 0) -> physics.World:
    """``count`` spheres of radii 4 to 8 cm thrown with random velocities into a 1.2 m square
    box (a floor and four walls) from up to ``height`` (m); float32, simultaneous solver."""
    rng = np.random.default_rng(seed)
    world = physics.World(solver="simultaneous", dtype="float32", seed=seed)
    world.add_plane((0, 1, 0), 0, friction=0.4)
    for normal in [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]:
        world.add_plane(normal, -0.6, friction=0.4)
    centre = rng.uniform((-0.5, 0.1, -0.5), (0.5, height, 0.5), (count, 3))
    world.add_spheres(centre, velocities=rng.normal(0, 1, (count, 3)),
                      radius=rng.uniform(0.04, 0.08, count), restitution=0.3, friction=0.4)
    return world
