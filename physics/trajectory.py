"""Trajectories: a world stepped for a while, with its state recorded as arrays over time.

``simulate(world, seconds)`` steps the world and returns a `Trajectory` of plain arrays that a
plot, a CSV file, a renderer or a test can read without knowing anything about the stepping.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass

import numpy as np

from physics.errors import PhysicsError, in_range, whole_number
from physics.world import MAX_STEPS


@dataclass
class Trajectory:
    """The recorded states of a world: T records of N spheres.

    Attributes
    ----------
    times : (T,) float64
        Simulated time of each record (s).
    steps : (T,) int64
        Step number of each record.
    positions, velocities, angular_velocities : (T, N, 3)
        Centres (m), velocities (m/s), angular velocities (rad/s), in the world's dtype.
    orientations : (T, N, 4)
        Unit quaternions (w, x, y, z).
    active : (T, N) bool
        Whether each sphere was still in the world (False once it left the bounds).
    energy : (T,) float64
        Kinetic + rotational + potential energy of the active spheres (J).
    momentum : (T, 3) float64
        Total linear momentum of the active spheres (kg m/s).
    events : structured ndarray of physics.events.EVENT_DTYPE
        The contact and left-bounds events during the run, in order.
    """
    times: np.ndarray
    steps: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    angular_velocities: np.ndarray
    orientations: np.ndarray
    active: np.ndarray
    energy: np.ndarray
    momentum: np.ndarray
    events: np.ndarray

    def to_csv(self, path) -> None:
        """One row per record and body: time, body, x, y, z, vx, vy, vz, wx, wy, wz, the
        orientation as a unit quaternion qw, qx, qy, qz (a box's or capsule's pose; a
        sphere's spin), and active. Numbers are written to round-trip exactly."""
        with open(path, "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["time", "body", "x", "y", "z", "vx", "vy", "vz",
                             "wx", "wy", "wz", "qw", "qx", "qy", "qz", "active"])
            for t, time in enumerate(self.times):
                for body in range(self.positions.shape[1]):
                    writer.writerow([repr(float(time)), body,
                                     *map(repr, self.positions[t, body].tolist()),
                                     *map(repr, self.velocities[t, body].tolist()),
                                     *map(repr, self.angular_velocities[t, body].tolist()),
                                     *map(repr, self.orientations[t, body].tolist()),
                                     int(self.active[t, body])])


def simulate(world, seconds, record_every: int = 1, step=None) -> Trajectory:
    """Step ``world`` (in place) for ``seconds`` and record it.

    Parameters
    ----------
    world : World
    seconds : float
        How long to simulate (s): round(seconds / dt) steps, at most MAX_STEPS (physics.world)
        of them.
    record_every : int
        Record the state every this many steps; the state before the first step is always
        recorded, and so is the last.
    step : callable, optional
        ``step(n)`` advances the world n steps and leaves its state readable; default
        ``world.step``. Another implementation of the same step plugs in here (the GPU
        step, `gpu_shader.physics.GpuStepper`; `marchlab.simulation.simulate` picks one by
        name).

    Returns
    -------
    Trajectory
    """
    seconds = in_range(seconds, "seconds", 0)
    if seconds / world.dt > MAX_STEPS:
        raise PhysicsError(f"seconds must be at most {MAX_STEPS * world.dt:.3g} s (that is "
                           f"{MAX_STEPS:,} steps of dt = {world.dt:g} s; got {seconds!r})")
    record_every = whole_number(record_every, "record_every", 1)
    step = world.step if step is None else step
    total = int(round(seconds / world.dt))
    first_event = len(world.events)
    records = [_snapshot(world)]
    done = 0
    while done < total:
        count = min(record_every - done % record_every, total - done)
        step(count)
        done += count
        records.append(_snapshot(world))
    columns = {name: np.array([record[name] for record in records]) for name in records[0]}
    return Trajectory(**columns, events=world.events[first_event:])


def _snapshot(world) -> dict:
    return dict(times=world.time, steps=world.steps, positions=world.position.copy(),
                velocities=world.velocity.copy(),
                angular_velocities=world.angular_velocity.copy(),
                orientations=world.orientation.copy(), active=world.active.copy(),
                energy=world.energy(), momentum=world.momentum().astype(np.float64))
