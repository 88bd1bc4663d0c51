"""The physics step on the GPU: physics.World's step as a GLSL compute shader, in float32.

``marchlab.simulation.simulate(world, seconds, backend="gpu")`` steps through a `GpuStepper`:
the world's state is uploaded once into shader storage buffers (std430), stepped there, and
read back into the `World` only at the steps a `Trajectory` records. The shader,
glsl/physics_step.glsl, runs the CPU step's stages as separate dispatches, with the CPU's
function names::

    begin_step           integrate_velocities, find_contacts (planes, shape_contacts,
                         spheres), warm_start
    collide_count/apply  each collision sweep of solve_simultaneous (mass split among the
                         contacts colliding in the sweep)
    warm_start_apply     _apply_warm_start
    rest_pass            each resting pass (mass split among all of a body's contacts)
    integrate_positions  the integrator, rotate_orientations, bounce_off_statics
    finish_step          stop_sphere_sweeps, separate_overlaps, _remove_out_of_bounds

with the same formulas, parameters and order of summation as physics/solvers.py and
physics/impulses.py: restitution max(e_a, e_b), friction sqrt(mu_a mu_b), the restitution
threshold, I = 2/5 m r^2, mass splitting, the capped push-out, the exact time of impact
against planes, warm starting, and the CPU's early exits from the sweep and pass loops (each
dispatch reads a counter the previous one wrote, so no read-back is needed to stop).

Static shapes (`physics.colliders.Shape`: boxes, bowls, pegs, any SDF) are Python functions
on the CPU. The GPU step is given the scene node each was built from (``shape_nodes``) and
collides with the renderer's own generated SDF code for it (gpu_shader/physics_shapes.py),
with the functions of physics/colliders.py under their names: shape_contacts (probes for
concave corners, surface_near for ridges), first_shape_hit (conservative advancement).

How it differs from the CPU step, and why:

- float32 only, and GLSL arithmetic: the driver may fuse a*b+c into one rounding and its
  division and sqrt need not be correctly rounded, so results agree with CPU float32 to
  rounding, not bit for bit. Worlds in float64 are refused (``world.copy(dtype="float32")``).
- the "simultaneous" solver only; "sequential" (Gauss-Seidel) has no data-parallel form.
- contacts and the sphere sweep test are found by brute force over all pairs, O(N^2) per
  step (one invocation per body gathers from every other body), instead of the CPU's broad
  phase. Same pairs, different cost: fine for the hundreds of spheres of a lesson.
- each body keeps at most MAX_CONTACTS contacts a step (planes first); more raises an error.
- at most 32 planes and 32 shapes (bit masks of the planes and shapes a body touches).
- the CPU's shapes may be any Python function; the GPU's are scene nodes the shader generator
  can write (every node of the scene format).
- warm starting starts cold at the start of each `simulate` call (a fresh world does too), and
  the accumulated impulses are not written back to the World afterwards.
- events are recorded by the shader with an atomic counter, drained every DRAIN_EVERY steps
  (a counter read; the state itself is read back only at records) and sorted into the CPU's
  order (step, then collision sweep, continuous pass, left-bounds; planes before pairs;
  by body). Their ``speed`` and ``impulse`` are float32 values.
"""

from __future__ import annotations

import numpy as np

from physics import colliders, continuous
from physics.errors import PhysicsError
from physics.events import EVENT_DTYPE
from scene_model.shapes import primitives

from .context import gl_context
from .dialects import GLSL
from .library import fill_template
from .physics_shapes import shape_code

MAX_CONTACTS = 24        # per body and step: 12 touching equal spheres, walls, and room
MAX_ITERATIONS = 64      # World.iterations allowed on the GPU (sizes the counter buffer)
MAX_PLANES = 32
MAX_SHAPES = 32
EVENT_CAPACITY = 1 << 16 # events held on the GPU (at least; 256 per body for large worlds)
DRAIN_EVERY = 4          # steps between read-backs of the event buffer (not of the state)
GROUP = 64               # local_size_x of the shader

STAGES = dict(begin=0, collide_count=1, collide_apply=2, warm_start=3, rest=4, positions=5,
              finish=6)
INTEGRATOR_CODES = {"explicit": 0, "semi_implicit": 1, "verlet": 2}
# The shader's event kinds, in the order the CPU records the events of one collision sweep.
EVENT_KINDS = np.array(["sphere-plane", "sphere-shape", "sphere-sphere", "left-bounds"])
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
                       ("contact_count", "<i4", 2), ("landing_count", "<i4"),
                       ("pad", "<i4")])
PLANE_DTYPE = np.dtype([("normal_offset", *VEC4), ("restitution", "<f4"), ("friction", "<f4"),
                        ("pad", "<f4", 2)])
GPU_EVENT_DTYPE = np.dtype([("step", "<i4"), ("stage", "<i4"), ("kind", "<i4"), ("body", "<i4"),
                            ("other", "<i4"), ("speed", "<f4"), ("impulse", "<f4"),
                            ("slot", "<i4")])
MOTION_BYTES, CONTACT_BYTES = 32, 64
PARAMETERS_BINDING = 0   # the uniform block of the shapes' numbers (physics_shapes.py)


def shader_source(shapes: str = "") -> str:
    """The compute shader's text: glsl/physics_step.glsl after its version, sizes and the
    constants of physics/colliders.py, with ``shapes`` (`physics_shapes.shape_code`) written in.
    """
    x, y, z = (GLSL.literal(c) for c in colliders.FALLBACK_NORMAL)
    a, b, c = (GLSL.literal(c) for c in colliders.OFF_RIDGE)
    head = (f"#version 430\n#define MAX_CONTACTS {MAX_CONTACTS}\n"
            f"#define MAX_ITERATIONS {MAX_ITERATIONS}\n#define MAX_PLANES {MAX_PLANES}\n"
            "// physics/colliders.py\n"
            f"#define FALLBACK_NORMAL vec3({x}, {y}, {z})\n"
            f"#define MAX_SHAPE_CONTACTS {colliders.MAX_SHAPE_CONTACTS}\n"
            f"#define SAME_SURFACE {GLSL.literal(colliders.SAME_SURFACE)}\n"
            f"#define MAX_ADVANCE {colliders.MAX_ADVANCE}\n"
            f"#define RIDGE {GLSL.literal(colliders.RIDGE)}\n"
            f"#define OFF_RIDGE vec3({a}, {b}, {c})\n"
            f"#define OFF_RIDGE_STEPS {GLSL.literal(colliders.OFF_RIDGE_STEPS)}\n\n")
    return head + fill_template("physics_step.glsl", shapes=shapes)


class GpuStepper:
    """Steps one float32 World (solver "simultaneous") on the GPU.

    ``stepper(n)`` takes n steps on the GPU, then copies the state and the events back into the
    world, so ``world.position`` etc. read as if the CPU had stepped it.

    Parameters
    ----------
    world : physics.World
    ctx : moderngl.Context, optional
    shape_nodes : sequence of scene_model.shapes.Node, optional
        For a world with static shapes: the scene object each of ``world.shapes`` was built
        from, in the same order (marchlab/colliders.py builds shape q from one node). The
        shader collides with the renderer's code for that node.
    shape_surfaces : sequence of (restitution (K,), friction (K,)) pairs, optional
        The coefficients of each primitive of each node, in depth-first order (the object
        ids of `scene_model.shapes.primitives`), as ``Shape.surface`` gives them on the CPU.
        Without them every primitive of shape q has ``world.shapes[q].restitution`` and
        ``.friction``.
    """

    def __init__(self, world, ctx=None, shape_nodes=None, shape_surfaces=None):
        check_world(world, shape_nodes)
        self.world = world
        self.ctx = ctx or gl_context()
        self.parity = 0
        n = max(world.count, 1)
        self.capacity = max(EVENT_CAPACITY, 256 * n)
        shapes = world_shape_code(world, shape_nodes or [], shape_surfaces)
        with self.ctx:
            limit = self.ctx.info["GL_MAX_UNIFORM_BLOCK_SIZE"]
            if shapes.parameters.nbytes > limit:
                raise PhysicsError(f"the static shapes need {len(shapes.parameters)} parameter "
                                   f"rows, more than this GPU's uniform block holds "
                                   f"({limit // 16})")
            self.program = self.ctx.compute_shader(shader_source(shapes.source))
            self.bodies = self.ctx.buffer(upload_bodies(world).tobytes())
            self.motion = self.ctx.buffer(reserve=2 * n * MOTION_BYTES)
            self.contacts = self.ctx.buffer(reserve=2 * n * MAX_CONTACTS * CONTACT_BYTES)
            self.planes = self.ctx.buffer(upload_planes(world).tobytes())
            self.counters = self.ctx.buffer(reserve=4 * (2 * MAX_ITERATIONS + 2))
            self.events = self.ctx.buffer(reserve=self.capacity * GPU_EVENT_DTYPE.itemsize)
            self.parameters = self.ctx.buffer(shapes.parameters.tobytes())
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
        uniforms = dict(u_count=w.count, u_planes=len(w.plane_offset), u_shapes=len(w.shapes),
                        u_integrator=INTEGRATOR_CODES[w.integrator],
                        u_event_capacity=self.capacity, u_has_bounds=int(w.bounds is not None),
                        u_h=float(np.float32(w.dt)), u_weight=_weight(w.integrator),
                        u_threshold=w.restitution_threshold, u_slop=w.slop,
                        u_skin=float(np.float32(continuous.SKIN_SLOPS * w.slop)),
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
        self.parameters.bind_to_uniform_block(PARAMETERS_BINDING)
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
            raise PhysicsError(f"a sphere had more than {MAX_CONTACTS} contacts in one step; "
                               "the gpu backend cannot hold that many")
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


def check_world(world, shape_nodes=None) -> None:
    """Raise PhysicsError, in one line, for a world the GPU step cannot run (with the scene
    nodes of its shapes, ``shape_nodes``)."""
    if world.dtype != np.float32:
        raise PhysicsError("the gpu backend steps in float32: use world.copy(dtype='float32')")
    if world.solver != "simultaneous":
        raise PhysicsError("the gpu backend runs the 'simultaneous' solver only: make the World "
                           "with solver='simultaneous'")
    if world.iterations > MAX_ITERATIONS:
        raise PhysicsError(f"the gpu backend allows at most {MAX_ITERATIONS} iterations")
    if len(world.plane_offset) > MAX_PLANES:
        raise PhysicsError(f"the gpu backend allows at most {MAX_PLANES} planes")
    if len(world.shapes) > MAX_SHAPES:
        raise PhysicsError(f"the gpu backend allows at most {MAX_SHAPES} static shapes")
    if world.shapes and shape_nodes is None:
        raise PhysicsError(f"the gpu backend needs the scene objects of the world's shapes "
                           f"(such as {world.shapes[0].name!r}) to write their SDF code: "
                           "give GpuStepper shape_nodes")
    if shape_nodes is not None and len(shape_nodes) != len(world.shapes):
        raise PhysicsError(f"{len(shape_nodes)} shape nodes for {len(world.shapes)} shapes")


def world_shape_code(world, nodes, surfaces=None):
    """The GLSL and parameter rows of ``world.shapes``, built from their scene ``nodes``
    (`physics_shapes.shape_code`); ``surfaces`` as `GpuStepper` takes them."""
    if surfaces is None:
        counts = [len(list(primitives([node]))) for node in nodes]
        surfaces = [(np.full(count, shape.restitution), np.full(count, shape.friction))
                    for count, shape in zip(counts, world.shapes)]
    return shape_code(nodes, surfaces, [shape.lipschitz for shape in world.shapes],
                      [shape.normal_step for shape in world.shapes],
                      [shape.name for shape in world.shapes])


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
    by step, then stage (sweep, continuous pass, bounds); within a collision sweep in the
    order of its contacts (planes, then shapes, then pairs; by body, other and slot), within
    a continuous pass or the bounds check by body."""
    sweep = raw["stage"] < 100
    kind = np.where(sweep, raw["kind"], 0)
    raw = raw[np.lexsort((raw["slot"], raw["other"], raw["body"], kind, raw["stage"],
                          raw["step"]))]
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
