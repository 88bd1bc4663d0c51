"""The CPU step against Bullet 3 (pybullet) on the same pile of spheres, side by side.

    pip install pybullet          # a benchmark's dependency only, not the toolkit's
    python benchmarks/bench_pybullet.py [--counts 100 1000 10000] [--seconds 0.25] [--repeat 5]

Both engines get the same world: spheres of radius 5 cm on a jittered lattice in a box (a
floor and four walls, as planes), with the same random velocities, restitution 0.5, friction
0.4, gravity -9.81 m/s^2 and dt = 1/240 s. marchlab steps it with `physics.World.step`
(float64, each solver), Bullet with `stepSimulation` (its default sequential impulse solver,
10 iterations, one substep; DIRECT mode, no GUI). The engines take turns, ``--repeat``
rounds: in each, every engine builds the world afresh, steps 0.25 s of warm-up (simulated)
and is timed over the next ``--seconds``, in this process's CPU time (`time.process_time`:
both run in this one thread, and time spent waiting for a core of a busy machine is not
counted). The table gives each engine's fastest and median run in microseconds per
sphere-step and marchlab's over Bullet's, fastest to fastest and median to median. Machines
are shared and noisy: compare the ratios of one run, not absolute times across runs.

Bullet is C++ with one call per step; marchlab is NumPy with a Python loop over the stages of
a step and, in the sequential solver, over dependency levels. The engines also differ in what
they compute (Bullet: a single contact point per pair, split impulses, its own restitution
threshold and sleeping), so the comparison is of speed on the same scene, not of answers.
"""

from __future__ import annotations

import argparse
import functools
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
SPACING = 2.2 * RADIUS
DT = 1 / 240
WARM_UP = 0.25


def pile(count: int, seed: int = 0):
    """Centres (count, 3), velocities (count, 3) and the box's half-width for ``count``
    spheres on a jittered lattice just above the floor."""
    side = int(np.ceil(count ** (1 / 3)))
    half = side * SPACING / 2 + RADIUS
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    grid = grid[rng.permutation(len(grid))[:count]]
    centre = (grid - (side - 1) / 2) * SPACING + rng.uniform(-0.2, 0.2, (count, 3)) * RADIUS
    centre[:, 1] += (side - 1) / 2 * SPACING + 1.5 * RADIUS
    return centre, rng.normal(0, 1, (count, 3)), half


def marchlab_stepper(count: int, solver: str):
    centre, velocity, half = pile(count)
    world = physics.World(dt=DT, solver=solver)
    world.add_plane((0, 1, 0), 0, friction=0.4)
    for normal in [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]:
        world.add_plane(normal, -half, friction=0.4)
    world.add_spheres(centre, velocities=velocity, radius=RADIUS, restitution=0.5,
                      friction=0.4)
    return world.step


def bullet_world():
    """(the pybullet module, a new client): DIRECT mode (no GUI), gravity -9.81 m/s^2 along
    y, dt = 1/240 s, as every benchmark against Bullet steps it."""
    import pybullet
    client = pybullet.connect(pybullet.DIRECT)
    pybullet.setGravity(0, -9.81, 0, physicsClientId=client)
    pybullet.setTimeStep(DT, physicsClientId=client)
    return pybullet, client


def bullet_stepper(count: int):
    centre, velocity, half = pile(count)
    pybullet, client = bullet_world()
    # Bullet's planes are z-up; the floor and walls are boxes, the same faces as the planes.
    walls = [((0, -0.5, 0), (half + 1, 0.5, half + 1))]
    for x, z in [(1, 0), (-1, 0), (0, 1), (0, -1)]:
        size = (0.5, 5, half + 1) if x else (half + 1, 5, 0.5)
        walls.append(((x * (half + 0.5), 5, z * (half + 0.5)), size))
    for position, size in walls:
        shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=size,
                                              physicsClientId=client)
        body = pybullet.createMultiBody(0, shape, basePosition=position,
                                        physicsClientId=client)
        pybullet.changeDynamics(body, -1, restitution=0.5, lateralFriction=0.4,
                                physicsClientId=client)
    sphere = pybullet.createCollisionShape(pybullet.GEOM_SPHERE, radius=RADIUS,
                                           physicsClientId=client)
    mass = 4 / 3 * np.pi * RADIUS ** 3 * 1000
    for x, v in zip(centre, velocity):
        body = pybullet.createMultiBody(mass, sphere, basePosition=x.tolist(),
                                        physicsClientId=client)
        pybullet.resetBaseVelocity(body, v.tolist(), physicsClientId=client)
        pybullet.changeDynamics(body, -1, restitution=0.5, lateralFriction=0.4,
                                physicsClientId=client)

    def step(n: int) -> None:
        for _ in range(n):
            pybullet.stepSimulation(physicsClientId=client)
    return step


def seconds_per_step(step, seconds: float, warm_up: float = WARM_UP,
                     clock=time.perf_counter) -> float:
    """Seconds of computing per step of ``step(n)``, timed by ``clock`` over ``seconds`` of
    simulated time after ``warm_up`` (both at dt = 1/240 s)."""
    step(round(warm_up / DT))
    steps = max(1, round(seconds / DT))
    start = clock()
    step(steps)
    return (clock() - start) / steps


def alternating_runs(makers, seconds: float, repeat: int, warm_up: float = WARM_UP):
    """CPU seconds per step of each of ``makers`` (each returns a new ``step(n)``), run by
    run: ``repeat`` rounds in which each in turn builds its world, steps ``warm_up`` simulated
    seconds and is timed over the next ``seconds``. Every run times the same stretch of the
    same simulation (a pile is busiest just after the warm-up and grows calmer), so the
    fastest and the median of the runs compare like with like. Returns one list of
    ``repeat`` figures per maker."""
    runs = [[] for _ in makers]
    for _ in range(repeat):
        for make, figures in zip(makers, runs):
            figures.append(seconds_per_step(make(), seconds, warm_up, time.process_time))
    return runs


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument("--seconds", type=float, default=0.25)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)
    try:
        import pybullet  # noqa: F401
    except ImportError:
        sys.exit("bench_pybullet: pybullet is not installed (pip install pybullet)")
    print(f"# {cpu_name()}, Python {platform.python_version()}, NumPy {np.__version__}; "
          f"{args.seconds} s simulated after {WARM_UP} s of warm-up, {args.repeat} alternating "
          f"runs, dt = 1/240 s, CPU time")
    print("| spheres | engine | µs per sphere-step: fastest, median | against Bullet: "
          "fastest, median |")
    print("|---:|---|---:|---:|")
    for count in args.counts:
        engines = [("Bullet 3 (pybullet)", functools.partial(bullet_stepper, count))]
        engines += [(f"marchlab, {solver}", functools.partial(marchlab_stepper, count, solver))
                    for solver in ("simultaneous", "sequential")]
        runs = alternating_runs([make for _, make in engines], args.seconds, args.repeat)
        figures = [(min(r), statistics.median(r)) for r in runs]
        for (name, _), (fastest, median) in zip(engines, figures):
            print(f"| {count:,} | {name} | {fastest / count * 1e6:.1f}, "
                  f"{median / count * 1e6:.1f} | {fastest / figures[0][0]:.2f}x, "
                  f"{median / figures[0][1]:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
