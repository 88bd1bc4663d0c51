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
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import physics  # noqa: E402
from bench_render import cpu_name  # noqa: E402  (the same /proc/cpuinfo reader)
from marchlab.colliders import object_shape  # noqa: E402
from scene_model.builder import Material, PhysicsSettings, Scene, box  # noqa: E402

RADIUS = 0.05
SPACING = 2.2 * RADIUS
WALL = 0.1                       # half-thickness of the slabs (m)


def spheres(world: physics.World, count: int, seed: int = 0) -> float:
    """Add ``count`` spheres on a jittered lattice; return the half-width of their box."""
    side = int(np.ceil(count ** (1 / 3)))
    half = side * SPACING / 2 + RADIUS
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    grid = grid[rng.permutation(len(grid))[:count]]
    centre = (grid - (side - 1) / 2) * SPACING + rng.uniform(-0.2, 0.2, (count, 3)) * RADIUS
    centre[:, 1] += (side - 1) / 2 * SPACING + 1.5 * RADIUS
    world.add_spheres(centre, velocities=rng.normal(0, 1, (count, 3)), radius=RADIUS,
                      restitution=0.5, friction=0.4)
    return half


def world_with(kind: str, count: int) -> physics.World:
    """The box of ``count`` spheres with the walls of ``kind``."""
    world = physics.World(solver="simultaneous")
    half = spheres(world, count)
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


def time_steps(world: physics.World, seconds: float) -> float:
    """Seconds of wall time per step, over ``seconds`` of simulated time after a warm-up."""
    world.step(round(0.25 / world.dt))
    steps = max(1, round(seconds / world.dt))
    start = time.perf_counter()
    world.step(steps)
    return (time.perf_counter() - start) / steps


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
            per_step = time_steps(world_with(kind, count), args.seconds)
            base = per_step if base is None else base
            print(f"| {count:,} | {kind} | {per_step / count * 1e6:.1f} | "
                  f"{per_step / base:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
