"""Saving a running world to a file and loading it back, so that a resumed run is bit-identical.

A `World` is two kinds of data. The *fixed description* (the bodies' shapes, sizes, masses
and coefficients, the planes, dt, the integrator and solver, the dtype, gravity, the bounds and
the solver's tolerances) comes from the scene and never changes while stepping. The *state*
is what `World.step` reads and then changes:

- ``position``, ``velocity``, ``angular_velocity`` (N, 3), ``orientation`` (N, 4), ``active``
  (N,) and ``steps`` (so ``time = steps x dt`` carries on);
- ``rng``, the generator that places a sphere spawned on another's centre;
- the warm start ``_resting_impulses``, last step's accumulated contact impulses (keys (K,),
  normal (K,), tangent (K, 3)). The next step's solver starts from them (Catto, "Iterative
  dynamics with temporal coherence", GDC 2005): a resumed run without them starts from zero,
  reaches slightly different impulses, and is no longer bit-identical;
- the events so far, so that ``world.events`` after a resume equals the uninterrupted run's.

`save_state` writes both kinds to one ``.npz`` file; `load_state` puts the state into a world
built again from the same scene, after checking that its fixed description is the file's, bit
for bit, and refusing in one line that names the first difference. The static SDF shapes
(``world.shapes``) hold Python functions and are not saved: they come from the scene, and only
their number is checked.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
import zlib

import numpy as np

from physics.errors import PhysicsError
from physics.events import EVENT_DTYPE
from scene_model.files import write_atomically

FORMAT = "marchlab physics state"     # the tag that says what the file is
VERSION = 3                           # raised whenever the keys or their meaning change

# The fixed description, checked in this order so the first difference named is the most
# basic one. Scalars: (key, what a message calls it, unit).
SETTINGS = (("dt", "dt", "s"), ("integrator", "integrator", ""), ("solver", "solver", ""),
            ("gravity", "gravity", "m/s^2"), ("bounds", "bounds", "m"),
            ("iterations", "iterations", ""),
            ("restitution_threshold", "restitution threshold", "m/s"),
            ("slop", "slop", "m"), ("push_out", "push-out fraction", ""))
# One value per sphere or per plane: (attribute, what a message calls it, unit).
BODY_COLUMNS = (("kind", "shape (0 sphere, 1 box, 2 capsule, 3 convex)", ""),
                ("radius", "radius", "m"), ("extent", "extent", "m"),
                ("gyration", "moments of inertia per unit mass", "m^2"), ("mass", "mass", "kg"),
                ("restitution", "restitution", ""), ("friction", "friction", ""))
PLANE_COLUMNS = (("plane_normal", "normal", ""), ("plane_offset", "offset", "m"),
                 ("plane_restitution", "restitution", ""), ("plane_friction", "friction", ""))
# The state: what a step reads and changes, with its dtype (None: the world's float dtype)
# and its shape after the count of bodies.
STATE_ARRAYS = (("position", None, (3,)), ("velocity", None, (3,)),
                ("angular_velocity", None, (3,)), ("orientation", None, (4,)),
                ("active", np.bool_, ()))
# The single values of the file and their numpy kinds (i: integer, f: float, U: text, b: bool).
SCALARS = dict(dtype="U", count="iu", planes="iu", shapes="iu", dt="f", integrator="U",
               solver="U", iterations="iu", restitution_threshold="f", slop="f",
               push_out="f", steps="iu", rng="U", warm_start="b")


def save_state(world, path) -> None:
    """Write ``world``'s state and fixed description to the ``.npz`` file ``path``.

    The file is written whole to a temporary beside ``path`` and renamed into place, so a
    failure leaves no file (and an older file at ``path`` untouched).

    Parameters
    ----------
    world : physics.World
    path : str or os.PathLike

    Raises
    ------
    PhysicsError
        If the file cannot be written (one line naming it).
    """
    payload = state_bytes(world)
    try:
        write_atomically(path, payload)
    except OSError as err:
        raise PhysicsError(f"{os.fspath(path)}: cannot write: {err.strerror}") from None


def state_bytes(world) -> bytes:
    """The bytes `save_state` writes, for a caller that writes several files together."""
    warm = world._resting_impulses
    arrays = dict(
        format=np.array(FORMAT), version=np.array(VERSION),
        # the fixed description
        dtype=np.array(np.dtype(world.dtype).name), count=np.array(world.count),
        planes=np.array(len(world.plane_offset)), shapes=np.array(len(world.shapes)),
        dt=np.array(world.dt), integrator=np.array(world.integrator),
        solver=np.array(world.solver), gravity=world.gravity,
        bounds=_bounds_array(world.bounds), iterations=np.array(world.iterations),
        restitution_threshold=np.array(world.restitution_threshold),
        slop=np.array(world.slop), push_out=np.array(world.push_out),
        **{name: getattr(world, name) for name, _, _ in BODY_COLUMNS + PLANE_COLUMNS},
        # the state
        **{name: getattr(world, name) for name, _, _ in STATE_ARRAYS},
        steps=np.array(world.steps, np.int64),
        rng=np.array(json.dumps(world.rng.bit_generator.state)),
        events=world.events,
        # None (no step yet) and an empty warm start behave alike, but are kept apart anyway
        warm_start=np.array(warm is not None),
        warm_keys=np.zeros(0, np.int64) if warm is None else warm[0],
        warm_normal=np.zeros(0, world.dtype) if warm is None else warm[1],
        warm_tangent=np.zeros((0, 3), world.dtype) if warm is None else warm[2])
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def load_state(world, path) -> None:
    """Put the state saved in ``path`` into ``world``, which must be built as the saved one was.

    Afterwards stepping ``world`` gives, bit for bit, what the saved world would have given.
    Nothing in ``world`` changes unless the whole file is read and accepted.

    Parameters
    ----------
    world : physics.World
        Built from the same scene (same spheres, planes, shapes and settings) as the world
        that was saved; its own state is replaced.
    path : str or os.PathLike
        A file written by `save_state`.

    Raises
    ------
    PhysicsError
        One line naming ``path`` and what is wrong: it is missing, unreadable, not a state
        file, of another format version, damaged, or saved from a different world (the first
        difference is named: ``state.npz: radius of body 3 is 0.25 m in the file but 0.3 m
        in the world``).
    """
    name = os.fspath(path)
    saved = _read(name)
    _check_same_world(name, saved, world)
    state = _checked_state(name, saved, world)
    # A new generator of the world's kind (PCG64), set to the saved state: the world's own
    # is replaced only once everything has been read and accepted.
    rng = np.random.Generator(type(world.rng.bit_generator)())
    try:
        rng.bit_generator.state = json.loads(str(saved["rng"]))
    except (ValueError, TypeError, KeyError) as err:
        raise PhysicsError(f"{name}: damaged random generator state ({_one_line(err)})") \
            from None
    for key, value in state.items():
        setattr(world, key, value)
    world.rng = rng


def _read(name: str) -> dict:
    """Every array of the file, or a PhysicsError naming it."""
    try:
        with open(name, "rb") as handle:
            data = io.BytesIO(handle.read())
    except FileNotFoundError:
        raise PhysicsError(f"{name}: no such state file") from None
    except OSError as err:
        raise PhysicsError(f"{name}: cannot read: {err.strerror or _one_line(err)}") from None
    # np.load guesses the kind of file, and takes anything that is not .npz or .npy for a
    # pickle; a state is always a whole .npz (zip) archive.
    if not zipfile.is_zipfile(data):
        raise PhysicsError(f"{name}: not a physics state file, or a damaged one (not a "
                           "complete .npz archive)")
    try:
        with np.load(data, allow_pickle=False) as archive:
            saved = {key: archive[key] for key in archive.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as err:
        raise PhysicsError(f"{name}: not a physics state file, or a damaged one "
                           f"({_one_line(err)})") from None
    if saved.get("format", np.array("")).tolist() != FORMAT:
        raise PhysicsError(f"{name}: not a physics state file (no {FORMAT!r} tag)")
    version = saved.get("version", np.array(None)).tolist()
    if version != VERSION:
        raise PhysicsError(f"{name}: physics state format version {version!r}, but only "
                           f"version {VERSION} can be read")
    arrays = {key for key, _, _ in BODY_COLUMNS + PLANE_COLUMNS + STATE_ARRAYS} | {
        "gravity", "bounds", "events", "warm_keys", "warm_normal", "warm_tangent"}
    missing = sorted((arrays | SCALARS.keys()) - saved.keys())
    if missing:
        raise PhysicsError(f"{name}: damaged physics state: no {', '.join(missing)}")
    for key, kind in SCALARS.items():
        if saved[key].shape != () or saved[key].dtype.kind not in kind:
            raise PhysicsError(f"{name}: damaged physics state: {key} is "
                               f"{saved[key].dtype} {saved[key].shape}, not one value")
    return saved


def _check_same_world(name: str, saved: dict, world) -> None:
    """A PhysicsError naming the first difference between the file's fixed description and
    ``world``'s; nothing if there is none."""
    def refuse(what: str, in_file, in_world, unit: str = "") -> None:
        def value(text) -> str:
            return f"{text} {unit}" if unit and text != "none" else str(text)
        raise PhysicsError(f"{name}: {what} is {value(in_file)} in the file but "
                           f"{value(in_world)} in the world")

    dtype = np.dtype(world.dtype).name
    if str(saved["dtype"]) != dtype:
        refuse("the dtype", saved["dtype"], dtype)
    for key, what in (("count", "the number of bodies"), ("planes", "the number of planes"),
                      ("shapes", "the number of shapes")):
        here = len(world.shapes) if key == "shapes" else (
            world.count if key == "count" else len(world.plane_offset))
        if int(saved[key]) != here:
            refuse(what, int(saved[key]), here)
    for key, what, unit in SETTINGS:
        here = _bounds_array(world.bounds) if key == "bounds" else np.asarray(getattr(world, key))
        if saved[key].shape != here.shape or not np.array_equal(saved[key], here):
            refuse(what, _text(saved[key]), _text(here), unit)
    for columns, kind in ((BODY_COLUMNS, "body"), (PLANE_COLUMNS, "plane")):
        for key, what, unit in columns:
            here = getattr(world, key)
            there = saved[key]
            if there.shape != here.shape or there.dtype != here.dtype:
                raise PhysicsError(f"{name}: damaged physics state: {key} is {there.dtype} "
                                   f"{there.shape}, not {here.dtype} {here.shape}")
            differ = there != here
            if differ.ndim > 1:
                differ = differ.any(axis=1)
            if differ.any():
                i = int(np.argmax(differ))
                refuse(f"{what} of {kind} {i}", _text(there[i]), _text(here[i]), unit)


def _checked_state(name: str, saved: dict, world) -> dict:
    """The state to set on ``world``, each array of the shape and dtype it must have."""
    n, dtype = world.count, world.dtype
    state = {}
    expected = [(key, dtype if kind is None else kind, (n,) + tail)
                for key, kind, tail in STATE_ARRAYS]
    warm_rows = saved["warm_keys"].size
    expected += [("warm_keys", saved["warm_keys"].dtype, (warm_rows,)),   # integers: below
                 ("warm_normal", dtype, (warm_rows,)), ("warm_tangent", dtype, (warm_rows, 3)),
                 ("events", EVENT_DTYPE, (saved["events"].size,))]
    for key, kind, shape in expected:
        array = saved[key]
        if array.dtype != kind or array.shape != shape:
            raise PhysicsError(f"{name}: damaged physics state: {key} is {array.dtype} "
                               f"{array.shape}, not {np.dtype(kind)} {shape}")
        state[key] = array.copy()
    if not np.issubdtype(state["warm_keys"].dtype, np.integer):
        raise PhysicsError(f"{name}: damaged physics state: warm_keys are not integers")
    steps = saved["steps"]
    if int(steps) < 0:
        raise PhysicsError(f"{name}: damaged physics state: steps is {_text(steps)}")
    warm = (state.pop("warm_keys"), state.pop("warm_normal"), state.pop("warm_tangent"))
    events = state.pop("events")
    state.update(steps=int(steps), _events=[events] if len(events) else [],
                 _resting_impulses=warm if bool(saved["warm_start"]) else None)
    return state


def _bounds_array(bounds) -> np.ndarray:
    """The (low, high) corners as a (2, 3) float64 array; (0, 3) for no bounds."""
    return np.zeros((0, 3)) if bounds is None else np.array(bounds, np.float64)


def _text(value) -> str:
    """A value as a message shows it: the shortest text that gives back its exact bits, so
    two values that differ never print alike (0.3 and 0.30000000000000004)."""
    value = np.asarray(value)
    if value.ndim == 0:
        return str(value.item() if value.dtype.kind in "biuU" else value[()])
    if value.size == 0:
        return "none"
    return "(" + ", ".join(_text(row) for row in value) + ")"


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__
