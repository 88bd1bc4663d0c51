"""Steps per second of the physics world for 100, 1,000 and 10,000 spheres in a box.

    python benchmarks/bench_physics.py [--counts 100 1000 10000] [--seconds 0.25]

Spheres (radius 5 cm) start on a jittered lattice in a box (floor and four walls) sized so the
crowding is the same at every count, with random velocities, and fall and collide. After a
warm-up of 0.25 s (simulated) the step is timed over ``--seconds`` of simulated time. The last
column, time per sphere-step relative to the smallest scene, is the scaling ratio: 1.0 is
perfectly linear, 100 would be quadratic from 100 to 10,000 spheres. Machines are shared and
noisy: compare ratios from one run, not absolute times across runs. The lattice starts just
above the floor, so by the end of the warm-up the spheres are settling into a pile with
thousands of contacts.

``--gpu`` adds rows for gpu_shader.physics (the same scene in float32, simultaneous solver,
brute-force O(N^2) contacts; the default counts there are 100 and 1,000), timed with a
read-back of the state at the end, as `physics.simulate` would do at a record.
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

RADIUS = 0.05
SPACING = 2.2 * RADIUS          # lattice spacing: 1.1 diameters between centres


def box_of_spheres(count: int, solver: str, seed: int = 0) -> physics.World:
    """``count`` spheres on a jittered lattice in a square box of matching size."""
    side = int(np.ceil(count ** (1 / 3)))
    half = side * SPACING / 2 + RADIUS
    world = physics.World(solver=solver, seed=seed)
    world.add_plane((0, 1, 0), 0, friction=0.4)
    for normal in [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]:
        world.add_plane(normal, -half, friction=0.4)
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    grid = grid[rng.permutation(len(grid))[:count]]
    centre = (grid - (side - 1) / 2) * SPACING + rng.uniform(-0.2, 0.2, (count, 3)) * RADIUS
    centre[:, 1] += (side - 1) / 2 * SPACING + 1.5 * RADIUS     # bottom layer just above floor
    world.add_spheres(centre, velocities=rng.normal(0, 1, (count, 3)), radius=RADIUS,
                      restitution=0.5, friction=0.4)
    return world


def time_steps(world: physics.World, seconds: float) -> tuple[int, float]:
    """(steps taken, wall seconds) for ``seconds`` of simulated time, after a 0.25 s warm-up."""
    world.step(int(round(0.25 / world.dt)))
    steps = max(1, int(round(seconds / world.dt)))
    start = time.perf_counter()
    world.step(steps)
    return steps, time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument("--seconds", type=float, default=0.25,
                        help="simulated seconds timed per scene (default 0.25, 60 steps)")
    parser.add_argument("--solver", action="append", choices=list(physics.SOLVERS),
                        help="solvers to time (default: both)")
    parser.add_argument("--gpu", action="store_true",
                        help="also time the GPU step (gpu_shader.physics) for --gpu-counts")
    parser.add_argument("--gpu-counts", type=int, nargs="+", default=[100, 1000])
    args = parser.parse_args(argv)
    print(f"`python benchmarks/bench_physics.py {' '.join(sys.argv[1:])}`".replace(" `", "`"))
    print(f"\nSpheres in a box, dt = 1/240 s, float64; {cpu_name()}, "
          f"{os.cpu_count()} cores; Python {platform.python_version()}, "
          f"NumPy {np.__version__}.\n")
    print("| solver | spheres | contacts (last step) | steps/s | ms/step | "
          "us per sphere-step | ratio to smallest |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for solver in args.solver or list(physics.SOLVERS):
        smallest = None
        for count in args.counts:
            world = box_of_spheres(count, solver)
            steps, wall = time_steps(world, args.seconds)
            contacts = len(physics.contacts.find_contacts(world, world.slop))
            per_sphere_step = wall / steps / count
            smallest = smallest or per_sphere_step
            print(f"| {solver} | {count:,} | {contacts:,} | {steps / wall:.1f} | "
                  f"{1e3 * wall / steps:.2f} | {1e6 * per_sphere_step:.2f} | "
                  f"{per_sphere_step / smallest:.2f} |", flush=True)
    if args.gpu:
        time_gpu(args.gpu_counts, args.seconds)
    return 0


def time_gpu(counts, seconds: float) -> None:
    """Rows for the GPU step: the same boxes, float32, steps/s including the final read-back."""
    from gpu_shader.context import gl_context, renderer_name
    from gpu_shader.physics import GpuStepper
    print(f"\nGPU step on {renderer_name(gl_context())} (float32, simultaneous, O(N^2) "
          "contacts):\n")
    print("| backend | spheres | steps/s | ms/step |")
    print("| --- | ---: | ---: | ---: |")
    for count in counts:
        world = box_of_spheres(count, "simultaneous").copy(dtype="float32")
        stepper = GpuStepper(world)
        stepper(int(round(0.25 / world.dt)))               # the same warm-up as the CPU
        steps = max(1, int(round(seconds / world.dt)))
        start = time.perf_counter()
        stepper(steps)
        wall = time.perf_counter() - start
        print(f"| gpu | {count:,} | {steps / wall:.1f} | {1e3 * wall / steps:.2f} |",
              flush=True)


if __name__ == "__main__":
    sys.exit(main())
