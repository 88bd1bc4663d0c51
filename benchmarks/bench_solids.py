"""Boxes in the CPU step: a resting stack and a falling pile, against Bullet 3 side by side.

    python benchmarks/bench_solids.py [--piles 10 30] [--seconds 0.5]
    (pip install pybullet for the Bullet column; without it only marchlab is timed)

Two scenes, the same in both engines (dt = 1/240 s, gravity -9.81 m/s^2, friction 0.6,
restitution 0, boxes of half sizes (0.2, 0.1, 0.15) m and density 500 kg/m^3):

- ``stack``: five boxes stacked on the floor, timed at rest after 1 s of settling: the cost of
  holding a stack still (about 24 contacts, most of them four to a face);
- ``pile N``: N boxes dropped from a lattice 0.5 m apart in random orientations, timed over
  the first ``--seconds`` after 0.25 s: landings, tumbling and box-box contacts.

marchlab steps with `physics.World.step` (float64, sequential solver: the one boxes need);
Bullet with `stepSimulation` (its default solver, 10 iterations, DIRECT mode). The table
gives milliseconds per step and marchlab's time over Bullet's, measured one after the other in
one run. Bullet is C++ with its own contact generation (a persistent manifold of at most 4
points per pair) and sleeping; marchlab is NumPy with a Python loop over colours and passes:
compare speeds, not answers.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import physics  # noqa: E402
from bench_pybullet import seconds_per_step  # noqa: E402  (the same timing, dt = 1/240 s)
from bench_render import cpu_name  # noqa: E402
from physics.quaternions import quaternion_from_rotation_vector  # noqa: E402

DT = 1 / 240
HALF = (0.2, 0.1, 0.15)
DENSITY = 500.0
FRICTION = 0.6


def stack_boxes(count: int = 5):
    """Centres (count, 3) and orientations (count, 4) of a stack on the floor."""
    centre = np.array([(0.0, HALF[1] * (2 * k + 1), 0.0) for k in range(count)])
    return centre, np.tile([1.0, 0, 0, 0], (count, 1))


def pile_boxes(count: int, seed: int = 0):
    """Centres and random orientations of ``count`` boxes on a lattice 0.5 m apart."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(count)))
    k = np.arange(count)
    centre = np.stack([(k % side - side / 2) * 0.5, 0.5 + 0.5 * (k // side) / side * 2
                       + rng.uniform(0, 0.3, count), (k // side % side - side / 2) * 0.5],
                      axis=1)
    turn = quaternion_from_rotation_vector(rng.uniform(-np.pi, np.pi, (count, 3)))
    return centre, turn


def marchlab_stepper(centre, turn):
    world = physics.World(dt=DT)
    world.add_plane((0, 1, 0), 0.0, restitution=0.0, friction=FRICTION)
    for x, q in zip(centre, turn):
        world.add_box(x, HALF, orientation=q, restitution=0.0, friction=FRICTION,
                      density=DENSITY)
    return world.step


def bullet_stepper(centre, turn):
    import pybullet
    client = pybullet.connect(pybullet.DIRECT)
    pybullet.setGravity(0, -9.81, 0, physicsClientId=client)
    pybullet.setTimeStep(DT, physicsClientId=client)
    floor = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=(50, 0.5, 50),
                                          physicsClientId=client)
    body = pybullet.createMultiBody(0, floor, basePosition=(0, -0.5, 0),
                                    physicsClientId=client)
    pybullet.changeDynamics(body, -1, restitution=0.0, lateralFriction=FRICTION,
                            physicsClientId=client)
    shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=HALF,
                                          physicsClientId=client)
    mass = 8 * np.prod(HALF) * DENSITY
    for x, q in zip(centre, turn):
        # Bullet's quaternions are (x, y, z, w); marchlab's (w, x, y, z).
        body = pybullet.createMultiBody(mass, shape, basePosition=x.tolist(),
                                        baseOrientation=[q[1], q[2], q[3], q[0]],
                                        physicsClientId=client)
        pybullet.changeDynamics(body, -1, restitution=0.0, lateralFriction=FRICTION,
                                physicsClientId=client)

    def step(n: int) -> None:
        for _ in range(n):
            pybullet.stepSimulation(physicsClientId=client)
    return step


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--piles", type=int, nargs="+", default=[10, 30])
    parser.add_argument("--seconds", type=float, default=0.5)
    args = parser.parse_args(argv)
    try:
        import pybullet  # noqa: F401
        bullet = True
    except ImportError:
        bullet = False
    print(f"# {cpu_name()}, Python {platform.python_version()}, NumPy {np.__version__}; "
          f"{args.seconds} s simulated, dt = 1/240 s")
    print("| scene | boxes | marchlab ms/step | Bullet ms/step | marchlab / Bullet |")
    print("|---|---:|---:|---:|---:|")
    cases = [("stack (at rest)", 1.0, stack_boxes())]
    cases += [("pile (falling)", 0.25, pile_boxes(count)) for count in args.piles]
    for name, warm_up, (centre, turn) in cases:
        ours = seconds_per_step(marchlab_stepper(centre, turn), args.seconds, warm_up)
        theirs = (seconds_per_step(bullet_stepper(centre, turn), args.seconds, warm_up)
                  if bullet else float("nan"))
        print(f"| {name} | {len(centre)} | {ours * 1e3:.2f} | {theirs * 1e3:.3f} | "
              f"{ours / theirs:.0f}x |", flush=True)


if __name__ == "__main__":
    main()
