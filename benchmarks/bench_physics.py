"""Steps per second of the physics world for 100, 1,000 and 10,000 spheres in a box.

    python benchmarks/bench_physics.py [--counts 100 1000 10000] [--seconds 0.25] [--worst]

Spheres (radius 5 cm) start on a jittered lattice in a box (floor and four walls) sized so the
crowding is the same at every count, with random velocities, and fall and collide. After a
warm-up of 0.25 s (simulated) the step is timed over ``--seconds`` of simulated time. The last
column, time per sphere-step relative to the smallest scene, is the scaling ratio: 1.0 is
perfectly linear, 100 would be quadratic from 100 to 10,000 spheres. Machines are shared and
noisy: compare ratios from one run, not absolute times across runs. The lattice starts just
above the floor, so by the end of the warm-up the spheres are settling into a pile with
thousands of contacts.

``--worst`` adds the worst cases for the broad phase and the push-out: 1,000 and 10,000 spheres
(``--worst-counts``) spawned at one point 1 m above the floor, and as many spawned overlapping,
uniformly in a ball of 3 radii per 1,000 spheres (about 60 spheres in every place where one
would fit). The first ``--worst-steps`` steps are timed from the spawn, when the crowd is densest;
"pairs examined" is the broad phase's candidate count summed over those steps (both of its uses
in a step: contacts and the swept test), "extent" the size of the crowd afterwards.

``--gpu`` adds a table for gpu_shader.physics side by side with the CPU step on the very same
world (the lattice in float32, simultaneous solver) for ``--gpu-counts`` (default 100, 1,000
and 10,000 spheres): steps/s of each after the same warm-up, the GPU's timed with a read-back
of the state at the end, as `physics.simulate` would do at a record. "candidates" is how many
bodies the GPU's grid walks met per sphere in the last step (contacts and sweep test
together; every pair would be 2 N). ``--gpu-repeat`` runs each that many times, CPU and GPU
in turn, and gives the fastest and the median. ``--counts`` with no value skips the float64
table:

    python benchmarks/bench_physics.py --counts --gpu --gpu-repeat 3
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
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


def spawned_crowd(count: int, spawn: str, solver: str, seed: int = 0) -> physics.World:
    """``count`` spheres of RADIUS above a floor, all at one point or overlapping in a ball."""
    world = physics.World(solver=solver, seed=seed)
    world.add_plane((0, 1, 0), 0)
    centre = np.zeros((count, 3)) + (0, 1, 0)
    if spawn == "overlapping":
        rng = np.random.default_rng(seed)
        direction = rng.normal(size=(count, 3))
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        ball = 3 * RADIUS * (count / 1000) ** (1 / 3)
        centre += direction * ball * rng.uniform(0, 1, (count, 1)) ** (1 / 3)
    world.add_spheres(centre, radius=RADIUS)
    return world


def time_crowd(world: physics.World, steps: int) -> tuple[float, float, int]:
    """(ms of the first step, mean ms per step, pairs examined or -1) over ``steps`` steps."""
    walls, examined = [], 0
    for _ in range(steps):
        start = time.perf_counter()
        world.step(1)
        walls.append(time.perf_counter() - start)
        work = getattr(world, "work", None)                 # the last step's counts
        examined = examined + work["pairs examined"] if work is not None else -1
    return 1e3 * walls[0], 1e3 * float(np.mean(walls)), examined


def time_steps(world: physics.World, seconds: float) -> tuple[int, float]:
    """(steps taken, wall seconds) for ``seconds`` of simulated time, after a 0.25 s warm-up."""
    world.step(int(round(0.25 / world.dt)))
    steps = max(1, int(round(seconds / world.dt)))
    start = time.perf_counter()
    world.step(steps)
    return steps, time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--counts", type=int, nargs="*", default=[100, 1000, 10000],
                        help="lattice sizes (default 100 1000 10000; none: skip them)")
    parser.add_argument("--seconds", type=float, default=0.25,
                        help="simulated seconds timed per scene (default 0.25, 60 steps)")
    parser.add_argument("--solver", action="append", choices=list(physics.SOLVERS),
                        help="solvers to time (default: both)")
    parser.add_argument("--worst", action="store_true",
                        help="also time spheres spawned at one point and overlapping")
    parser.add_argument("--worst-counts", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--worst-steps", type=int, default=10,
                        help="steps timed from the spawn in the worst cases (default 10)")
    parser.add_argument("--gpu", action="store_true",
                        help="also time the GPU step (gpu_shader.physics) for --gpu-counts")
    parser.add_argument("--gpu-counts", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument("--gpu-repeat", type=int, default=1,
                        help="alternating CPU and GPU runs per count, each on a new world "
                             "(default 1)")
    args = parser.parse_args(argv)
    print(f"`python benchmarks/bench_physics.py {' '.join(sys.argv[1:])}`".replace(" `", "`"))
    print(f"\nSpheres in a box, dt = 1/240 s, float64; {cpu_name()}, "
          f"{os.cpu_count()} cores; Python {platform.python_version()}, "
          f"NumPy {np.__version__}.\n")
    if args.counts:
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
    if args.worst:
        time_worst(args.worst_counts, args.worst_steps, args.solver or list(physics.SOLVERS))
    if args.gpu:
        time_gpu(args.gpu_counts, args.seconds, args.gpu_repeat)
    return 0


def time_worst(counts, steps: int, solvers) -> None:
    """Rows for crowds spawned at one point and overlapping, timed from the spawn."""
    print(f"\nWorst cases: the first {steps} steps after the spawn, float64.\n")
    print("| solver | spawn | spheres | first step ms | ms/step | pairs examined | "
          "contacts (last step) | extent after (m) |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for solver in solvers:
        for spawn in ("one point", "overlapping"):
            for count in counts:
                world = spawned_crowd(count, spawn, solver)
                first, mean, examined = time_crowd(world, steps)
                contacts = len(physics.contacts.find_contacts(world, world.slop))
                extent = float(np.max(np.ptp(world.position, axis=0)))
                shown = f"{examined:,}" if examined >= 0 else "not counted"
                print(f"| {solver} | {spawn} | {count:,} | {first:.0f} | {mean:.0f} | {shown} | "
                      f"{contacts:,} | {extent:.3f} |", flush=True)


def time_gpu(counts, seconds: float, repeat: int = 1) -> None:
    """Rows for the GPU step beside the CPU step: the same boxes in float32, simultaneous
    solver, the same warm-up; the GPU's steps/s include the final read-back. With ``repeat``
    > 1 the two take turns, each run on a world built afresh and timed over the same stretch
    after the warm-up, and the table gives the fastest run of each (the median in brackets)."""
    from gpu_shader.context import gl_context, renderer_name
    from gpu_shader.physics import GpuStepper
    print(f"\nGPU step on {renderer_name(gl_context())} beside the CPU step, both float32, "
          f"simultaneous solver, the same world; fastest of {repeat} alternating runs "
          "(median):\n")
    print("| spheres | contacts (last step) | CPU steps/s | GPU steps/s | GPU / CPU | "
          "GPU ms/step | GPU candidates per sphere |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    def cell(fastest: float, median: float, digits: int) -> str:      # "fastest (median)"
        return f"{fastest:.{digits}f}" + (f" ({median:.{digits}f})" if repeat > 1 else "")

    for count in counts:
        cpu_walls, gpu_walls = [], []
        for _ in range(repeat):
            world = box_of_spheres(count, "simultaneous").copy(dtype="float32")
            steps, wall = time_steps(world, seconds)
            cpu_walls.append(wall)
            contacts = len(physics.contacts.find_contacts(world, world.slop))
            world = box_of_spheres(count, "simultaneous").copy(dtype="float32")
            stepper = GpuStepper(world)
            stepper(int(round(0.25 / world.dt)))               # the same warm-up as the CPU
            start = time.perf_counter()
            stepper(steps)
            gpu_walls.append(time.perf_counter() - start)
        cpu, gpu = steps / min(cpu_walls), steps / min(gpu_walls)
        cpu_median, gpu_median = (steps / statistics.median(w) for w in (cpu_walls, gpu_walls))
        print(f"| {count:,} | {contacts:,} | {cell(cpu, cpu_median, 1)} | "
              f"{cell(gpu, gpu_median, 1)} | {cell(gpu / cpu, gpu_median / cpu_median, 2)} | "
              f"{1e3 / gpu:.2f} | {stepper.candidates() / count:.1f} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
