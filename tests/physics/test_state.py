"""Saving and loading a running world (physics/state.py): a resumed run is the same run.

Stopping after A steps, saving, loading into a world built afresh and stepping B more must give
exactly, bit for bit, what A + B steps without stopping give: positions, velocities, spins,
orientations, the active flags, the events and the time (tolerance 0). The scene has what
makes that hard: balls that bounce, slide and roll with friction, one hitting a wall, and a
two-ball stack at rest, whose contacts the solver warm-starts from the last step's impulses.
A file from another world, or a damaged one, is refused in one line naming the file.
"""

import io
import os
import zipfile

import numpy as np
import pytest

import physics
from physics.state import VERSION, state_bytes

A, B = 150, 250          # steps before and after the save: the stack rests, balls bounce


def stepped_world(dtype=np.float64, solver="sequential", seed=0) -> physics.World:
    """Floor and wall; a two-ball stack at rest, a ball thrown up at the wall, one sliding, and
    one that leaves the bounds (|z| <= 3 m) at t = 0.84 s, between the save and the end."""
    world = physics.World(dtype=dtype, solver=solver, seed=seed,
                          bounds=((-3, -1, -3), (3, 6, 3)))
    world.add_plane((0, 1, 0), 0, friction=0.5)
    world.add_plane((1, 0, 0), -1, restitution=0.5)                   # the wall x = -1
    world.add_sphere((0, 0.1, 0), radius=0.1, friction=0.4)
    world.add_sphere((0, 0.3, 0), radius=0.1, mass=3.0)                # resting on the first
    world.add_sphere((0.8, 1, 0), velocity=(-2, 3, 0), radius=0.2, restitution=0.8)
    world.add_sphere((0.5, 0.15, 0.4), velocity=(-3, 0, 0), radius=0.15,
                     angular_velocity=(0, 5, 0), friction=0.3)         # slides, then rolls
    world.add_sphere((0, 4.5, 2.5), velocity=(0, 0, 0.6), radius=0.1)    # leaves at step 201
    return world


def resumed(dtype, solver, tmp_path, keep_warm_start=True, seed=0) -> physics.World:
    """A steps, saved, loaded into a new world, then B steps."""
    first = stepped_world(dtype, solver)
    first.step(A)
    physics.save_state(first, tmp_path / "state.npz")
    second = stepped_world(dtype, solver, seed=seed)
    physics.load_state(second, tmp_path / "state.npz")
    if not keep_warm_start:
        second._resting_impulses = None
    second.step(B)
    return second


def assert_same_run(a: physics.World, b: physics.World) -> None:
    for name in ("position", "velocity", "angular_velocity", "orientation", "active"):
        assert getattr(a, name).dtype == getattr(b, name).dtype, name
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.events, b.events)
    assert (a.steps, a.time) == (b.steps, b.time)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_resume_is_bit_identical_to_not_stopping(dtype, solver, tmp_path):
    straight = stepped_world(dtype, solver)
    straight.step(A + B)
    again = resumed(dtype, solver, tmp_path)
    assert_same_run(straight, again)
    assert again.position.dtype == dtype
    # The scene does what the docstring says, so the comparison covers it:
    kinds = set(straight.events["kind"][straight.events["step"] > A].tolist())
    assert {"sphere-plane", "left-bounds"} <= kinds and not straight.active[4]
    assert straight.position[:2, 1] == pytest.approx([0.1, 0.3], abs=1e-3)          # resting
    assert np.abs(straight.angular_velocity[3]).max() > 1                             # rolling


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("solver", list(physics.SOLVERS))
def test_resume_without_the_warm_start_is_not_bit_identical(dtype, solver, tmp_path):
    """Guard for the test above: the resting stack needs last step's impulses, so a state
    file without them would be caught. The positions differ by more than 1e-6 m, far more
    than a last bit."""
    straight = stepped_world(dtype, solver)
    straight.step(A + B)
    cold = resumed(dtype, solver, tmp_path, keep_warm_start=False)
    assert np.abs(straight.position - cold.position).max() > 1e-6


def spawn_two_at_one_point(world: physics.World) -> np.ndarray:
    """Add two balls at one free point (the second is moved off it in a random direction);
    their centres (2, 3) m."""
    added = world.add_spheres([(0.5, 1.5, -0.5)] * 2, radius=0.05)
    return world.position[added]


def test_a_sphere_spawned_after_resume_lands_where_it_would_have(tmp_path):
    """Spawning on another's centre draws a direction from the world's generator, so the
    generator's state is part of the saved state. The resumed world is built with another seed:
    only the file can make its draws those of the uninterrupted run."""
    straight = stepped_world()
    straight.step(A + B)
    again = resumed(np.float64, "sequential", tmp_path, seed=99)
    spawned = spawn_two_at_one_point(again)
    np.testing.assert_array_equal(spawn_two_at_one_point(straight), spawned)
    straight.step(50)
    again.step(50)
    assert_same_run(straight, again)
    # Guard: with the generator of its own seed, the resumed world would spawn elsewhere.
    own_seed = resumed(np.float64, "sequential", tmp_path, seed=99)
    own_seed.rng = np.random.default_rng(99)
    assert not np.array_equal(spawn_two_at_one_point(own_seed), spawned)


def test_saving_leaves_the_world_as_it_was_and_its_run_unchanged(tmp_path):
    paused, untouched = stepped_world(), stepped_world()
    paused.step(A)
    untouched.step(A)
    physics.save_state(paused, tmp_path / "state.npz")
    paused.step(B)
    untouched.step(B)
    assert_same_run(paused, untouched)


def test_loading_a_state_saved_before_any_step_gives_the_fresh_world(tmp_path):
    fresh = stepped_world()
    physics.save_state(fresh, tmp_path / "start.npz")
    loaded = stepped_world(seed=5)
    physics.load_state(loaded, tmp_path / "start.npz")
    assert loaded._resting_impulses is None and loaded.events.size == 0
    fresh.step(A)
    loaded.step(A)
    assert_same_run(fresh, loaded)


# --- refusals: one line naming the file ---------------------------------------------------


def refused(world, path) -> str:
    with pytest.raises(physics.PhysicsError) as caught:
        physics.load_state(world, path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(f"{path}: "), message
    return message


@pytest.fixture(scope="module")
def saved_bytes() -> dict:
    """The state file of `stepped_world` after A steps, by dtype (made once: stepping is slow)."""
    saved = {}
    for dtype in (np.float64, np.float32):
        world = stepped_world(dtype)
        world.step(A)
        saved[dtype] = state_bytes(world)
    return saved


@pytest.fixture
def saved(tmp_path, saved_bytes):
    """``saved(dtype)``: the path of a fresh copy of that state file in tmp_path."""
    def write(dtype=np.float64):
        path = tmp_path / "state.npz"
        path.write_bytes(saved_bytes[dtype])
        return path
    return write


def test_a_state_from_a_world_with_another_radius_is_refused_naming_the_body(saved):
    path = saved()
    world = stepped_world()
    world.radius[3] = 0.25
    assert refused(world, path) == (f"{path}: radius of body 3 is 0.15 m in the file but "
                                    "0.25 m in the world")


@pytest.mark.parametrize("change, message", [
    (lambda w: w.add_sphere((5, 5, 5)), "the number of bodies is 5 in the file but 6 in the "
                                        "world"),
    (lambda w: w.add_plane((0, 0, 1), -3), "the number of planes is 2 in the file but 3"),
    (lambda w: setattr(w, "dt", 1 / 120), "dt is 0.004166666666666667 s in the file but "
                                          "0.008333333333333333 s"),
    (lambda w: setattr(w, "solver", "simultaneous"), "solver is sequential in the file"),
    (lambda w: w.mass.__setitem__(0, 2.0), "mass of body 0 is"),
    (lambda w: w.plane_offset.__setitem__(1, -2.0), "offset of plane 1 is -1.0 m in the file"),
    (lambda w: setattr(w, "gravity", np.array([0, -1.62, 0])), "gravity is (0.0, -9.81, 0.0)"),
    (lambda w: setattr(w, "slop", 1e-3), "slop is 0.0001 m in the file but 0.001 m"),
], ids=["count", "planes", "dt", "solver", "mass", "plane", "gravity", "slop"])
def test_a_state_from_a_different_world_is_refused_naming_the_first_difference(
        saved, change, message):
    path = saved()
    world = stepped_world()
    before = world.position.copy()
    change(world)
    assert message in refused(world, path)
    np.testing.assert_array_equal(world.position[:5], before)     # nothing was loaded


def test_a_float32_state_is_refused_by_a_float64_world_and_kept_float32_by_its_own(saved):
    path = saved(np.float32)
    assert "the dtype is float32 in the file but float64 in the world" in refused(
        stepped_world(np.float64), path)
    world = stepped_world(np.float32)
    physics.load_state(world, path)
    assert world.position.dtype == world.velocity.dtype == world.orientation.dtype \
        == world._resting_impulses[1].dtype == np.float32


def test_a_different_number_of_shapes_is_refused(saved):
    path = saved()
    world = stepped_world()
    world.shapes.append(object())         # only counted: shapes come from the scene
    assert "the number of shapes is 0 in the file but 1 in the world" in refused(world, path)


def rewritten(path, **changes) -> None:
    """Rewrite the state file at ``path`` with some of its arrays replaced or (None) dropped."""
    with np.load(path) as archive:
        arrays = {key: archive[key] for key in archive.files}
    for key, value in changes.items():
        if value is None:
            del arrays[key]
        else:
            arrays[key] = value
    np.savez(path, **arrays)


def flipped_middle_byte(data: bytes) -> bytes:
    """``data`` with the bits of its middle byte inverted (inside an array's bytes)."""
    middle = len(data) // 2
    return data[:middle] + bytes([data[middle] ^ 0xFF]) + data[middle + 1:]


@pytest.mark.parametrize("damage, message", [
    (lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]), "damaged"),
    (lambda p: p.write_bytes(flipped_middle_byte(p.read_bytes())), "Bad CRC-32"),
    (lambda p: p.write_bytes(b"not a zip file at all"), "not a physics state file"),
    (lambda p: p.write_bytes(b""), "not a physics state file"),
    (lambda p: np.savez(p, x=np.zeros(3)), "not a physics state file (no 'marchlab physics "
                                           "state' tag)"),
    (lambda p: rewritten(p, version=np.array(VERSION + 1)),
     f"physics state format version {VERSION + 1}, but only version {VERSION} can be read"),
    (lambda p: rewritten(p, velocity=None), "damaged physics state: no velocity"),
    (lambda p: rewritten(p, position=np.zeros((4, 2))), "damaged physics state: position"),
    (lambda p: rewritten(p, steps=np.array("many")), "damaged physics state: steps"),
    (lambda p: rewritten(p, rng=np.array("{}")), "damaged random generator state"),
    (lambda p: p.unlink(), "no such state file"),
    (lambda p: (p.unlink(), p.mkdir()), "cannot read"),
], ids=["truncated", "flipped_byte", "garbage", "empty", "other_npz", "version",
        "missing_key", "bad_shape", "bad_steps", "bad_rng", "missing_file", "folder"])
def test_a_damaged_missing_or_other_version_file_is_refused_in_one_line(saved, damage,
                                                                         message):
    path = saved()
    damage(path)
    world = stepped_world()
    before = world.position.copy()
    assert message in refused(world, path)
    np.testing.assert_array_equal(world.position, before)
    assert world.steps == 0


# --- writing: whole or not at all -----------------------------------------------------------


def test_a_save_that_fails_while_encoding_leaves_no_file(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("disk on fire")
    monkeypatch.setattr(np, "savez", broken)
    with pytest.raises(RuntimeError):
        physics.save_state(stepped_world(), tmp_path / "state.npz")
    assert list(tmp_path.iterdir()) == []


def test_a_save_that_fails_at_the_rename_leaves_no_file_and_keeps_the_old_one(
        tmp_path, saved, monkeypatch):
    path = saved()
    old = path.read_bytes()

    def refuse_rename(*args):
        raise PermissionError(13, "Permission denied", args[1])
    monkeypatch.setattr(os, "replace", refuse_rename)
    world = stepped_world()
    world.step(1)
    with pytest.raises(physics.PhysicsError, match=r"state.npz: cannot write: Permission denied"):
        physics.save_state(world, path)
    assert [p.name for p in tmp_path.iterdir()] == ["state.npz"] and path.read_bytes() == old


def test_a_save_into_a_folder_that_cannot_exist_is_one_line_naming_the_file(tmp_path):
    (tmp_path / "file").write_text("a file, not a folder")
    path = tmp_path / "file" / "state.npz"
    with pytest.raises(physics.PhysicsError) as caught:
        physics.save_state(stepped_world(), path)
    assert str(caught.value) == f"{path}: cannot write: Not a directory"


def test_the_file_is_a_plain_npz_without_pickles_holding_the_documented_state(saved):
    path = saved()
    with zipfile.ZipFile(path) as archive:
        names = {name.removesuffix(".npy") for name in archive.namelist()}
    assert {"format", "version", "position", "velocity", "angular_velocity", "orientation",
            "active", "steps", "rng", "events", "warm_keys", "warm_normal",
            "warm_tangent"} <= names
    with np.load(path, allow_pickle=False) as archive:
        assert int(archive["steps"]) == A
    assert np.load(io.BytesIO(state_bytes(stepped_world())))["version"] == VERSION
