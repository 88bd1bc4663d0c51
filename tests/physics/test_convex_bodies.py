"""Bodies of any convex shape (physics/convex.py, convex_contacts.py and the convex kinds of
solid_contacts.py and solid_sweeps.py), each against a closed form or against the box or
sphere body of the same shape, under a stated tolerance.

The solids are built as `marchlab.colliders.body_solid` builds them, from the renderer's SDF
of a scene node in float64 (reference_cpu.scene_sdf) and its central-difference normal, but
without importing marchlab: the physics tests stay below the front door. Their mass, centre
and inertia come from a 96-cell grid, so they are right to about 0.1% (measured below);
every check that depends on them says so in its tolerance. The measured errors quoted are
those of the tree these tests were written against. Runs are short (at most 1.5 s of
one or two convex bodies at dt = 1/240 s, 10-30 ms a step).
"""

import dataclasses

import numpy as np
import pytest
from test_shapes import box_shape

import physics
from physics.convex import convex_solid, support
from physics.quaternions import quaternion_from_rotation_vector, rotation_matrices
from physics.solids import CONVEX
from reference_cpu.normals import estimate_normal
from reference_cpu.scene_sdf import build_scene_sdf
from reference_cpu.sdf import sdf_capped_cylinder
from scene_model.bounds import bounding_sphere
from scene_model.geometry import quaternion_from_matrix, rotation_matrix
from scene_model.shapes import Box, CappedCylinder, Cone, HexPrism, Rotate, Sphere, Translate

G = 9.81
SLOP = 1e-4              # the World's default slop (m): how far a resting contact may sink
NORMAL_STEP = 1e-5       # the float64 normal step marchlab.colliders uses for body solids (m)
TURN = (30.0, -50.0, 70.0)   # Euler degrees of a turn about no special axis


def solid_of(node):
    """The `ConvexSolid` of a scene node, as marchlab.colliders.body_solid makes it."""
    sdf = build_scene_sdf([node], np.float64)
    centre, radius = bounding_sphere(node)
    return convex_solid(node.kind, lambda p: sdf(p)[0],
                        lambda p: estimate_normal(sdf, p, NORMAL_STEP),
                        centre - radius, centre + radius)


def add_placed(world, solid, origin, degrees=(0.0, 0.0, 0.0), **kwargs) -> int:
    """Add ``solid`` as a convex body with the frame it was given in (the node's own) at
    ``origin`` turned by Euler ``degrees``, as `marchlab.simulation.build_world` places a
    scene's convex body: centre of mass at origin + R centroid, principal axes R axes."""
    turn = rotation_matrix(degrees)
    return world.add_convex(np.asarray(origin, float) + turn @ solid.centroid, solid,
                            quaternion_from_matrix(turn @ solid.axes), **kwargs)


def given_to_world(world, j, solid, points):
    """World positions (K, 3) of points (K, 3) given in the frame ``solid`` was built in."""
    own = (np.asarray(points, float) - solid.centroid) @ solid.axes
    return world.position[j] + own @ rotation_matrices(world.orientation[j:j + 1])[0].T


def world_to_given(world, j, solid, points):
    """The inverse of `given_to_world`."""
    own = (np.asarray(points, float) - world.position[j]) @ rotation_matrices(
        world.orientation[j:j + 1])[0]
    return solid.centroid + own @ solid.axes.T


def cylinder_axis(world, j, solid):
    """The world direction (3,) of a CappedCylinder body's axis (its node's y)."""
    ends = given_to_world(world, j, solid, [[0, 0, 0], [0, 1, 0]])
    return ends[1] - ends[0]


def hex_corners(apothem, half_length):
    """The 12 corners (12, 3) of a HexPrism node: a hexagon with corners on the x axis at
    2 apothem / sqrt 3 from it, extruded along z."""
    angle = np.radians(60.0 * np.arange(6))
    ring = 2 * apothem / np.sqrt(3) * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    return np.array([[x, y, z] for x, y in ring for z in (-half_length, half_length)])


# --- mass, centre and principal axes -----------------------------------------------------------

R, HH = 0.2, 0.25        # a cylinder: radius and half height
CR, CH = 0.3, 0.5        # a cone: base radius and height (moments 0.0229 and 0.0270 m^2 apart)
A, B, C = 0.3, 0.2, 0.1  # a box's half sizes
HA, HL = 0.15, 0.25      # a hexagonal prism's apothem and half length


def cylinder_gyration(r, h):
    """I / m about the axis and across it through the centre, h the whole height (any
    mechanics text, e.g. Goldstein, Classical Mechanics, 3rd ed., table 5.1)."""
    return [r * r / 2, (3 * r * r + h * h) / 12, (3 * r * r + h * h) / 12]


MASS_CASES = {
    # node, volume, I / m (any order), centre of mass (given frame), symmetry axis or None
    "cylinder": (CappedCylinder(radius=R, half_height=HH), np.pi * R * R * 2 * HH,
                 cylinder_gyration(R, 2 * HH), (0, 0, 0), (0, 1, 0)),
    "turned_cylinder": (Rotate(CappedCylinder(radius=R, half_height=HH), degrees=TURN),
                        np.pi * R * R * 2 * HH, cylinder_gyration(R, 2 * HH), (0, 0, 0),
                        rotation_matrix(TURN) @ (0, 1, 0)),
    # A cone's centre of mass is h/4 above its base; about it I_axis = 3/10 m r^2 and
    # I_across = m (3/20 r^2 + 3/80 h^2).
    "cone": (Cone(radius=CR, height=CH), np.pi * CR * CR * CH / 3,
             [0.3 * CR ** 2, 0.15 * CR ** 2 + 3 / 80 * CH ** 2,
              0.15 * CR ** 2 + 3 / 80 * CH ** 2], (0, CH / 4, 0), (0, 1, 0)),
    "moved_turned_cone": (Translate(Rotate(Cone(radius=CR, height=CH), degrees=TURN),
                                    offset=(0.1, -0.2, 0.05)),
                          np.pi * CR * CR * CH / 3,
                          [0.3 * CR ** 2, 0.15 * CR ** 2 + 3 / 80 * CH ** 2,
                           0.15 * CR ** 2 + 3 / 80 * CH ** 2],
                          rotation_matrix(TURN) @ (0, CH / 4, 0) + (0.1, -0.2, 0.05),
                          rotation_matrix(TURN) @ (0, 1, 0)),
    "turned_box": (Rotate(Box(half_size=(A, B, C)), degrees=TURN), 8 * A * B * C,
                   [(B * B + C * C) / 3, (A * A + C * C) / 3, (A * A + B * B) / 3], (0, 0, 0),
                   None),
    # A regular hexagon of apothem a: area 2 sqrt 3 a^2, second moments of area per unit
    # area 5 a^2 / 18 about each in-plane axis and 5 a^2 / 9 about its centre.
    "hex_prism": (HexPrism(apothem=HA, half_length=HL), 2 * np.sqrt(3) * HA * HA * 2 * HL,
                  [5 * HA * HA / 9, 5 * HA * HA / 18 + HL * HL / 3,
                   5 * HA * HA / 18 + HL * HL / 3], (0, 0, 0), (0, 0, 1)),
}


@pytest.mark.parametrize("case", MASS_CASES)
def test_grid_mass_properties_match_closed_forms_within_0_5_percent(case):
    """Volume within 2e-3 relative (measured at most 4.0e-4, the cones), principal I/m within
    5e-3 relative (measured at most 1.2e-3, the cones; 1e-5 for the box, whose faces the
    second pass's grid follows), centre of mass within 1e-4 m (measured at most 3.3e-5 m,
    the cones): 96 cells across the solid's box, partial-cell weights making it second
    order."""
    node, volume, gyration, centre, _ = MASS_CASES[case]
    solid = solid_of(node)
    assert solid.volume == pytest.approx(volume, rel=2e-3)
    np.testing.assert_allclose(solid.gyration, np.sort(gyration), rtol=5e-3)
    assert np.all(np.diff(solid.gyration) >= 0)                     # ascending
    np.testing.assert_allclose(solid.centroid, centre, rtol=0, atol=1e-4)


@pytest.mark.parametrize("case", [name for name, value in MASS_CASES.items()
                                  if value[4] is not None])
def test_the_symmetry_axis_is_the_principal_axis_of_the_odd_moment_within_1e_5_rad(case):
    """A solid of revolution (or a hexagonal prism) has its symmetry axis as the principal
    axis whose moment differs from the other two: the smallest for the long cylinder, the
    largest for the flat cone and the prism. Within 1e-5 rad (measured at most 1.5e-6 rad,
    the turned cylinder)."""
    node, _, gyration, _, axis = MASS_CASES[case]
    solid = solid_of(node)
    odd = 0 if gyration[0] < gyration[1] else 2
    cosine = abs(solid.axes[:, odd] @ np.asarray(axis, float))
    assert np.arccos(min(cosine, 1.0)) < 1e-5
    np.testing.assert_allclose(solid.axes.T @ solid.axes, np.eye(3), atol=1e-12)
    assert np.linalg.det(solid.axes) == pytest.approx(1.0, abs=1e-12)


def test_a_turned_boxs_principal_axes_are_its_turned_edges_up_to_sign_within_3e_5():
    """Half sizes 0.3 > 0.2 > 0.1: moments ascending along its x, y, z, so the own axes are
    the columns of R (Euler 30, -50, 70), each up to sign; measured 6.5e-6."""
    solid = solid_of(Rotate(Box(half_size=(A, B, C)), degrees=TURN))
    np.testing.assert_allclose(np.abs(solid.axes.T @ rotation_matrix(TURN)), np.eye(3),
                               rtol=0, atol=3e-5)


def test_surface_samples_lie_on_the_surface_and_include_a_boxs_corners():
    """Every sample has |d| below 1e-9 m (projected to 1e-10 of the size), and each of a
    box's 8 corners, where it first meets a floor, is a sample to 1e-9 m."""
    solid = solid_of(Rotate(Box(half_size=(A, B, C)), degrees=TURN))
    assert np.abs(solid.distance(solid.samples)).max() < 1e-9
    corners = np.array([[i * A, j * B, k * C] for i in (-1, 1) for j in (-1, 1)
                        for k in (-1, 1)]) @ rotation_matrix(TURN).T
    own = (corners - solid.centroid) @ solid.axes
    apart = np.linalg.norm(own[:, None, :] - solid.samples[None, :, :], axis=2).min(axis=1)
    assert apart.max() < 1e-9
    assert solid.radius >= np.linalg.norm(own, axis=1).max()


# --- support points ----------------------------------------------------------------------------

def random_directions(count, seed):
    u = np.random.default_rng(seed).normal(size=(count, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def box_support_value(u):
    """max over the 8 corners of u . corner, of the box of half sizes (A, B, C) turned by TURN."""
    corners = np.array([[i * A, j * B, k * C] for i in (-1, 1) for j in (-1, 1)
                        for k in (-1, 1)]) @ rotation_matrix(TURN).T
    return (u @ corners.T).max(axis=1)


def cylinder_support_value(u):
    """max of u . p over the cylinder of radius R and half height HH along y:
    R sqrt(ux^2 + uz^2) + HH |uy|."""
    return R * np.hypot(u[:, 0], u[:, 2]) + HH * np.abs(u[:, 1])


SUPPORT_CASES = {"turned_box": (Rotate(Box(half_size=(A, B, C)), degrees=TURN),
                                box_support_value),
                 "cylinder": (CappedCylinder(radius=R, half_height=HH), cylinder_support_value)}


def near_face_normals(solid_node_case):
    """Directions a few milliradians off a face's normal (or, for the box, an edge's
    normal): where `support` has the farthest to travel across a flat face."""
    if solid_node_case == "turned_box":
        own = np.array([[0.002, 1.0, 0.002], [-0.003, 0.001, 1.0], [1.0, 0.002, -0.001],
                        [0.0015, 0.7, 0.7]])
        own = own @ rotation_matrix(TURN).T
    else:
        own = np.array([[0.003, 1.0, 0.0], [0.0, -1.0, 0.002], [0.002, 1.0, 0.002]])
    return own / np.linalg.norm(own, axis=1, keepdims=True)


@pytest.mark.parametrize("case", SUPPORT_CASES)
def test_support_value_along_any_direction_is_exact_within_1e_6_of_the_size(case):
    """u . support(u) equals the solid's exact support value max over the solid of u . p
    (the turned box: its best corner; the cylinder: R sqrt(ux^2 + uz^2) + HH |uy|) within
    1e-6 of the bounding radius, for 2000 seeded random directions and a few just off a
    face's normal, and is never below the best surface sample by more than that. Measured:
    1.3e-9 m short at worst (box; cylinder 3.2e-10). (With a fixed reach per move, 0.4% of
    the directions had fallen short by up to 2.1e-4 m.)"""
    node, exact = SUPPORT_CASES[case]
    solid = solid_of(node)
    u = np.concatenate([random_directions(2000, seed=3), near_face_normals(case)])
    own_u = u @ solid.axes
    point = solid.centroid + support(solid, own_u) @ solid.axes.T
    reached = np.sum(u * point, axis=1)
    best_sample = (solid.samples @ own_u.T).max(axis=0) + solid.centroid @ u.T
    assert np.abs(reached - exact(u)).max() <= 1e-6 * solid.radius
    assert np.all(reached >= best_sample - 1e-6 * solid.radius)


@pytest.mark.parametrize("case", SUPPORT_CASES)
def test_support_value_away_from_flat_features_is_exact_within_1e_8_m(case):
    """Directions whose components along the box's edges (the cylinder's axis and its
    side's directions) are all at least 0.05 in size, where one or two moves of `support`
    cross any face: the support value is exact within 1e-8 m (measured 1.4e-9 m short at
    worst, what stopping once a move is below 1e-6 of the radius leaves) and its point lies
    on the surface (|d| < 1e-9 m; measured 4e-11 m)."""
    node, exact = SUPPORT_CASES[case]
    solid = solid_of(node)
    u = random_directions(4000, seed=4)
    frame = rotation_matrix(TURN) if case == "turned_box" else np.eye(3)
    local = u @ frame
    keep = np.abs(local).min(axis=1) >= 0.05
    if case == "cylinder":
        keep = (np.abs(local[:, 1]) >= 0.05) & (np.hypot(local[:, 0], local[:, 2]) >= 0.05)
    u = u[keep]
    assert len(u) > 2500
    own = support(solid, u @ solid.axes)
    reached = np.sum(u * (solid.centroid + own @ solid.axes.T), axis=1)
    np.testing.assert_allclose(reached, exact(u), rtol=0, atol=1e-8)
    assert np.abs(solid.distance(own)).max() < 1e-9


def test_support_across_a_cylinders_axis_lies_on_its_side_at_exactly_its_radius():
    """What a rolling cylinder's contact needs: along directions at right angles to its
    axis the support point is at distance R from the axis and u . p = R (1e-9 m)."""
    solid = solid_of(CappedCylinder(radius=R, half_height=HH))
    angle = np.linspace(0, 2 * np.pi, 37)
    u = np.stack([np.cos(angle), np.zeros_like(angle), np.sin(angle)], axis=1)
    p = solid.centroid + support(solid, u @ solid.axes) @ solid.axes.T
    np.testing.assert_allclose(np.sum(u * p, axis=1), R, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 2]), R, rtol=0, atol=1e-9)


# --- rolling down an incline -------------------------------------------------------------------

SLOPE = np.radians(30)
UP_NORMAL = np.array([-np.sin(SLOPE), np.cos(SLOPE), 0.0])     # the incline's normal
DOWNHILL = np.array([-np.cos(SLOPE), -np.sin(SLOPE), 0.0])


def incline_world(friction=0.5):
    world = physics.World(gravity=(0, -G, 0))
    world.add_plane(UP_NORMAL, 0.0, restitution=0.0, friction=friction)
    return world


def fitted_acceleration(positions, dt):
    """The acceleration down the slope of the least-squares parabola through the positions
    (S, 3) recorded every step."""
    t = np.arange(len(positions)) * dt
    s = (positions - positions[0]) @ DOWNHILL
    return 2 * np.polyfit(t, s, 2)[0]


def test_a_cylinder_rolls_down_a_30_degree_incline_at_two_thirds_g_sin_within_1e_3():
    """Lying across the slope (axis along z), mu = 0.5 > tan 30 / 3, e = 0, released at rest
    touching: it rolls without slipping at a = g sin 30 / (1 + I/(m r^2)) = 2/3 g sin 30 =
    3.27 m/s^2 (fit over 0.5 s; within 1e-3 relative: measured 1.2e-4, what the grid's
    3.7e-4 error in I / m makes of a, 1/3 of it). The contact point does not slide (its
    speed below 1e-6 m/s; measured 4e-9) and the lowest point of the cylinder (exact, from
    its axis) stays within the slop of the plane (measured: -6e-11 m to +3e-12 m)."""
    solid = solid_of(CappedCylinder(radius=R, half_height=HH))
    world = incline_world()
    add_placed(world, solid, R * UP_NORMAL, (90.0, 0.0, 0.0), restitution=0.0, friction=0.5)
    positions, gaps, slips = [world.position[0].copy()], [], []
    for _ in range(120):
        world.step()
        positions.append(world.position[0].copy())
        along = cylinder_axis(world, 0, solid) @ UP_NORMAL
        gaps.append(world.position[0] @ UP_NORMAL - R * np.sqrt(1 - along ** 2)
                    - HH * abs(along))
        contact = world.velocity[0] + np.cross(world.angular_velocity[0], -R * UP_NORMAL)
        slips.append(np.linalg.norm(contact))
    expected = 2 / 3 * G * np.sin(SLOPE)
    assert fitted_acceleration(np.array(positions), world.dt) == pytest.approx(expected,
                                                                               rel=1e-3)
    assert max(slips) < 1e-6
    assert min(gaps) >= -SLOP and max(gaps) <= SLOP
    assert world.kind[0] == CONVEX


def test_a_convex_sphere_rolls_at_five_sevenths_g_sin_like_add_sphere_within_1e_3():
    """A Sphere node as a convex body: a = g sin 30 / (1 + 2/5) = 5/7 g sin 30 (fit over
    0.5 s), as `add_sphere`'s ball (which gets it to 1e-15); within 1e-3 relative (measured
    2.1e-4, from the grid's 7.5e-4 error in I / m, times 2/7)."""
    solid = solid_of(Sphere(radius=R))
    world = incline_world()
    add_placed(world, solid, R * UP_NORMAL, restitution=0.0, friction=0.5)
    world.add_sphere(R * UP_NORMAL + (0, 0, 1.0), radius=R, restitution=0.0, friction=0.5)
    positions = [world.position.copy()]
    for _ in range(120):
        world.step()
        positions.append(world.position.copy())
    positions = np.array(positions)
    expected = 5 / 7 * G * np.sin(SLOPE)
    convex = fitted_acceleration(positions[:, 0], world.dt)
    ball = fitted_acceleration(positions[:, 1], world.dt)
    assert ball == pytest.approx(expected, rel=1e-9)
    assert convex == pytest.approx(expected, rel=1e-3)
    assert np.abs((positions[:, 0] - positions[0, 0]) @ UP_NORMAL).max() <= SLOP


# --- standing still ----------------------------------------------------------------------------

def floor_world(restitution=0.0, friction=0.5):
    world = physics.World(gravity=(0, -G, 0))
    world.add_plane((0, 1, 0), 0.0, restitution=restitution, friction=friction)
    return world


def test_a_cone_standing_on_its_base_stays_put_within_1e_8_m_for_1_s():
    """Base on the floor, apex up, e = 0: it stands on the ring of its rim (the contact
    patch's tilted support points); no point moves more than 1e-8 m nor turns more than
    1e-8 in 1 s (measured 2.4e-10 m)."""
    solid = solid_of(Cone(radius=CR, height=CH))
    world = floor_world()
    add_placed(world, solid, (0.0, 0.0, 0.0), restitution=0.0, friction=0.5)
    start, turn = world.position.copy(), world.orientation.copy()
    drift = 0.0
    for _ in range(240):
        world.step()
        drift = max(drift, np.abs(world.position - start).max())
    assert drift < 1e-8
    assert np.abs(world.orientation - turn).max() < 1e-8
    assert world.position[0, 1] == pytest.approx(CH / 4, abs=1e-4)   # base on the floor


def test_a_cylinder_standing_on_another_cylinder_cap_on_cap_stands_within_3e_5_m_for_1_s():
    """Two equal upright cylinders (r 0.15, height 0.4) stacked on the floor, e = 0: the
    convex-convex patch holds the top one up on its rim; neither moves more than 3e-5 m nor
    turns more than 3e-5 in 1 s (measured 4.4e-6 m and 1.3e-6, the contacts settling into
    the slop in the first 0.25 s), once settled (after 0.5 s) neither moves more than 1e-6 m
    (measured below 1e-8 m, also over 3 s), and the top one never sinks into the lower by
    more than the slop (measured 6e-7 m)."""
    solid = solid_of(CappedCylinder(radius=0.15, half_height=0.2))
    world = floor_world()
    for y in (0.2, 0.6):
        add_placed(world, solid, (0.0, y, 0.0), restitution=0.0, friction=0.5)
    start, turn = world.position.copy(), world.orientation.copy()
    drift, sink = 0.0, 0.0
    for step in range(240):
        world.step()
        drift = max(drift, np.abs(world.position - start).max())
        sink = max(sink, (world.position[0, 1] + 0.2) - (world.position[1, 1] - 0.2))
        if step == 119:
            settled = world.position.copy()
    assert drift < 3e-5
    assert np.abs(world.position - settled).max() < 1e-6
    assert np.abs(world.orientation - turn).max() < 3e-5
    assert sink <= SLOP


# --- free flight -------------------------------------------------------------------------------

BOX_SPIN = (1.0, 4.0, -2.0)                      # rad/s, about no principal axis
BOX_TURN = quaternion_from_rotation_vector(np.array([[0.3, -0.2, 0.5]]))[0]


def tumbling(add):
    """A world without gravity holding one 2 kg body added by ``add(world)``, spun BOX_SPIN."""
    world = physics.World(gravity=(0, 0, 0))
    add(world)
    return world


def convex_box(solid):
    return lambda world: world.add_convex((0, 0, 0), solid, BOX_TURN, angular_velocity=BOX_SPIN,
                                          mass=2.0)


def plain_box(world):
    world.add_box((0, 0, 0), (A, B, C), BOX_TURN, angular_velocity=BOX_SPIN, mass=2.0)


def test_a_tumbling_convex_box_keeps_its_angular_momentum_to_1e_12_and_energy_to_1e_5():
    """Torque-free for 1 s: L to 1e-12 relative (measured 5e-14; the splitting turns L's
    body-frame image, never L), the energy within 1e-5 relative (measured 3.6e-6: the
    splitting's O((h w)^2) error, oscillating)."""
    world = tumbling(convex_box(solid_of(Box(half_size=(A, B, C)))))
    momentum, energy = world.angular_momentum(), world.energy()
    for _ in range(240):
        world.step()
        np.testing.assert_allclose(world.angular_momentum(), momentum, rtol=0,
                                   atol=1e-12 * np.linalg.norm(momentum))
        assert abs(world.energy() - energy) <= 1e-5 * energy


def test_a_convex_box_tumbles_step_for_step_like_add_box():
    """The Box node's solid has its own axes along the box's edges (its moments ascend along
    x, y, z), and the integration's second pass, over a grid along those axes, makes its
    I / m the closed form's within 1e-9 relative (measured 5e-13). So the convex body and
    `add_box`'s follow the same orientations and spins over 1 s within 1e-9 (measured 4e-13
    in R, 1.5e-12 rad/s in w, |w| = 4.4 rad/s); and bit for bit with the closed-form I / m
    put in place of the grid's (the step sees nothing else of a body in free flight)."""
    solid = solid_of(Box(half_size=(A, B, C)))
    np.testing.assert_allclose(np.abs(solid.axes), np.eye(3), atol=1e-9)
    exact = np.array([(B * B + C * C) / 3, (A * A + C * C) / 3, (A * A + B * B) / 3])
    np.testing.assert_allclose(solid.gyration, exact, rtol=1e-9)
    reference = tumbling(plain_box)
    same = tumbling(convex_box(dataclasses.replace(solid, gyration=exact)))
    grid = tumbling(convex_box(solid))
    apart_turn = apart_spin = 0.0
    for _ in range(240):
        for world in (reference, same, grid):
            world.step()
        np.testing.assert_array_equal(same.orientation, reference.orientation)
        np.testing.assert_array_equal(same.angular_velocity, reference.angular_velocity)
        turns = rotation_matrices(np.concatenate([grid.orientation, reference.orientation]))
        apart_turn = max(apart_turn, np.abs(turns[0] - turns[1]).max())
        apart_spin = max(apart_spin, np.abs(grid.angular_velocity - reference.angular_velocity)
                         .max())
    assert apart_turn < 1e-9 and apart_spin < 1e-9


# --- landing -----------------------------------------------------------------------------------

def test_a_tumbling_hex_prism_lands_without_gaining_energy_and_rests_on_a_face():
    """Dropped from 0.6 m turned (20, 10, 0) degrees and spinning at 3 rad/s, e = 0.5,
    mu = 0.5: the energy (kinetic + rotational + potential) never rises above the start and
    rises in no step by more than m g times the slop, 9.8e-4 J for 1 kg (what the push-out of
    a contact within the slop may lift it by; measured at most 2.6e-4 J, in a few steps
    while it settles, 1.0 to 1.1 s); after 1.5 s it is at rest (kinetic energy below 1e-10
    J; measured 2e-22 J, still from 1.25 s), no corner lower than -slop (measured down to
    -6e-5 m during the landing, then -3e-9 m) and it lies on one of its side faces: at
    least 4 of its 12 corners within 2e-4 m of the floor."""
    solid = solid_of(HexPrism(apothem=HA, half_length=HL))
    world = floor_world(restitution=0.5)
    add_placed(world, solid, (0.0, 0.6, 0.0), (20.0, 10.0, 0.0), angular_velocity=(0, 0, 3.0),
               restitution=0.5, friction=0.5, mass=1.0)
    corners = hex_corners(HA, HL)
    energy = [world.energy()]
    lowest = np.inf
    for _ in range(360):
        world.step()
        energy.append(world.energy())
        lowest = min(lowest, given_to_world(world, 0, solid, corners)[:, 1].min())
    energy = np.array(energy)
    assert energy.max() <= energy[0]
    assert np.diff(energy).max() <= 1.0 * G * SLOP
    assert world.kinetic_energy() < 1e-10
    heights = given_to_world(world, 0, solid, corners)[:, 1]
    assert lowest >= -SLOP
    assert np.sum(heights < 2e-4) >= 4
    assert world.events["kind"][0] == "convex-plane"


# --- a thin wall: continuous collision ---------------------------------------------------------

WALL = 1.0               # the wall's centre (m): a 1 cm slab, its near face at x = 0.995


def thrown_at_a_wall(node, degrees, spin, restitution):
    """A 1 cm static wall (an exact box SDF shape) and ``node``'s solid at the origin thrown
    along +x at 50 m/s (21 cm a step at dt = 1/240 s, 21 times the wall's thickness), no
    gravity."""
    world = physics.World(gravity=(0, 0, 0))
    world.add_shape(box_shape((WALL, 0, 0), (0.005, 1, 1), restitution=restitution))
    solid = solid_of(node)
    add_placed(world, solid, (0.0, 0.0, 0.0), degrees, velocity=(50.0, 0, 0),
               angular_velocity=spin, restitution=restitution)
    return world, solid


def farthest_x(world, solid, node):
    """The exact largest x of the body now: a cylinder's from its axis, a prism's corner."""
    if isinstance(node, CappedCylinder):
        axis = cylinder_axis(world, 0, solid)
        return world.position[0, 0] + node.radius * np.sqrt(1 - axis[0] ** 2) + \
            node.half_height * abs(axis[0])
    corners = hex_corners(node.apothem, node.half_length)
    return given_to_world(world, 0, solid, corners)[:, 0].max()


THROWN = {"cylinder": (CappedCylinder(radius=0.1, half_height=0.15), (90.0, 0.0, 0.0),
                       (0.0, 0.0, 0.0)),
          "hex_prism": (HexPrism(apothem=0.1, half_length=0.15), (0.0, 0.0, 0.0),
                        (0.0, 0.0, 0.0)),
          "spinning_hex_prism": (HexPrism(apothem=0.1, half_length=0.15), (20.0, 10.0, 0.0),
                                 (3.0, 20.0, -10.0))}

@pytest.mark.parametrize("case, restitution", [
    ("cylinder", 0.0), ("cylinder", 1.0), ("hex_prism", 0.0), ("hex_prism", 1.0),
    ("spinning_hex_prism", 0.0), ("spinning_hex_prism", 1.0)])
def test_a_convex_body_thrown_at_50_m_s_never_passes_into_a_1_cm_wall(case, restitution):
    """At every step of 0.1 s its farthest point (exact) is at most the slop past the wall's
    near face (measured 3e-12 m or less past it without spin; the spinning prism 5.2e-5 m
    past it with e = 0, stopped at the wall and turning a corner into it, which the swept
    test looks for at 8 times a step, and 2.6e-3 m short of it with e = 1), and it ends on
    the near side. Without spin: e = 1, it leaves at -50 m/s
    (1e-6 relative) after one impact event; e = 0, it stops at the wall (1e-6 m/s)."""
    node, degrees, spin = THROWN[case]
    world, solid = thrown_at_a_wall(node, degrees, spin, restitution)
    farthest = -np.inf
    for _ in range(24):
        world.step()
        farthest = max(farthest, farthest_x(world, solid, node))
    assert farthest <= WALL - 0.005 + SLOP
    assert world.position[0, 0] < WALL - 0.005
    assert world.events["kind"][0] == "convex-shape"
    if case != "spinning_hex_prism":
        if restitution == 1.0:
            assert world.velocity[0, 0] == pytest.approx(-50.0, rel=1e-6)
            assert len(world.events) == 1
        else:
            assert abs(world.velocity[0, 0]) < 1e-6


# --- a ball on a convex body -------------------------------------------------------------------

@pytest.mark.parametrize("restitution", [0.5, 1.0])
def test_a_ball_dropped_on_a_standing_cylinder_bounces_as_off_a_box_and_never_enters_it(
        restitution):
    """A 0.5 kg ball (r 0.1) dropped 0.5 m onto the flat top of a 3 kg cylinder (r 0.2,
    height 0.4) standing on the floor (e = 0 for the cylinder and the floor): the sphere-
    convex contact is exact (the ball's centre in the solid's SDF), so the ball's centre is
    never nearer the cylinder's exact surface than r - slop (measured: r + 5e-5 m), and its
    vertical speed at every step equals that of a ball dropped on a box of the same top and
    mass within 1e-6 m/s (measured 9e-10): the rebound (0.43 and 0.86 of the impact speed
    here, the sequential solver's answer with the cylinder pressed into the floor) included.
    """
    solid = solid_of(CappedCylinder(radius=0.2, half_height=0.2))
    worlds = []
    for kind in ("convex", "box"):
        world = floor_world()
        if kind == "convex":
            add_placed(world, solid, (0.0, 0.2, 0.0), restitution=0.0, mass=3.0)
        else:
            world.add_box((0.0, 0.2, 0.0), (0.2, 0.2, 0.2), restitution=0.0, mass=3.0)
        world.add_sphere((0.0, 1.0, 0.0), radius=0.1, restitution=restitution, mass=0.5)
        worlds.append(world)
    convex, box = worlds
    nearest, speeds = np.inf, []
    for _ in range(100):
        convex.step()
        box.step()
        centre = world_to_given(convex, 0, solid, convex.position[1:2])
        nearest = min(nearest, sdf_capped_cylinder(centre, 0.2, 0.2)[0])
        speeds.append((convex.velocity[1, 1], box.velocity[1, 1]))
    speeds = np.array(speeds)
    assert nearest >= 0.1 - SLOP
    np.testing.assert_allclose(speeds[:, 0], speeds[:, 1], rtol=0, atol=1e-6)
    assert speeds[:, 0].max() > 0.4 * restitution * np.sqrt(2 * G * 0.5)     # it bounced
    assert "sphere-convex" in set(convex.events["kind"])
