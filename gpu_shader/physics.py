"""The physics step on the GPU: physics.World's step as a GLSL compute shader, in float32.

``marchlab.simulation.simulate(world, seconds, backend="gpu")`` steps through a `GpuStepper`:
the world's state is uploaded once into shader storage buffers (std430), stepped there, and
read back into the `World` only at the steps a `Trajectory` records. The shader, glsl/physics_step.glsl,
runs the CPU step's stages as separate dispatches, with the CPU's function names::

    begin_step           integrate_velocities, find_contacts, warm_start
    collide_count/apply  each collision sweep of solve_simultaneous (mass split among the
                         contacts colliding in the sweep)
    warm_start_apply     _apply_warm_start
    rest_pass            each resting pass (mass split among all of a body's contacts)
    integrate_positions  the integrator, rotate_orientations, bounce_off_planes
    finish_step          stop_sphere_sweeps, separate_overlaps, _remove_out_of_bounds

with the same formulas, parameters and order of summation as physics/solvers.py and
physics/impulses.py: restitution max(e_a, e_b), friction sqrt(mu_a mu_b), the restitution
threshold, I = 2/5 m r^2, mass splitting, the capped push-out, the exact time of impact
against planes, warm starting, and the CPU's early exits from the sweep and pass loops (each
dispatch reads a counter the previous one wrote, so no read-back is needed to stop).

How it differs from the CPU step, and why:

- float32 only, and GLSL arithmetic: the driver may fuse a*b+c into one rounding and its
  division and sqrt need not be correctly rounded, so results agree with CPU float32 to
  rounding, not bit for bit. Worlds in float64 are refused (``world.copy(dtype="float32")``).
- the "simultaneous" solver only; "sequential" (Gauss-Seidel) has no data-parallel form.
- contacts and the sphere sweep test are found by brute force over all pairs, O(N^2) per
  step (one invocation per body gathers from every other body), instead of the CPU's broad
  phase. Same pairs, different cost: fine for the hundreds of spheres of a lesson.
- each body keeps at most MAX_CONTACTS contacts a step (planes first); more raises an error.
- at most 32 planes (a bit mask of the planes a body touches).
- warm starting starts cold at the start of each `simulate` call (a fresh world does too), and
  the accumulated impulses are not written back to the World afterwards.
- events are recorded by the shader with an atomic counter, drained every DRAIN_EVERY steps
  (a counter read; the state itself is read back only at records) and sorted into the CPU's
  order (step, then collision sweep, continuous pass, left-bounds; planes before pairs;
  by body). Their ``speed`` and ``impulse`` are float32 values.
"""

from __future__ import annotations

import numpy as np

from physics.errors import PhysicsError
from physics.events import EVENT_DTYPE

from .context import gl_context
from .library import glsl_file

MAX_CONTACTS = 24        # per body and step: 12 touching equal spheres, walls, and room
MAX_ITERATIONS = 64      # World.iterations allowed on the GPU (sizes the counter buffer)
MAX_PLANES = 32
EVENT_CAPACITY = 1 << 16 # events held on the GPU (at least; 256 per body for large worlds)
DRAIN_EVERY = 4          # steps between read-backs of the event buffer (not of the state)
GROUP = 64               # local_size_x of the shader

STAGES = dict(begin=0, collide_count=1, collide_apply=2, warm_start=3, rest=4, positions=5,
              finish=6)
INTEGRATOR_CODES = {"explicit": 0, "semi_implicit": 1, "verlet": 2}
EVENT_KINDS = np.array(["sphere-plane", "sphere-sphere", "left-bounds"])
COUNT_EVENTS = 2 * MAX_ITERATIONS
COUNT_OVERFLOW = 2 * MAX_ITERATIONS + 1

# The std430 layouts of the shader's structs, field by field.
VEC4 = ("<f4", 4)
BODY_DTYPE = np.dtype([("position", *VEC4), ("velocity", *VEC4), ("spin", *VEC4),
                       ("orientation", *VEC4), ("start_position", *VEC4),
                       ("start_velocity", *VEC4), ("start_spin", *VEC4),
                       ("end_position", *VEC4), ("radius", "<f4"), ("inverse_mass", "<f4"),
                       ("inverse_inertia", "<f4"), ("restitution", "<f4"), ("friction", "<f4"),
                       ("in_world", "<i4"), ("start_in_world", "<i4"), ("colliding", "<i4"),
                       ("contact_count", "<i4", 2), ("pad", "<i4", 2)])
PLANE_DTYPE = np.dtype([("normal_offset", *VEC4), ("restitution", "<f4"), ("friction", "<f4"),
                        ("pad", "<f4", 2)])
GPU_EVENT_DTYPE = np.dtype([("step", "<i4"), ("stage", "<i4"), ("kind", "<i4"), ("body", "<i4"),
                            ("other", "<i4"), ("speed", "<f4"), ("impulse", "<f4"),
                            ("pad", "<i4")])
MOTION_BYTES, CONTACT_BYTES = 32, 48


def shader_source() -> str:
    """The compute shader's text: glsl/physics_step.glsl after its version and sizes."""
    return (f"#version 430\n#define MAX_CONTACTS {MAX_CONTACTS}\n"
            f"#define MAX_ITERATIONS {MAX_ITERATIONS}\n"
            + glsl_file("physics_step.glsl"))


class GpuStepper:
    """Steps one float32 World (solver "simultaneous") on the GPU.

    ``stepper(n)`` takes n steps on the GPU, then copies the state and the events back into the
    world, so ``world.position`` etc. read as if the CPU had stepped it.
    """

    def __init__(self, world, ctx=None):
        check_world(world)
        self.world = world
        self.ctx = ctx or gl_context()
        self.parity = 0
        n = max(world.count, 1)
        self.capacity = max(EVENT_CAPACITY, 256 * n)
        with self.ctx:
            self.program = self.ctx.compute_shader(shader_source())
            self.bodies = self.ctx.buffer(upload_bodies(world).tobytes())
            self.motion = self.ctx.buffer(reserve=2 * n * MOTION_BYTES)
            self.contacts = self.ctx.buffer(reserve=2 * n * MAX_CONTACTS * CONTACT_BYTES)
            self.planes = self.ctx.buffer(upload_planes(world).tobytes())
            self.counters = self.ctx.buffer(reserve=4 * (2 * MAX_ITERATIONS + 2))
            self.events = self.ctx.buffer(reserve=self.capacity * GPU_EVENT_DTYPE.itemsize)
            self._set_constants()         # uniforms are set on the current context

    def __call__(self, steps: int) -> None:
        """Take ``steps`` steps, then read the state back into the world."""
        if self.world.count:
            with self.ctx:
                for done in range(1, steps + 1):
                    self._step()
                    if done % DRAIN_EVERY == 0 and done < steps:
                        self._drain_events()
                self._drain_events()
                self._read_back()
        else:
            self.world.steps += steps

    def _set_constants(self) -> None:
        w = self.world
        uniforms = dict(u_count=w.count, u_planes=len(w.plane_offset),
                        u_integrator=INTEGRATOR_CODES[w.integrator],
                        u_event_capacity=self.capacity, u_has_bounds=int(w.bounds is not None),
                        u_h=float(np.float32(w.dt)), u_weight=_weight(w.integrator),
                        u_threshold=w.restitution_threshold, u_slop=w.slop,
                        u_push_out=w.push_out, u_gravity=tuple(map(float, w.gravity)))
        low, high = w.bounds if w.bounds is not None else ((0.0,) * 3, (0.0,) * 3)
        uniforms.update(u_low=tuple(map(float, low)), u_high=tuple(map(float, high)))
        for name, value in uniforms.items():
            self.program[name].value = value

    def _dispatch(self, stage: str, read: int = 0, pass_: int = 0) -> None:
        self.program["u_stage"].value = STAGES[stage]
        self.program["u_read"].value = read
        self.program["u_pass"].value = pass_
        self.program.run((self.world.count + GROUP - 1) // GROUP)
        self.ctx.memory_barrier()

    def _step(self) -> None:
        """One World._step: the dispatches listed in glsl/physics_step.glsl, in order."""
        iterations = self.world.iterations
        for index, buffer in enumerate((self.bodies, self.motion, self.contacts, self.planes,
                                        self.counters, self.events)):
            buffer.bind_to_storage_buffer(index)
        self.program["u_list"].value = self.parity
        self.program["u_step"].value = self.world.steps + 1
        self._dispatch("begin")
        read = 0                                  # velocity slot holding v*
        for k in range(iterations):               # collision sweeps
            self._dispatch("collide_count", read, k)
            self._dispatch("collide_apply", read, k)
            read ^= 1
        self._dispatch("warm_start", read)
        read ^= 1
        for k in range(iterations):               # resting-contact passes
            self._dispatch("rest", read, k)
            read ^= 1
        self._dispatch("positions", read)
        self._dispatch("finish")
        self.parity ^= 1
        self.world.steps += 1

    def _drain_events(self) -> None:
        """Move the events recorded so far into the world and empty the GPU's event buffer;
        raise if a contact list or the event buffer overflowed."""
        counters = np.frombuffer(self.counters.read(), "<u4")
        if counters[COUNT_OVERFLOW]:
            raise PhysicsError(f"a sphere touched more than {MAX_CONTACTS} bodies in one step; "
                               "the gpu backend cannot hold that many contacts")
        count = int(counters[COUNT_EVENTS])
        if count > self.capacity:
            raise PhysicsError(f"{count} contact events in {DRAIN_EVERY} steps overflow the "
                               f"gpu buffer ({self.capacity} events)")
        if count:
            raw = np.frombuffer(self.events.read(count * GPU_EVENT_DTYPE.itemsize),
                                GPU_EVENT_DTYPE)
            self.world._events.append(cpu_events(raw, self.world.dt))
            self.counters.write(np.zeros(1, "<u4").tobytes(), offset=4 * COUNT_EVENTS)

    def _read_back(self) -> None:
        """Copy positions, velocities, spins, orientations and active flags to the world."""
        w = self.world
        state = np.frombuffer(self.bodies.read(), BODY_DTYPE)
        dtype = w.dtype
        w.position = state["position"][:, :3].astype(dtype)
        w.velocity = state["velocity"][:, :3].astype(dtype)
        w.angular_velocity = state["spin"][:, :3].astype(dtype)
        w.orientation = state["orientation"].astype(dtype)
        w.active = state["in_world"] != 0
        w._resting_impulses = None     # kept on the GPU only (see the module docstring)


def check_world(world) -> None:
    """Raise PhysicsError, in one line, for a world the GPU step cannot run."""
    if world.dtype != np.float32:
        raise PhysicsError("the gpu backend steps in float32: use world.copy(dtype='float32')")
    if world.solver != "simultaneous":
        raise PhysicsError("the gpu backend runs the 'simultaneous' solver only: make the World "
                           "with solver='simultaneous'")
    if world.iterations > MAX_ITERATIONS:
        raise PhysicsError(f"the gpu backend allows at most {MAX_ITERATIONS} iterations")
    if len(world.plane_offset) > MAX_PLANES:
        raise PhysicsError(f"the gpu backend allows at most {MAX_PLANES} planes")


def upload_bodies(world) -> np.ndarray:
    """The world's spheres as (N,) BODY_DTYPE records (at least one, so buffers are not empty)."""
    n = world.count
    state = np.zeros(max(n, 1), BODY_DTYPE)
    state["position"][:n, :3] = world.position
    state["velocity"][:n, :3] = world.velocity
    state["spin"][:n, :3] = world.angular_velocity
    state["orientation"][:n] = world.orientation
    state["radius"][:n] = world.radius
    state["inverse_mass"][:n] = world.inverse_mass
    state["inverse_inertia"][:n] = world.inverse_inertia
    state["restitution"][:n] = world.restitution
    state["friction"][:n] = world.friction
    state["in_world"][:n] = world.active
    return state


def upload_planes(world) -> np.ndarray:
    """The world's planes as (P,) PLANE_DTYPE records (at least one)."""
    p = len(world.plane_offset)
    planes = np.zeros(max(p, 1), PLANE_DTYPE)
    planes["normal_offset"][:p, :3] = world.plane_normal
    planes["normal_offset"][:p, 3] = world.plane_offset
    planes["restitution"][:p] = world.plane_restitution
    planes["friction"][:p] = world.plane_friction
    return planes


def cpu_events(raw: np.ndarray, dt: float) -> np.ndarray:
    """GPU events (K,) GPU_EVENT_DTYPE as EVENT_DTYPE, in the order the CPU step records them:
    by step, then stage (sweep, continuous pass, bounds), planes before pairs, body, other."""
    raw = raw[np.lexsort((raw["other"], raw["body"], raw["kind"], raw["stage"], raw["step"]))]
    events = np.zeros(len(raw), EVENT_DTYPE)
    events["step"] = raw["step"]
    events["time"] = raw["step"] * dt
    events["kind"] = EVENT_KINDS[raw["kind"]]
    for name in ("body", "other", "speed", "impulse"):
        events[name] = raw[name]
    return events


def _weight(integrator: str) -> float:
    from physics.integrators import INTEGRATORS
    return INTEGRATORS[integrator].weight
