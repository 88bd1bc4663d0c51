"""Boxes and capsules in scenes: ``shape``, ``half_size``, ``half_length`` and ``rotation`` of a
``[[bodies]]`` entry, the world built from them, the bundled `stack` scene, and the renderers
drawing each body at its simulated pose (scene_model/bodies.py, marchlab/simulation.py).

Every check is against a closed form: the masses from the volumes, the orientation from the
scene's Euler angles, the exact box and capsule SDFs at the pixels the renderer says it hit.
Sizes are tiny and runs short; the one 2 s simulation of `stack` is shared (module fixture).
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

import marchlab
import physics
from marchlab.cli import main
from marchlab.simulation import body_rotations, build_world, simulate
from physics.quaternions import rotation_matrices
from physics.solids import box_distance, segment_closest
from scene_model.builder import Body, Camera, Material, PhysicsSettings, Scene, plane
from scene_model.geometry import quaternion_from_matrix, rotation_matrix
from scene_model.scene import rendered_scene, scene_at
from scene_model.shapes import Box, Capsule, primitives
from scene_model.scenefile import load_scene

from cli_helpers import assert_one_line_error, run_cli

SOLIDS = """\
[physics]
density = 900.0

[materials.default]

[[objects]]
type = "plane"

[[bodies]]
shape = "box"
position = [-1.0, 1.0, 0.0]
half_size = [0.3, 0.2, 0.1]
rotation = [30.0, -50.0, 70.0]
density = 700.0

[[bodies]]
shape = "capsule"
position = [1.0, 1.0, 0.0]
half_length = 0.4
radius = 0.15
rotation = [-20.0, 80.0, 10.0]
"""


@pytest.fixture
def solids_file(tmp_path):
    path = tmp_path / "solids.toml"
    path.write_text(SOLIDS)
    return path


# --- The scene file and the world ----------------------------------------------------------------

def test_box_and_capsule_bodies_build_with_their_sizes_masses_and_turns_to_1e_12(solids_file):
    """Box: m = 8 a b c rho (its own density, 700); capsule: m = rho (pi r^2 2l + 4/3 pi r^3)
    ([physics] density, 900); each orientation's matrix is R = Rz Ry Rx of its rotation."""
    scene = load_scene(solids_file)
    world = build_world(scene)
    assert world.kind.tolist() == [1, 2]
    np.testing.assert_array_equal(world.extent, [[0.3, 0.2, 0.1], [0.0, 0.4, 0.0]])
    assert world.radius[1] == 0.15
    assert world.radius[0] == pytest.approx(math.sqrt(0.3**2 + 0.2**2 + 0.1**2), rel=1e-12)
    box_mass = 8 * 0.3 * 0.2 * 0.1 * 700.0
    capsule_mass = 900.0 * (math.pi * 0.15**2 * 2 * 0.4 + 4 / 3 * math.pi * 0.15**3)
    np.testing.assert_allclose(world.mass, [box_mass, capsule_mass], rtol=1e-12)
    for body, turned in zip(scene.bodies, rotation_matrices(world.orientation)):
        np.testing.assert_allclose(turned, rotation_matrix(body.rotation), rtol=0, atol=1e-12)


BAD_SOLIDS = [
    ("bodies[0].shape=cube", "bodies[0].shape: must be one of 'sphere', 'box', 'capsule'"),
    ("bodies[0].half_size=[0.3, -0.2, 0.1]", "bodies[0].half_size[1]: must be positive"),
    ("bodies[1].half_length=0", "bodies[1].half_length: must be positive"),
]


@pytest.mark.parametrize("assignment, message", BAD_SOLIDS, ids=["cube", "negative_half_size",
                                                                  "zero_half_length"])
def test_a_bad_solid_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, solids_file,
                                                           assignment, message):
    before = sorted(tmp_path.iterdir())
    code, _, stderr = run_cli(capsys, "simulate", solids_file, "--set", assignment,
                              "-o", tmp_path / "out.gif", "--csv", tmp_path / "out.csv",
                              "--size", "16x12")
    assert_one_line_error(code, stderr)
    assert f"{solids_file}: {message}" in stderr, stderr
    assert sorted(tmp_path.iterdir()) == before


# --- The bundled stack ---------------------------------------------------------------------------

STACK_FPS = 30
STACK_SECONDS = 2.0


@pytest.fixture(scope="module")
def stack_rows(tmp_path_factory):
    """The CSV of `marchlab simulate stack` over 2 s at 30 frames per second (61 records, at
    t = 0, 1/30, ..., 2 s), rendered at 16x12 by the numpy backend: the header and the rows."""
    folder = tmp_path_factory.mktemp("stack")
    table = folder / "stack.csv"
    code = main(["simulate", "stack", "--seconds", str(STACK_SECONDS + 1 / STACK_FPS),
                 "--fps", str(STACK_FPS), "--size", "16x12", "--backend", "numpy",
                 "-o", str(folder / "stack.gif"), "--csv", str(table)])
    assert code == 0
    with open(table, newline="") as handle:
        reader = csv.DictReader(handle)
        return reader.fieldnames, list(reader)


def test_stack_csv_has_the_pose_columns_and_one_row_per_body_per_record(stack_rows):
    header, rows = stack_rows
    scene = marchlab.load_scene("stack")
    assert [body.shape for body in scene.bodies] == ["box"] * 5 + ["capsule", "sphere"]
    assert header == ["time", "body", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz",
                      "qw", "qx", "qy", "qz", "active"]
    quaternions = np.array([[float(row[k]) for k in ("qw", "qx", "qy", "qz")] for row in rows])
    np.testing.assert_allclose(np.linalg.norm(quaternions, axis=1), 1.0, atol=1e-12)
    records = round(STACK_SECONDS * STACK_FPS) + 1
    assert len(rows) == records * len(scene.bodies)
    assert [int(row["body"]) for row in rows] == list(range(len(scene.bodies))) * records
    times = np.array([float(row["time"]) for row in rows]).reshape(records, -1)
    np.testing.assert_allclose(times[:, 0], np.arange(records) / STACK_FPS, atol=1e-12)
    assert (times == times[:, :1]).all()


def test_stack_stands_every_box_within_2e_4_m_of_where_it_was_built_for_2_s(stack_rows):
    """Every body starts exactly touching what holds it, so all that may move is the contacts
    settling into the solver's slop (1e-4 m per contact). Measured: the boxes sway by at most
    1.2e-4 m in the first 0.1 s (the top box; sampled at 30 fps, 1.0e-4 m) and are then still
    to 1e-7 m, their speeds below 1e-7 m/s at 2 s. The capsule and the ball lie on the floor
    and do not move at all (1e-16 m); 1e-6 m leaves room for rounding."""
    _, rows = stack_rows
    scene = marchlab.load_scene("stack")
    bodies = len(scene.bodies)
    table = np.array([[float(row[key]) for key in ("x", "y", "z", "vx", "vy", "vz")]
                      for row in rows]).reshape(-1, bodies, 6)
    built = np.array([body.position for body in scene.bodies])
    drift = np.abs(table[:, :, :3] - built).max(axis=(0, 2))
    assert drift[:5].max() < 2e-4, drift
    assert drift[5:].max() < 1e-6, drift
    assert np.abs(table[-1, :, 3:]).max() < 1e-6
    assert all(row["active"] == "1" for row in rows)


# --- Drawn where the physics has it --------------------------------------------------------------

# Render epsilon 1e-3 (the default): sphere tracing stops within it of a surface and never
# passes through it, so every hit point is 0 to 1e-3 m outside the surface it hit.
EPSILON = 1e-3
SIZE = (64, 48)


@pytest.fixture(scope="module")
def tumbled():
    """A box and a capsule thrown spinning (no contact yet after 0.3 s of free flight), the
    scene posed at their simulated positions and orientations, and the world."""
    scene = Scene(camera=Camera(position=(0.0, 1.0, 3.5), look_at=(0.0, 0.8, 0.0), fov=40.0),
                  materials={"default": Material()}, objects=(plane(),),
                  physics=PhysicsSettings(restitution=0.0),
                  bodies=(Body(shape="box", position=(-0.5, 1.2, 0.0),
                               half_size=(0.3, 0.2, 0.12), rotation=(25.0, -40.0, 60.0),
                               angular_velocity=(4.0, -6.0, 9.0)),
                          Body(shape="capsule", position=(0.5, 1.2, 0.0), half_length=0.3,
                               radius=0.12, rotation=(-30.0, 20.0, 70.0),
                               angular_velocity=(-5.0, 7.0, 3.0))))
    world = build_world(scene)
    physics.simulate(world, 0.3)
    posed = scene_at(scene, world.position, rotations=body_rotations(world.orientation))
    return scene, posed, world


def hit_points(scene: Scene, kind):
    """The hit points (K, 3) of the pixels whose object is the scene's one primitive of
    ``kind``, in the NumPy reference renderer at `SIZE`."""
    frame = marchlab.render(scene, *SIZE, backend="numpy")
    ids = [index for index, node in enumerate(primitives(rendered_scene(scene).objects))
           if isinstance(node, kind)]
    assert len(ids) == 1
    mine = frame.hit & (frame.object_id == ids[0])
    origin, directions = marchlab.camera_rays(scene.camera, *SIZE)
    return origin + frame.depth[mine][:, None] * directions[mine]


def test_the_tumbled_bodies_turned_far_from_their_start(tumbled):
    """Otherwise the pose checks below would also pass with the scene's initial rotation."""
    scene, _, world = tumbled
    for body, now in zip(scene.bodies, rotation_matrices(world.orientation)):
        cos = (np.trace(rotation_matrix(body.rotation).T @ now) - 1) / 2
        assert math.degrees(math.acos(np.clip(cos, -1, 1))) > 60
    assert world.position[:, 1].min() < 1.0                      # and they fell


def test_the_box_is_drawn_at_its_simulated_pose_within_the_render_epsilon(tumbled):
    """Every pixel the renderer says is the box has its hit point on the exact SDF of the box
    at the physics pose (x, R(q)), evaluated at R^T (p - x): 0 <= d <= 1e-3 (+1e-9 for
    rounding). The same points against the box at its scene's initial turn are centimetres
    off, so the check tells the poses apart."""
    scene, posed, world = tumbled
    points = hit_points(posed, Box)
    assert len(points) > 50                          # the box covers about 3% of 64 x 48
    half = np.tile(world.extent[0], (len(points), 1))
    local = (points - world.position[0]) @ rotation_matrices(world.orientation)[0]
    distance, _ = box_distance(local, half)
    assert distance.min() >= -1e-9 and distance.max() <= EPSILON + 1e-9
    start = (points - world.position[0]) @ rotation_matrix(scene.bodies[0].rotation)
    assert np.abs(box_distance(start, half)[0]).max() > 1e-2


def test_the_capsule_is_drawn_at_its_simulated_pose_within_the_render_epsilon(tumbled):
    """The same for the capsule: distance to its segment (x +- l R(q) e_y) minus r."""
    scene, posed, world = tumbled
    points = hit_points(posed, Capsule)
    assert len(points) > 30
    axis = rotation_matrices(world.orientation)[1][:, 1] * world.extent[1, 1]
    start = np.tile(world.position[1] - axis, (len(points), 1))
    end = np.tile(world.position[1] + axis, (len(points), 1))
    t = segment_closest(start, end, points)
    nearest = start + t[:, None] * (end - start)
    distance = np.linalg.norm(points - nearest, axis=1) - world.radius[1]
    assert distance.min() >= -1e-9 and distance.max() <= EPSILON + 1e-9


def test_body_rotations_of_random_quaternions_give_back_their_matrices_to_1e_12():
    rng = np.random.default_rng(7)
    q = rng.normal(size=(500, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    degrees = body_rotations(q)
    assert degrees.shape == (500, 3)
    back = np.array([rotation_matrix(row) for row in degrees])
    np.testing.assert_allclose(back, rotation_matrices(q), rtol=0, atol=1e-12)


def test_body_rotations_near_gimbal_lock_give_back_their_matrices_to_1e_12():
    """y = +-90 degrees and within 1e-12 to 1e-3 degrees of it, x and z random."""
    rng = np.random.default_rng(8)
    angles = [(x, sign * (90 - offset), z)
              for offset in (0, 1e-12, 1e-8, 1e-6, 1e-5, 1e-3) for sign in (1, -1)
              for x, z in rng.uniform(-180, 180, size=(10, 2))]
    q = np.array([quaternion_from_matrix(rotation_matrix(a)) for a in angles])
    back = np.array([rotation_matrix(row) for row in body_rotations(q)])
    np.testing.assert_allclose(back, rotation_matrices(q), rtol=0, atol=1e-12)


# --- The gpu step --------------------------------------------------------------------------------

def test_the_gpu_step_refuses_the_stack_in_one_line_before_making_a_gl_context(monkeypatch):
    """Even in float32 with the simultaneous solver (what the gpu step needs), a box is refused
    by `gpu_shader.physics.check_world`, before any OpenGL context is asked for: so the test
    needs no GL, and a machine without one gets the same message."""
    import gpu_shader.physics

    def no_context(*args, **kwargs):
        raise AssertionError("the refusal must come before the OpenGL context")

    monkeypatch.setattr(gpu_shader.physics, "gl_context", no_context)
    scene = marchlab.load_scene("stack", ["physics.solver=simultaneous"])
    with pytest.raises(physics.PhysicsError) as caught:
        simulate(build_world(scene, np.float32), 0.1, backend="gpu", scene=scene)
    message = str(caught.value)
    assert message == ("the gpu backend steps spheres only (body 0 is a box body): use the cpu "
                       "backend")
