"""Boxes in the CPU step: a resting stack and a falling pile, against Bullet 3 side by side.

    python benchmarks/bench_solids.py [--piles 10 30] [--thrown 10] [--seconds 0.5] [--unswept]
                                      [--repeat 1]
    (pip install pybullet for the Bullet column; without it only marchlab is timed)

Three scenes, the same in both engines (dt = 1/240 s, gravity -9.81 m/s^2, friction 0.6,
restitution 0, boxes of half sizes (0.2, 0.1, 0.15) m and density 500 kg/m^3):

- ``stack``: five boxes stacked on the floor, timed at rest after 1 s of settling: the cost of
  holding a stack still (about 24 contacts, most of them four to a face);
- ``pile N``: N boxes dropped from a lattice 0.5 m apart in random orientations, timed over
  the first ``--seconds`` after 0.25 s: landings, tumbling and box-box contacts;
- ``thrown N``: the same pile thrown down at 20 m/s (8 cm a step), timed from the start: the
  swept test (physics/solid_sweeps.py) meets the floor and the boxes at their time of impact.

``--unswept`` times marchlab a second time, in the same run, with the step as it was before
the swept test: contacts found within each body's whole speculative margin and no box swept
(`without_sweeps`), and adds that column and the swept step's time over it. ``--repeat N``
times every engine N times, one after the other in turn, and keeps the fastest: on a machine
shared with other work the fastest of a few runs is the one least disturbed.

marchlab steps with `physics.World.step` (float64, sequential solver: the one boxes need);
Bullet with `stepSimulation` (its default solver, 10 iterations, DIRECT mode). The table
gives milliseconds per step and marchlab's time over Bullet's, measured one after the other in
one run. Bullet is C++ with its own contact generation (a persistent manifold of at most 4
points per pair) and sleeping; marchlab is NumPy with a Python loop over colours and passes:
compare speeds, not answers.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import physics  # noqa: E402
from bench_pybullet import bullet_world, seconds_per_step  # noqa: E402  (dt = 1/240 s)
from bench_render import cpu_name  # noqa: E402
import physics.world  # noqa: E402
from physics.quaternions import quaternion_from_rotation_vector  # noqa: E402
from physics.solid_contacts import speculative_margin  # noqa: E402

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


THROWN = (0.0, -20.0, 0.0)   # m/s, the ``thrown`` scene's initial velocity


@contextlib.contextmanager
def without_sweeps():
    """Step as before the swept test of boxes and capsules: contacts within each body's
    whole speculative margin (solid_contacts.speculative_margin, not capped at the
    speculative distance) and `World._sweep_solids` doing nothing. For timing only."""
    saved = physics.world.contact_reach, physics.World._sweep_solids
    physics.world.contact_reach = speculative_margin
    physics.World._sweep_solids = lambda self, *arguments: []
    try:
        yield
    finally:
        physics.world.contact_reach, physics.World._sweep_solids = saved


def marchlab_stepper(centre, turn, velocity=(0.0, 0.0, 0.0)):
    world = physics.World(dt=DT)
    world.add_plane((0, 1, 0), 0.0, restitution=0.0, friction=FRICTION)
    for x, q in zip(centre, turn):
        world.add_box(x, HALF, orientation=q, velocity=velocity, restitution=0.0,
                      friction=FRICTION, density=DENSITY)
    return world.step


def bullet_stepper(centre, turn, velocity=(0.0, 0.0, 0.0)):
    pybullet, client = bullet_world()
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
        pybullet.resetBaseVelocity(body, linearVelocity=velocity, physicsClientId=client)

    def step(n: int) -> None:
        for _ in range(n):
            pybullet.stepSimulation(physicsClientId=client)
    return step


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--piles", type=int, nargs="+", default=[10, 30])
    parser.add_argument("--thrown", type=int, nargs="*", default=[10])
    parser.add_argument("--seconds", type=float, default=0.5)
    parser.add_argument("--unswept", action="store_true",
                        help="also time marchlab without the swept test (the step before it)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="time each engine this many times in turn, keep the fastest")
    args = parser.parse_args(argv)
    try:
        import pybullet  # noqa: F401
        bullet = True
    except ImportError:
        bullet = False
    print(f"# {cpu_name()}, Python {platform.python_version()}, NumPy {np.__version__}; "
          f"{args.seconds} s simulated, dt = 1/240 s")
    unswept = " marchlab unswept ms/step | swept / unswept |" if args.unswept else ""
    print(f"| scene | boxes | marchlab ms/step | Bullet ms/step | marchlab / Bullet |{unswept}")
    print("|---|---:|---:|---:|---:|" + ("---:|---:|" if args.unswept else ""))
    still = (0.0, 0.0, 0.0)
    cases = [("stack (at rest)", 1.0, stack_boxes(), still)]
    cases += [("pile (falling)", 0.25, pile_boxes(count), still) for count in args.piles]
    cases += [("thrown down at 20 m/s", 0.0, pile_boxes(count), THROWN)
              for count in args.thrown]
    for name, warm_up, (centre, turn), velocity in cases:
        ours = theirs = before = float("inf")
        for _ in range(args.repeat):
            ours = min(ours, seconds_per_step(marchlab_stepper(centre, turn, velocity),
                                              args.seconds, warm_up))
            if bullet:
                theirs = min(theirs, seconds_per_step(bullet_stepper(centre, turn, velocity),
                                                      args.seconds, warm_up))
            if args.unswept:
                with without_sweeps():
                    before = min(before, seconds_per_step(
                        marchlab_stepper(centre, turn, velocity), args.seconds, warm_up))
        theirs = theirs if bullet else float("nan")
        row = (f"| {name} | {len(centre)} | {ours * 1e3:.2f} | {theirs * 1e3:.3f} | "
               f"{ours / theirs:.0f}x |")
        if args.unswept:
            row += f" {before * 1e3:.2f} | {ours / before:.2f}x |"
        print(row, flush=True)


if __name__ == "__main__":
    main()
