"""What it costs to collide with the scene's SDF instead of exact planes, side by side.

    python benchmarks/bench_colliders.py [--counts 10 100 1000] [--seconds 0.25]

The same spheres (radius 5 cm, on a jittered lattice, random velocities) fall into the same
box, built three ways: five exact planes (floor and four walls, the only colliders before
shapes existed), one shape (a block with a box-shaped hollow: a CSG subtraction, whose
corners need the probes of physics/colliders.py), and five shapes (a floor slab and four wall
slabs, each a box). Shapes use the reference renderer's SDF and normals
(marchlab/colliders.py), as `marchlab simulate` does. After a warm-up of 0.25 s (simulated),
steps are timed over ``--seconds`` of simulated time; the table gives microseconds per
sphere-step and the ratio to the planes' box in the same run. Machines are shared and noisy:
compare ratios from one run, not absolute times across runs.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import physics  # noqa: E402
from bench_pybullet import RADIUS, pile, seconds_per_step  # noqa: E402  (the same pile)
from bench_render import cpu_name  # noqa: E402  (the same /proc/cpuinfo reader)
from marchlab.colliders import object_shape  # noqa: E402
from scene_model.builder import Material, PhysicsSettings, Scene, box  # noqa: E402

WALL = 0.1                       # half-thickness of the slabs (m)


def world_with(kind: str, count: int) -> physics.World:
    """The box of ``count`` spheres with the walls of ``kind``."""
    world = physics.World(solver="simultaneous")
    centre, velocity, half = pile(count)
    world.add_spheres(centre, velocities=velocity, radius=RADIUS, restitution=0.5,
                      friction=0.4)
    height = 2 * half + 1.0
    if kind == "5 planes":
        world.add_plane((0, 1, 0), 0, friction=0.4)
        for normal in [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]:
            world.add_plane(normal, -half, friction=0.4)
        return world
    if kind == "1 shape (hollow block)":
        nodes = [box(half + WALL, height / 2, half + WALL).at(0, height / 2 - WALL, 0)
                 - box(half, height / 2, half).at(0, height / 2, 0)]
    else:
        nodes = [box(half + WALL, WALL, half + WALL).at(0, -WALL, 0)]
        for x, z in [(1, 0), (-1, 0), (0, 1), (0, -1)]:
            size = (WALL, height / 2, half + WALL) if x else (half + WALL, height / 2, WALL)
            nodes.append(box(*size).at(x * (half + WALL), height / 2, z * (half + WALL)))
    scene = Scene(materials={"default": Material(friction=0.4)}, objects=tuple(nodes))
    settings = PhysicsSettings(plane_friction=0.4, plane_restitution=0.0)
    for index, node in enumerate(nodes):
        world.add_shape(object_shape(node, f"objects[{index}]", scene, settings, np.float64))
    return world


KINDS = ("5 planes", "1 shape (hollow block)", "5 shapes (box slabs)")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[10, 100, 1000])
    parser.add_argument("--seconds", type=float, default=0.25)
    args = parser.parse_args(argv)
    print(f"# {cpu_name()}, Python {platform.python_version()}, NumPy {np.__version__}; "
          f"{args.seconds} s simulated after 0.25 s of warm-up, dt = 1/240 s")
    print("| spheres | walls | us per sphere-step | against 5 planes |")
    print("|---:|---|---:|---:|")
    for count in args.counts:
        base = None
        for kind in KINDS:
            per_step = seconds_per_step(world_with(kind, count).step, args.seconds)
            base = per_step if base is None else base
            print(f"| {count:,} | {kind} | {per_step / count * 1e6:.1f} | "
                  f"{per_step / base:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
