"""The physics step on the GPU: physics.World's step as a GLSL compute shader, in float32.

``marchlab.simulation.simulate(world, seconds, backend="gpu")`` steps through a `GpuStepper`:
the world's state is uploaded once into shader storage buffers (std430), stepped there, and
read back into the `World` only at the steps a `Trajectory` records. The shader,
glsl/physics_step.glsl, runs the CPU step's stages as separate dispatches (one compiled
program each), with the CPU's function names::

    grid_count .. _scatter
                         the broad phase (glsl/physics_grid.glsl): the bodies sorted by
                         the cell of a uniform grid they are in
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

A shape that moves (a kinematic object, ``Shape.motion``) is met where it is at the start of
each step, as the CPU's ``Shape.at(world.time)`` puts it: before each step's dispatches the
stepper writes its pose (R, pivot + s, w, s' at ``world.time``, computed in float64 by
scene_model.motion) into its rows of the parameter block (`physics_shapes.pose_rows`), and
the shader's contacts carry its surface velocity, which the solver subtracts from the
relative velocity and the continuous test uses in the impact, as physics/impulses.py and
physics/continuous.py do.

How it differs from the CPU step, and why:

- float32 only, and GLSL arithmetic: the driver may fuse a*b+c into one rounding and its
  division and sqrt need not be correctly rounded, so results agree with CPU float32 to
  rounding, not bit for bit. Worlds in float64 are refused (``world.copy(dtype="float32")``).
- the "simultaneous" solver only; "sequential" (Gauss-Seidel) has no data-parallel form.
- the broad phase is one uniform grid of hashed cells (after Teschner et al. 2003, each row
  of cells along x in consecutive slots), sorted by cell with a counting sort every step,
  cells as wide as the largest sphere plus the slop: each body looks for the spheres it may
  touch, or meet on its way, in the rows of cells around it, about O(N); the two stages that
  do (begin_step, finish_step) take the bodies in the grid's order, neighbours together. It
  finds exactly the pairs a loop over every pair finds (``all_pairs=True`` runs that loop;
  tests compare the two), and each body keeps its contacts in the order the CPU sums
  them (by the other's index), so the sums are the CPU's. The CPU keeps one grid per size
  class instead: here a few large spheres among many small ones make the cells, and the
  walks, larger (correct, slower). The sweep test's walks widen by the farthest any sphere
  moves in the step, so one very fast sphere makes every walk longer; a walk over more cells
  than there are bodies (so every walk in a world of a few bodies) loops over all bodies.
- each body keeps at most MAX_CONTACTS contacts a step (planes first); more raises an error.
  The CPU's crowd window (physics/crowds.py) is not mirrored: a crowd stops with that error.
- at most 32 planes and 32 shapes (bit masks of the planes and shapes a body touches).
- the CPU's shapes may be any Python function; the GPU's are scene nodes the shader generator
  can write (every node of the scene format).
- a moving shape's pose is rounded to float32 once and applied in float32 (the CPU applies
  it in float64 and rounds the point it gives), so where a kinematic object is involved the
  steps agree with the CPU's to rounding, not bit for bit.
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

from . import buffer_texture
from .context import gl_context
from .dialects import GLSL
from .library import fill_template
from .physics_shapes import pose_rows, shape_code

MAX_CONTACTS = 24        # per body and step: 12 touching equal spheres, walls, and room
MAX_ITERATIONS = 64      # World.iterations allowed on the GPU (sizes the counter buffer)
MAX_PLANES = 32
MAX_SHAPES = 32
EVENT_CAPACITY = 1 << 16 # events held on the GPU (at least; 256 per body for large worlds)
DRAIN_EVERY = 4          # steps between read-backs of the event buffer (not of the state)
GROUP = 64               # local_size_x of the shader
# texture units of the buffer textures read with TEXEL_READS (above the raster passes')
CONTACT_TEXELS, MOTION_TEXELS, BODY_TEXELS, ENTRY_TEXELS = 16, 17, 18, 19

STAGES = dict(begin=0, collide_count=1, collide_apply=2, warm_start=3, rest=4, positions=5,
              finish=6, grid_count=7, grid_scan=8, grid_scan_blocks=9, grid_scatter=10,
              grid_scan_add=11, order_scan=12, order_scatter=13)
INTEGRATOR_CODES = {"explicit": 0, "semi_implicit": 1, "verlet": 2}
# The shader's event kinds, in the order the CPU records the events of one collision sweep.
EVENT_KINDS = np.array(["sphere-plane", "sphere-shape", "sphere-sphere", "left-bounds"])
COUNT_EVENTS = MAX_ITERATIONS
COUNT_OVERFLOW = MAX_ITERATIONS + 1
COUNT_CANDIDATES = MAX_ITERATIONS + 3
COUNT_OUTSIDE_GRID = MAX_ITERATIONS + 4
COUNT_LISTED = MAX_ITERATIONS + 5     # MAX_ITERATIONS of them
COUNTERS = COUNT_LISTED + MAX_ITERATIONS    # the shader's counters[] (physics_step.glsl)

# The std430 layouts of the shader's structs, field by field.
VEC4 = ("<f4", 4)
BODY_DTYPE = np.dtype([("position", *VEC4), ("velocity", *VEC4), ("spin", *VEC4),
                       ("orientation", *VEC4), ("start_position", *VEC4),
                       ("start_velocity", *VEC4), ("start_spin", *VEC4),
                       ("end_position", *VEC4), ("radius", "<f4"), ("inverse_mass", "<f4"),
                       ("inverse_inertia", "<f4"), ("restitution", "<f4"), ("friction", "<f4"),
                       ("in_world", "<i4"), ("start_in_world", "<i4"), ("colliding", "<i4"),
                       ("contact_count", "<i4", 2), ("landing_count", "<i4"),
                       ("grid_rank", "<i4")])
PLANE_DTYPE = np.dtype([("normal_offset", *VEC4), ("restitution", "<f4"), ("friction", "<f4"),
                        ("pad", "<f4", 2)])
CONTACT_DTYPE = np.dtype([("normal_gap", *VEC4), ("tangent_total", *VEC4),
                          ("surface_velocity", *VEC4), ("other", "<i4"), ("slot", "<i4"),
                          ("normal_total", "<f4"), ("gravity_part", "<f4"),
                          ("coefficients", "<f4", 2), ("pad", "<f4", 2)])
GPU_EVENT_DTYPE = np.dtype([("step", "<i4"), ("stage", "<i4"), ("kind", "<i4"), ("body", "<i4"),
                            ("other", "<i4"), ("speed", "<f4"), ("impulse", "<f4"),
                            ("slot", "<i4")])
MOTION_BYTES, CONTACT_BYTES = 32, CONTACT_DTYPE.itemsize
STORAGE_BUFFERS = 11     # bindings 0 .. 10 of the shader
PARAMETERS_BINDING = 0   # the uniform block of the shapes' numbers (physics_shapes.py)


def shader_source(shapes: str = "", stage: str = "begin", texel_reads: bool = False) -> str:
    """The compute shader of one stage (a name of STAGES): glsl/physics_step.glsl after its
    version, sizes, the constants of physics/colliders.py and the STAGE, with ``shapes``
    (`physics_shapes.shape_code`) written in; with ``texel_reads``, the step reads contacts,
    velocities, bodies and grid entries through buffer textures (`buffer_texture`) at units
    CONTACT_TEXELS, MOTION_TEXELS, BODY_TEXELS and ENTRY_TEXELS.
    """
    x, y, z = (GLSL.literal(c) for c in colliders.FALLBACK_NORMAL)
    a, b, c = (GLSL.literal(c) for c in colliders.OFF_RIDGE)
    head = (f"#version 430\n#define STAGE {STAGES[stage]}  // {stage}\n"
            f"#define MAX_CONTACTS {MAX_CONTACTS}\n"
            f"#define MAX_ITERATIONS {MAX_ITERATIONS}\n#define MAX_PLANES {MAX_PLANES}\n"
            f"#define TEXEL_READS {int(texel_reads)}\n#define CONTACT_TEXELS {CONTACT_TEXELS}\n"
            f"#define MOTION_TEXELS {MOTION_TEXELS}\n#define BODY_TEXELS {BODY_TEXELS}\n"
            f"#define ENTRY_TEXELS {ENTRY_TEXELS}\n"
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
        shader collides with the renderer's code for that node; where ``world.shapes[q]``
        has a motion (a kinematic object), with that node put where the motion has it at the
        start of each step.
    shape_surfaces : sequence of (restitution (K,), friction (K,)) pairs, optional
        The coefficients of each primitive of each node, in depth-first order (the object
        ids of `scene_model.shapes.primitives`), as ``Shape.surface`` gives them on the CPU.
        Without them every primitive of shape q has ``world.shapes[q].restitution`` and
        ``.friction``.
    all_pairs : bool
        False (default): spheres look for each other in the grid of glsl/physics_grid.glsl.
        True: every sphere tests every other, the textbook O(N^2) loop the grid replaces; the
        same pairs, so the same steps (tests compare the two).
    texel_reads : bool, optional
        Whether the step reads contacts, velocities, bodies and grid entries through buffer
        textures (`buffer_texture`: the same numbers, a step in about 30% less time on
        llvmpipe) rather than as storage buffers. Default: where the context and the world's
        size allow it (the contact lists, the largest, fit GL_MAX_TEXTURE_BUFFER_SIZE).
    """

    def __init__(self, world, ctx=None, shape_nodes=None, shape_surfaces=None,
                 all_pairs=False, texel_reads=None):
        check_world(world, shape_nodes)
        self.world = world
        self.ctx = ctx or gl_context()
        self.all_pairs = bool(all_pairs)
        self.parity = 0
        self.stepped = False            # whether the contact lists hold a step's contacts
        n = max(world.count, 1)
        self.capacity = max(EVENT_CAPACITY, 256 * n)
        self.table_size, self.scan_block = grid_sizes(n)
        self.cell_size = cell_size(world)
        shapes = world_shape_code(world, shape_nodes or [], shape_surfaces)
        self.moving_shapes = shapes.pose_rows  # shape q -> the first row of its pose in P
        with self.ctx:
            limit = self.ctx.info["GL_MAX_UNIFORM_BLOCK_SIZE"]
            if shapes.parameters.nbytes > limit:
                raise PhysicsError(f"the static shapes need {len(shapes.parameters)} parameter "
                                   f"rows, more than this GPU's uniform block holds "
                                   f"({limit // 16})")
            storage = self.ctx.info.get("GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS", STORAGE_BUFFERS)
            if storage < STORAGE_BUFFERS:
                raise PhysicsError(f"the gpu physics step needs {STORAGE_BUFFERS} storage "
                                   f"buffers in a compute shader; this GPU allows {storage}")
            contact_bytes = 2 * n * MAX_CONTACTS * CONTACT_BYTES     # two steps' lists
            contact_texels = contact_bytes // buffer_texture.TEXEL_BYTES
            possible = (buffer_texture.available(self.ctx)
                        and contact_texels <= buffer_texture.max_texels(self.ctx))
            self.texel_reads = possible if texel_reads is None else bool(texel_reads)
            if self.texel_reads and not possible:
                raise PhysicsError("texel_reads: this context cannot make buffer textures of "
                                   f"{contact_texels} texels")
            self.programs = {stage: self.ctx.compute_shader(
                shader_source(shapes.source, stage, self.texel_reads)) for stage in STAGES}
            self.bodies = self.ctx.buffer(upload_bodies(world).tobytes())
            self.motion = self.ctx.buffer(reserve=2 * n * MOTION_BYTES)
            self.contacts = self.ctx.buffer(reserve=contact_bytes)
            self.planes = self.ctx.buffer(upload_planes(world).tobytes())
            # zeroed: the event count and the overflow flag are only ever added to (a reserved
            # buffer may hold what a released one left, as NVIDIA's driver gives it back)
            self.counters = self.ctx.buffer(bytes(4 * COUNTERS))
            self.events = self.ctx.buffer(reserve=self.capacity * GPU_EVENT_DTYPE.itemsize)
            # the grid (glsl/physics_grid.glsl); the counts start empty and the scan empties
            # them again after reading them, and the last start of each table stays 0
            blocks = self.table_size // self.scan_block
            self.cell_counts = self.ctx.buffer(bytes(4 * self.table_size))
            self.cell_starts = self.ctx.buffer(bytes(4 * (self.table_size + 1)))
            self.block_starts = self.ctx.buffer(bytes(4 * (blocks + 1)))
            self.grid_entries = self.ctx.buffer(reserve=16 * n)
            # the solver's order of the bodies: counts (start empty; the scan empties them
            # again), starts, then 2 N ints (glsl/physics_step.glsl, Order)
            self.order = self.ctx.buffer(bytes(4 * (2 * (MAX_CONTACTS + 1) + 2 * n)))
            self.parameters = self.ctx.buffer(shapes.parameters.tobytes())
            # the views the step reads through (TEXEL_READS), by texture unit
            self.texels = ({CONTACT_TEXELS: buffer_texture.BufferTexture(self.contacts),
                            MOTION_TEXELS: buffer_texture.BufferTexture(self.motion),
                            BODY_TEXELS: buffer_texture.BufferTexture(self.bodies),
                            ENTRY_TEXELS: buffer_texture.BufferTexture(self.grid_entries)}
                           if self.texel_reads else {})
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

    BUFFERS = ("bodies", "motion", "contacts", "planes", "counters", "events", "cell_counts",
               "cell_starts", "block_starts", "grid_entries", "order", "parameters")

    def release(self) -> None:
        """Free the programs and buffers (moderngl does not free them when collected)."""
        with self.ctx:
            for program in self.programs.values():
                program.release()
            for name in self.BUFFERS:
                getattr(self, name).release()
            for texture in self.texels.values():
                texture.release()

    def set_gravity(self, gravity) -> None:
        """Use ``gravity`` (3,) m/s^2 from the next step on (the world's, changed by a slider).
        Call it with the stepper's context current (``with stepper.ctx:``)."""
        for program in self.programs.values():
            _set_uniform(program, "u_gravity", tuple(map(float, gravity)))

    def _set_constants(self) -> None:
        w = self.world
        uniforms = dict(u_count=w.count, u_planes=len(w.plane_offset), u_shapes=len(w.shapes),
                        u_integrator=INTEGRATOR_CODES[w.integrator],
                        u_event_capacity=self.capacity, u_has_bounds=int(w.bounds is not None),
                        u_h=float(np.float32(w.dt)), u_weight=_weight(w.integrator),
                        u_threshold=w.restitution_threshold, u_slop=w.slop,
                        u_skin=float(np.float32(continuous.SKIN_SLOPS * w.slop)),
                        u_push_out=w.push_out, u_gravity=tuple(map(float, w.gravity)),
                        u_max_radius=float(np.max(w.radius, initial=0.0)),
                        u_cell_size=self.cell_size, u_table_size=self.table_size,
                        u_scan_block=self.scan_block, u_all_pairs=int(self.all_pairs))
        low, high = w.bounds if w.bounds is not None else ((0.0,) * 3, (0.0,) * 3)
        uniforms.update(u_low=tuple(map(float, low)), u_high=tuple(map(float, high)))
        for program in self.programs.values():
            for name, value in uniforms.items():
                _set_uniform(program, name, value)

    def _dispatch(self, stage: str, read: int = 0, pass_: int = 0, invocations=None) -> None:
        """Run ``stage`` once per body (or for ``invocations``), then wait for its writes."""
        program = self.programs[stage]
        for name, value in (("u_read", read), ("u_pass", pass_), ("u_list", self.parity),
                            ("u_step", self.world.steps + 1)):
            _set_uniform(program, name, value)
        count = self.world.count if invocations is None else invocations
        program.run((count + GROUP - 1) // GROUP)
        self.ctx.memory_barrier()

    def _step(self) -> None:
        """One World._step: the dispatches listed in glsl/physics_step.glsl, in order."""
        iterations = self.world.iterations
        self._place_moving_shapes()
        for index, buffer in enumerate((self.bodies, self.motion, self.contacts, self.planes,
                                        self.counters, self.events, self.cell_counts,
                                        self.cell_starts, self.block_starts,
                                        self.grid_entries, self.order)):
            buffer.bind_to_storage_buffer(index)
        self.parameters.bind_to_uniform_block(PARAMETERS_BINDING)
        for unit, texture in self.texels.items():
            texture.use(unit)
        self._dispatch("grid_count")              # the broad phase: sort the bodies by cell
        self._dispatch("grid_scan", invocations=self.table_size // self.scan_block)
        self._dispatch("grid_scan_blocks", invocations=1)
        self._dispatch("grid_scan_add", invocations=self.table_size + 1)
        self._dispatch("grid_scatter")
        self._dispatch("begin")
        self._dispatch("order_scan", invocations=1)   # the solver's bodies by contact count
        self._dispatch("order_scatter")
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
        self.stepped = True
        self.world.steps += 1

    def _place_moving_shapes(self) -> None:
        """Write where each moving shape is at the start of this step (``world.time``, as
        World._step's ``shape.at(self.time)``) into its rows of the parameter block."""
        t = self.world.time
        for q, row in self.moving_shapes.items():
            rows = pose_rows(self.world.shapes[q].motion, t)
            self.parameters.write(rows.tobytes(), offset=16 * row)

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

    def candidates(self) -> int:
        """How many bodies the last step's walks met: the candidates its contact and sweep
        tests looked at, summed over the bodies (2 N^2 with ``all_pairs``). A read-back."""
        with self.ctx:
            return int(np.frombuffer(self.counters.read(), "<u4")[COUNT_CANDIDATES])

    def contact_lists(self) -> list[np.ndarray]:
        """The other spheres in each body's contact list of the last step, in list order.

        Returns
        -------
        list of N int ndarrays
            For body i, the indices j of the spheres it touched (gap <= slop) at the positions
            the last step started from, in the order its impulses are summed: those of higher
            index (where i is a), then those of lower index (where i is b), each by index, as
            np.add.at adds `physics.contacts.find_contacts`' pairs. Planes and shapes (which
            come first) are left out. For tests and lessons: a read-back.
        """
        n = self.world.count
        if n == 0 or not self.stepped:
            return [np.zeros(0, np.int64) for _ in range(n)]
        parity = self.parity ^ 1                  # the list the last step wrote
        with self.ctx:
            counts = np.frombuffer(self.bodies.read(), BODY_DTYPE)["contact_count"][:n, parity]
            lists = np.frombuffer(self.contacts.read(), CONTACT_DTYPE)
        others = lists["other"].reshape(2, n, MAX_CONTACTS)[parity]
        return [row[:count][row[:count] >= 0].astype(np.int64)
                for row, count in zip(others, counts)]


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
    solid = np.flatnonzero(world.kind != 0)
    if len(solid):
        from physics.solids import KIND_NAMES
        raise PhysicsError(f"the gpu backend steps spheres only (body {solid[0]} is a "
                           f"{KIND_NAMES[world.kind[solid[0]]]} body): use the cpu backend")


def grid_sizes(count: int) -> tuple[int, int]:
    """(slots of the grid's hash table, slots per block of its scan) for ``count`` bodies.

    The table is the smallest power of two with at least two slots per body, so that few cells
    share a slot; a block is its square root (rounded up to a power of two), so that each
    invocation of the scan and the one that adds up the blocks do about as much work.
    """
    log2_table = max(1, (2 * count - 1).bit_length())
    return 1 << log2_table, 1 << ((log2_table + 1) // 2)


def cell_size(world) -> float:
    """The side of a grid cell (m): the diameter of the largest sphere plus the slop, as the
    CPU's grid (2 max(r + slop / 2)), in float32."""
    size = float(np.float32(2 * np.max(world.radius, initial=0.0) + world.slop))
    return size if size > 0 else 1.0


def world_shape_code(world, nodes, surfaces=None):
    """The GLSL and parameter rows of ``world.shapes``, built from their scene ``nodes``
    (`physics_shapes.shape_code`); ``surfaces`` as `GpuStepper` takes them."""
    if surfaces is None:
        counts = [len(list(primitives([node]))) for node in nodes]
        surfaces = [(np.full(count, shape.restitution), np.full(count, shape.friction))
                    for count, shape in zip(counts, world.shapes)]
    return shape_code(nodes, surfaces, [shape.lipschitz for shape in world.shapes],
                      [shape.normal_step for shape in world.shapes],
                      [shape.name for shape in world.shapes],
                      [shape.motion for shape in world.shapes])


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
    raw = raw.take(lexicographic_order([raw["step"], raw["stage"], kind, raw["body"],
                                        raw["other"], raw["slot"]]))
    events = np.zeros(len(raw), EVENT_DTYPE)
    events["step"] = raw["step"]
    events["time"] = raw["step"] * dt
    events["kind"] = EVENT_KINDS[raw["kind"]]
    for name in ("body", "other", "speed", "impulse"):
        events[name] = raw[name]
    return events


def lexicographic_order(keys: list) -> np.ndarray:
    """The stable order (K,) of rows sorted by ``keys`` (integer arrays (K,)), the first the
    most significant: np.lexsort's, with its keys the other way round.

    The keys are read as the digits of one int64 number, each in base (its largest value -
    its smallest + 1), and that number is argsorted: one sort instead of lexsort's one per
    key, two to three times faster on the 40,000 events a step of a 10,000-sphere pile
    records (and ``take`` rather than fancy indexing gathers the structured rows, which it
    does twenty times faster). Keys whose digits would not fit in 63 bits go to np.lexsort.
    Where no two rows are equal on every key (no two events of a step are), any sort gives
    the stable order: NumPy's default sort is tried first, about three times faster, and
    kept unless two numbers tie.
    """
    if not len(keys[0]):
        return np.zeros(0, np.intp)
    number, span = np.zeros(len(keys[0]), np.int64), 1
    for key in keys:
        low = int(key.min())
        base = int(key.max()) - low + 1
        span *= base
        if span >= 2 ** 63:
            return np.lexsort(keys[::-1])
        number = number * base + (key.astype(np.int64) - low)
    order = np.argsort(number)
    ordered = number.take(order)
    if np.any(ordered[1:] == ordered[:-1]):     # a tie: only a stable sort keeps its order
        return np.argsort(number, kind="stable")
    return order


def _set_uniform(program, name: str, value) -> None:
    """Set a uniform of ``program``, if its stage uses it (the compiler drops the others)."""
    member = program.get(name, None)
    if member is not None:
        member.value = value


def _weight(integrator: str) -> float:
    from physics.integrators import INTEGRATORS
    return INTEGRATORS[integrator].weight
