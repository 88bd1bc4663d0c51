"""Convex SDF bodies in the CPU step: speed against error, and against Bullet 3 side by side.

    python benchmarks/bench_convex.py [--seconds 0.5] [--repeat 3]
    (pip install pybullet for the Bullet rows; without it only marchlab is timed)

Two cases, the same in both engines (dt = 1/240 s, gravity -9.81 m/s^2, e = 0, density
1000 kg/m^3):

- ``rolling``: a solid cylinder (radius 0.2 m, half height 0.25 m) lying on a plane inclined
  30 degrees, mu = 0.5, released at rest: it rolls with a = 2/3 g sin 30 = 3.270 m/s^2. The
  table gives the acceleration fitted over ``--seconds`` and its error. marchlab's cylinder
  is a convex body (`physics.World.add_convex` of the scene's capped_cylinder SDF), and for
  comparison its capsule of the same radius (an exact kind: a ball's 5/7 is not the answer
  for it either, so only its time is shown); Bullet's is its GEOM_CYLINDER.
- ``standing``: a cone (radius 0.3 m, height 0.6 m) on its base on the floor, mu = 0.5: it
  must not move; the table gives how far its centre drifted. Bullet's cone is the convex hull
  of 64 points of its base circle and its apex (pybullet has no cone shape).

Each engine steps each case ``--repeat`` times, in turn, and the fastest is kept: these
machines are shared. Times are milliseconds per step, measured over the same ``--seconds``.
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
from bench_pybullet import DT, bullet_world  # noqa: E402  (Bullet set up as for the spheres)
from bench_render import cpu_name  # noqa: E402
from marchlab.colliders import body_solid  # noqa: E402
from scene_model.geometry import quaternion_from_matrix, rotation_matrix  # noqa: E402
from scene_model.shapes import CappedCylinder, Cone, Rotate  # noqa: E402

SLOPE = np.radians(30.0)
NORMAL = np.array([-np.sin(SLOPE), np.cos(SLOPE), 0.0])
DOWN = -np.array([np.cos(SLOPE), np.sin(SLOPE), 0.0])
RADIUS, HALF_HEIGHT = 0.2, 0.25
CONE_RADIUS, CONE_HEIGHT = 0.3, 0.6
EXACT = 2 / 3 * 9.81 * np.sin(SLOPE)


def marchlab_rolling(kind: str):
    """(step(n), centre()) of marchlab's cylinder or capsule lying on the incline."""
    world = physics.World(dt=DT)
    world.add_plane(NORMAL, 0.0, restitution=0.0, friction=0.5)
    along_z = rotation_matrix((90.0, 0.0, 0.0))
    centre = NORMAL * RADIUS
    if kind == "convex":
        solid = body_solid(Rotate(CappedCylinder(RADIUS, HALF_HEIGHT), (90.0, 0.0, 0.0)))
        world.add_convex(centre, solid, quaternion_from_matrix(solid.axes), density=1000,
                         restitution=0.0, friction=0.5)
    else:
        world.add_capsule(centre, HALF_HEIGHT, RADIUS, quaternion_from_matrix(along_z),
                          density=1000, restitution=0.0, friction=0.5)
    return world.step, lambda: world.position[0].copy()


def marchlab_standing():
    world = physics.World(dt=DT)
    world.add_plane((0, 1, 0), 0.0, restitution=0.0, friction=0.5)
    solid = body_solid(Cone(CONE_RADIUS, CONE_HEIGHT))
    world.add_convex(solid.centroid, solid, quaternion_from_matrix(solid.axes), density=1000,
                     restitution=0.0, friction=0.5)
    return world.step, lambda: world.position[0].copy()


def bullet_body(pybullet, client, shape, mass, position, orientation):
    body = pybullet.createMultiBody(mass, shape, basePosition=list(position),
                                    baseOrientation=list(orientation), physicsClientId=client)
    pybullet.changeDynamics(body, -1, restitution=0.0, lateralFriction=0.5,
                            physicsClientId=client)
    return body


def bullet_ground(pybullet, client, normal):
    """A thick box whose top face is the plane through the origin with ``normal``."""
    shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[20, 0.5, 20],
                                          physicsClientId=client)
    turn = np.eye(3)
    turn[:, 1] = normal
    turn[:, 0] = np.cross(normal, (0, 0, 1.0))
    turn[:, 0] /= np.linalg.norm(turn[:, 0])
    turn[:, 2] = np.cross(turn[:, 0], normal)
    w, x, y, z = quaternion_from_matrix(turn)
    bullet_body(pybullet, client, shape, 0, -0.5 * np.asarray(normal), (x, y, z, w))


def bullet_rolling():
    pybullet, client = bullet_world()
    bullet_ground(pybullet, client, NORMAL)
    # Bullet's cylinder runs along its own z: no turn needed to lie across the slope.
    shape = pybullet.createCollisionShape(pybullet.GEOM_CYLINDER, radius=RADIUS,
                                          height=2 * HALF_HEIGHT, physicsClientId=client)
    mass = np.pi * RADIUS ** 2 * 2 * HALF_HEIGHT * 1000
    body = bullet_body(pybullet, client, shape, mass, NORMAL * RADIUS, (0, 0, 0, 1))
    return _bullet_pair(pybullet, client, body)


def bullet_standing():
    pybullet, client = bullet_world()
    bullet_ground(pybullet, client, (0.0, 1.0, 0.0))
    angle = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    base = np.stack([CONE_RADIUS * np.cos(angle), np.zeros(64),
                     CONE_RADIUS * np.sin(angle)], axis=1)
    points = np.concatenate([base, [[0.0, CONE_HEIGHT, 0.0]]]) - [0, CONE_HEIGHT / 4, 0]
    shape = pybullet.createCollisionShape(pybullet.GEOM_MESH, vertices=points.tolist(),
                                          physicsClientId=client)
    mass = np.pi * CONE_RADIUS ** 2 * CONE_HEIGHT / 3 * 1000
    body = bullet_body(pybullet, client, shape, mass, (0, CONE_HEIGHT / 4, 0), (0, 0, 0, 1))
    return _bullet_pair(pybullet, client, body)


def _bullet_pair(pybullet, client, body):
    def step(n: int) -> None:
        for _ in range(n):
            pybullet.stepSimulation(physicsClientId=client)

    def centre():
        return np.array(pybullet.getBasePositionAndOrientation(body, client)[0])
    return step, centre


def timed(make, seconds: float):
    """(ms per step, the centre's track (T, 3)) of a fresh world from ``make``."""
    step, centre = make()
    track = [centre()]
    elapsed = 0.0
    for _ in range(round(seconds / DT)):
        start = time.perf_counter()
        step(1)
        elapsed += time.perf_counter() - start
        track.append(centre())
    return 1e3 * elapsed / (len(track) - 1), np.array(track)


def acceleration(track) -> float:
    """The acceleration down the slope (m/s^2) fitted to the track."""
    t = np.arange(len(track)) * DT
    return 2 * np.polyfit(t, (track - track[0]) @ DOWN, 2)[0]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=0.5)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    try:
        import pybullet  # noqa: F401
        bullet = True
    except ImportError:
        bullet = False
    cases = [("rolling", "marchlab convex cylinder", lambda: marchlab_rolling("convex")),
             ("rolling", "marchlab capsule", lambda: marchlab_rolling("capsule")),
             ("standing", "marchlab convex cone", marchlab_standing)]
    if bullet:
        cases += [("rolling", "Bullet cylinder", bullet_rolling),
                  ("standing", "Bullet cone (hull of 65 points)", bullet_standing)]
    best = {}
    for _ in range(args.repeat):
        for case, name, make in cases:
            ms, track = timed(make, args.seconds)
            if (case, name) not in best or ms < best[case, name][0]:
                best[case, name] = (ms, track)
    print(f"{platform.python_version()}, {cpu_name()}, {os.cpu_count()} cores; "
          f"{args.seconds} s of dt = 1/240 s, fastest of {args.repeat}\n")
    print("| case | body | ms/step | result |")
    print("|---|---|---:|---|")
    for (case, name), (ms, track) in best.items():
        if case == "rolling":
            a = acceleration(track)
            result = (f"a = {a:.4f} m/s^2, error {abs(a - EXACT) / EXACT:.2%}"
                      if "capsule" not in name else f"a = {a:.4f} m/s^2 (not a cylinder)")
        else:
            result = f"drift {np.max(np.linalg.norm(track - track[0], axis=1)):.2e} m"
        print(f"| {case} | {name} | {ms:.3f} | {result} |")
    if not bullet:
        print("\n(pybullet is not installed: no Bullet rows)")


if __name__ == "__main__":
    main()
