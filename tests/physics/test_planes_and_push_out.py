"""Planes lie where the renderer draws them, and what the push-out of overlaps costs in energy.

A plane is ``normal/|normal| . x = offset``: the normal is normalised and the offset is the
signed distance from the origin, as in the renderer and the scene format. Push-out moves
overlapping bodies apart by position (physics/solvers.py, separate_overlaps) and never gives
them speed, but lifting a body out of the floor raises it: a ball spawned d into the floor ends
resting at a depth of ``slop``, gaining m g (d - slop) of potential energy and no kinetic.
"""

import numpy as np
import pytest

import physics

RADIUS = 0.1
G = 9.81


@pytest.mark.parametrize("normal, offset", [((0, 2, 0), 1.0), ((0, 0.25, 0), 1.0),
                                            ((0, 1, 0), 1.0)])
def test_a_plane_normal_of_any_length_is_normalised(normal, offset):
    world = physics.World()
    world.add_plane(normal, offset)
    assert world.plane_normal[0] == pytest.approx([0, 1, 0], abs=0)
    assert world.plane_offset[0] == offset


@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_a_ball_dropped_on_the_plane_normal_0_2_0_offset_1_rests_at_y_1_plus_r_within_slop(
        solver):
    world = physics.World(solver=solver)
    world.add_plane((0, 2, 0), 1.0)
    world.add_sphere((0, 1.5, 0), radius=RADIUS, restitution=0.0)
    world.step(480)                                            # 2 s: dropped 0.4 m, at rest
    assert abs(world.position[0, 1] - (1.0 + RADIUS)) <= world.slop
    assert np.all(np.abs(world.velocity[0]) <= 1e-9)


@pytest.mark.parametrize("depth", [0.01, 0.03])
def test_a_ball_spawned_into_the_floor_gains_m_g_depth_minus_slop_within_1e_9(depth):
    """Spawned 1 cm into the floor, a 4.19 kg ball gains m g (0.01 - 1e-4) = 0.4068 J."""
    world = physics.World()
    world.add_plane((0, 1, 0), 0)
    world.add_sphere((0, RADIUS - depth, 0), radius=RADIUS, density=1000)
    energy = world.energy()
    world.step(480)
    m = world.mass[0]
    assert world.kinetic_energy() == 0, "lifted by position only"
    assert world.position[0, 1] == pytest.approx(RADIUS - world.slop, abs=1e-12)
    assert world.energy() - energy == pytest.approx(m * G * (depth - world.slop), rel=1e-9)
