"""marchlab's physics against an independent engine, Bullet 3 (pybullet), where it is meaningful.

pybullet is not a dependency of the toolkit (`pip install pybullet` to run these); without it
the tests are skipped. Bullet's contact model differs from ours (one contact point per pair,
its own restitution handling and sleeping), so only motions that both should get exactly are
compared: a solid ball rolling without slipping down a ramp, where both must give
a = 5/7 g sin 30 and so the same path.
"""

import math

import numpy as np
import pytest

import marchlab
import physics
from marchlab.simulation import build_world

pybullet = pytest.importorskip("pybullet", reason="pybullet is optional: pip install pybullet")


def bullet_ramp_path(scene, steps: int) -> np.ndarray:
    """The bundled ramp in Bullet: the same box turned 30 degrees about z, the same ball and
    friction, no rolling friction or damping; the ball's centre after each step (steps, 3)."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        pybullet.setGravity(0, -9.81, 0, physicsClientId=client)
        pybullet.setTimeStep(scene.physics.dt, physicsClientId=client)
        box = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[2.5, 0.1, 0.6],
                                            physicsClientId=client)
        turned = pybullet.getQuaternionFromEuler([0, 0, math.radians(30)])
        ramp = pybullet.createMultiBody(0, box, basePosition=[0, 1.4, 0],
                                        baseOrientation=turned, physicsClientId=client)
        body = scene.bodies[0]
        sphere = pybullet.createCollisionShape(pybullet.GEOM_SPHERE, radius=body.radius,
                                               physicsClientId=client)
        mass = 4 / 3 * math.pi * body.radius ** 3 * scene.physics.density
        ball = pybullet.createMultiBody(mass, sphere, basePosition=list(body.position),
                                        physicsClientId=client)
        for handle in (ramp, ball):
            pybullet.changeDynamics(handle, -1, lateralFriction=0.5, restitution=0.0,
                                    rollingFriction=0.0, spinningFriction=0.0,
                                    linearDamping=0.0, angularDamping=0.0,
                                    physicsClientId=client)
        path = []
        for _ in range(steps):
            pybullet.stepSimulation(physicsClientId=client)
            path.append(pybullet.getBasePositionAndOrientation(ball, physicsClientId=client)[0])
        return np.array(path)
    finally:
        pybullet.disconnect(client)


def test_ramp_ball_follows_bullets_path_within_1e_5_m_for_1_s():
    """Measured: 8.7e-6 m apart after 240 steps; Bullet's acceleration is 5/7 g sin 30 to
    2e-15, ours to 2e-12 (tests/test_scene_colliders.py)."""
    scene = marchlab.load_scene("ramp")
    ours = physics.simulate(build_world(scene), 1.0).positions[1:, 0]
    theirs = bullet_ramp_path(scene, len(ours))
    assert np.abs(ours - theirs).max() < 1e-5
    down = -np.array([math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0])
    t = np.arange(1, len(theirs) + 1) * scene.physics.dt
    s = (theirs - np.array(scene.bodies[0].position)) @ down
    assert 2 * np.polyfit(t, s, 2)[0] == pytest.approx(5 / 7 * 9.81 * 0.5, rel=1e-9)
