"""Physics that plays live in a viewer: the fixed-dt world stepped by a clock of frames.

A window draws frames at whatever rate it manages; the physics steps with the scene's fixed dt.
`Playback.advance` joins the two with the fixed-timestep loop of Glenn Fiedler, "Fix your
timestep!" (gafferongames.com/post/fix_your_timestep, 2004): each frame's time goes into an
accumulator, and as many whole steps of dt as fit are taken out of it. The run is then the same
whatever the frame rate, step for step (tests/test_playback.py checks it bit for bit).

Every button and slider of the viewer is a method here (play, pause, step, reset, time scale,
gravity, restitution, friction, kick, pick a ball, grab it and throw it), so a test presses them
without a window; the window turns input into these calls and draws ``playback.scene_now()``.
"""

from __future__ import annotations

import dataclasses
from collections import deque

import numpy as np

from physics import PhysicsError
from physics.errors import in_range, vector3, whole_number
from reference_cpu.truth.analytic import interval_sphere
from scene_model.bodies import PhysicsSettings
from scene_model.errors import MarchlabError, SceneError
from scene_model.scene import Scene, scene_at

from .render import backend_problem
from .simulation import STEPPERS, build_world, drawn_poses, physics_settings

MIN_TIME_SCALE, MAX_TIME_SCALE = 0.1, 4.0   # slow motion to fast forward
# A stalled frame (a window dragged, a breakpoint) must not make the next one take seconds of
# steps, which would stall it in turn (Fiedler's "spiral of death"). 64 steps cover a time
# scale of 4 at 30 frames per second with the default dt of 1/240 s, with room to spare.
MAX_STEPS_PER_FRAME = 64
HISTORY = 600                               # samples for the live plots: 10 s at 60 frames/s


class Playback:
    """A scene's bodies stepped live: what a viewer's buttons, sliders and mouse do to them.

    Parameters
    ----------
    scene : Scene
        Its bodies, planes and ``[physics]`` settings make the world (`build_world`).
    backend : {"cpu", "gpu"}
        "cpu": `physics.World.step` in float64. "gpu": the compute shader of
        `gpu_shader.physics` in float32, for scenes with ``solver = "simultaneous"``.
    max_steps_per_frame : int
        Most steps one `advance` takes; the time beyond is dropped (`dropped_seconds`).
    history : int
        How many samples of (time, energy, momentum) `history` keeps.

    Attributes
    ----------
    world : physics.World
        The live state: ``world.position`` (N, 3) m, ``world.velocity`` (N, 3) m/s, ...
        (`reset` puts a new World here: read it through the Playback, do not keep it.)
    playing : bool
        Whether `advance` steps. A new Playback is paused, so a viewer shows the scene as
        written until the user presses play.
    settings : PhysicsSettings
        The scene's ``[physics]`` with the values the sliders last set. Until a slider moves,
        a body's own restitution or friction in ``[[bodies]]`` wins over this table's.
    dropped_seconds : float
        Simulated seconds the per-frame cap has thrown away since the last reset.

    Raises
    ------
    MarchlabError
        An unknown backend, a gpu backend that cannot run here or cannot step this scene, or
        a scene whose values the physics module refuses (`SceneError`).
    """

    def __init__(self, scene: Scene, backend: str = "cpu", *,
                 max_steps_per_frame: int = MAX_STEPS_PER_FRAME, history: int = HISTORY):
        if backend not in STEPPERS:
            raise MarchlabError(f"backend must be one of {', '.join(map(repr, STEPPERS))} "
                                f"(got {backend!r})")
        if backend == "gpu":
            _check_gpu(scene)
        self.scene = scene
        self.backend = backend
        self.max_steps_per_frame = _user(whole_number, max_steps_per_frame,
                                         "max_steps_per_frame", 1)
        self._initial = build_world(scene, np.float32 if backend == "gpu" else np.float64)
        self._history = deque(maxlen=_user(whole_number, history, "history", 1))
        self._stepper = None
        self._time_scale = 1.0
        self.playing = False
        self.reset()

    # --- the clock ------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated time (s), steps x dt."""
        return self.world.time

    @property
    def steps(self) -> int:
        """Steps taken since the last reset."""
        return self.world.steps

    @property
    def time_scale(self) -> float:
        """Simulated seconds per second of frames, MIN_TIME_SCALE to MAX_TIME_SCALE."""
        return self._time_scale

    @time_scale.setter
    def time_scale(self, value: float) -> None:
        self._time_scale = _user(in_range, value, "time_scale", MIN_TIME_SCALE, MAX_TIME_SCALE)

    @property
    def alpha(self) -> float:
        """How far the clock is into the next step, 0 to 1: what is left in the accumulator
        over dt (the blend weight of ``positions(blend=True)``)."""
        return min(max(self._accumulator / self.world.dt, 0.0), 1.0)

    def play(self) -> None:
        self.playing = True

    def pause(self) -> None:
        self.playing = False

    def advance(self, frame_seconds: float) -> int:
        """Let ``frame_seconds`` of the viewer's clock pass; return the steps taken (0 if paused).

        frame_seconds x time_scale goes into the accumulator and whole steps of dt come out,
        the remainder waiting for the next frame. More than ``max_steps_per_frame`` steps are
        not taken: the excess whole steps are dropped and counted in `dropped_seconds`.
        """
        seconds = _user(in_range, frame_seconds, "frame_seconds", 0)
        if not self.playing:
            return 0
        dt = self.world.dt
        self._accumulator += seconds * self._time_scale
        steps = int(self._accumulator // dt)
        excess = max(steps - self.max_steps_per_frame, 0)
        self.dropped_seconds += excess * dt
        steps -= excess
        self._accumulator -= (steps + excess) * dt
        if steps:
            self._take(steps)
            self._sample()
        return steps

    def step(self) -> None:
        """Take exactly one step, playing or paused (the accumulator is left alone)."""
        self._take(1)
        self._sample()

    def reset(self) -> None:
        """Back to the scene as written: its bodies, its ``[physics]`` settings, time 0.

        Whether it plays and the time scale are the viewer's, and are kept.
        """
        self.world = self._initial.copy()
        self.settings = physics_settings(self.scene)
        self._accumulator = 0.0
        self.dropped_seconds = 0.0
        self._kicks = np.random.default_rng(self.settings.seed)
        self._held = self._target = None
        self._previous = self.world.position.copy()
        self._history.clear()
        self._stale = False
        if self.backend == "gpu":
            # A new stepper: the old one's contact lists (for warm starting) belong to the old run.
            _release(self._stepper)
            try:
                self._stepper = STEPPERS["gpu"](self.world, self.scene)
            except PhysicsError as err:
                raise MarchlabError(f"the gpu backend cannot step this scene: {err}") from None
        else:
            self._stepper = self.world.step
        self._sample()

    # --- the sliders ----------------------------------------------------------------------

    def set_gravity(self, gravity) -> None:
        """Gravity (3,) m/s^2 from now on; the bodies keep their state. Also moves the zero
        of `energy`'s potential term, -m g.x, so the energy curve jumps."""
        self.settings = self._changed(gravity=gravity)
        self.world.gravity = np.asarray(self.settings.gravity, self.world.dtype)
        self._stale = True

    def set_restitution(self, restitution: float) -> None:
        """Restitution e of every body and plane, so every pair bounces with e (a pair takes
        the larger of its two, physics/impulses.py). The bodies keep their state."""
        self.settings = self._changed(restitution=restitution, plane_restitution=restitution)
        self.world.restitution[:] = self.settings.restitution
        self.world.plane_restitution[:] = self.settings.restitution
        self._stale = True

    def set_friction(self, friction: float) -> None:
        """Friction mu of every body and plane, so every pair slides with mu (a pair takes
        sqrt(mu_a mu_b)). The bodies keep their state."""
        self.settings = self._changed(friction=friction, plane_friction=friction)
        self.world.friction[:] = self.settings.friction
        self.world.plane_friction[:] = self.settings.friction
        self._stale = True

    def _changed(self, **change) -> PhysicsSettings:
        # The ranges a scene file allows, checked by the same code, named by the same path.
        try:
            return dataclasses.replace(self.settings, **change)
        except SceneError as err:
            raise err.under("physics") from None

    # --- the mouse and the kick -----------------------------------------------------------

    def kick(self, strength: float, seed: int | None = None) -> np.ndarray:
        """Give every body in the world an impulse of ``strength`` (N s) in a random direction.

        Each velocity changes by impulse / mass. The directions are uniform on the sphere
        (normalised Gaussian vectors, Muller 1959), drawn from ``np.random.default_rng(seed)``;
        without a seed, from a generator seeded by ``[physics] seed`` at reset, so a session's
        kicks differ from each other but repeat from run to run.

        Returns
        -------
        (N, 3) ndarray
            The impulses (N s), zero for bodies that have left the world.
        """
        strength = _user(in_range, strength, "strength", 0)
        rng = self._kicks if seed is None else np.random.default_rng(
            _user(whole_number, seed, "seed", 0))
        direction = rng.standard_normal((self.world.count, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        impulse = strength * direction * self.world.active[:, None]
        self.world.velocity += impulse * self.world.inverse_mass[:, None]
        self._stale = True
        return impulse

    def pick(self, origin, direction) -> int | None:
        """The body whose sphere the ray ``origin + t direction`` (t >= 0) meets first, or None.

        A ray that starts inside a ball picks it. The intersection is the exact one of
        `reference_cpu.truth.analytic.interval_sphere`.
        """
        origin = _user(vector3, origin, "origin")
        direction = _user(vector3, direction, "direction")
        if not direction.any():
            raise MarchlabError("direction must not be the zero vector")
        nearest, best = None, np.inf
        for body in np.flatnonzero(self.world.active):
            centre = self.world.position[body].astype(np.float64)
            t_in, t_out, _, _ = interval_sphere((origin - centre)[None], direction[None],
                                                float(self.world.radius[body]))
            if t_out[0] < 0:                       # missed (t_out = -inf) or behind the origin
                continue
            t = max(float(t_in[0]), 0.0)
            if t < best:
                nearest, best = int(body), t
        return nearest

    def grab(self, body: int) -> None:
        """Hold ``body`` (an index into ``scene.bodies``) so that it follows `drag_to`.

        A held ball is led, not pulled: each step it is put on the straight path from where it
        was at the start of the frame to the target and given the velocity of that path, its
        spin stopped. So it lets go with exactly the velocity the drag gave it (a spring would
        lag, and overshoot unless tuned to the ball's mass and dt). Other bodies feel it as a
        body of its own mass moving that way.
        """
        if not self.world.count:
            raise MarchlabError("the scene has no bodies to grab")
        body = _user(whole_number, body, "body", 0, self.world.count - 1)
        if not self.world.active[body]:
            raise MarchlabError(f"body {body} has left the world and cannot be grabbed")
        self._held = body
        self._target = self.world.position[body].astype(np.float64)

    def drag_to(self, point) -> None:
        """Move the held body's target to ``point`` (3,) m.

        Playing, the body gets there over the steps of the next `advance` or `step`, with the
        velocity that takes it there. Paused, no time passes: it is put there at rest.
        """
        if self._held is None:
            raise MarchlabError("nothing is held: grab a body before dragging it")
        self._target = _user(vector3, point, "point")
        if not self.playing:
            self._hold(self._target, np.zeros(3))
            self._previous[self._held] = self._target

    def release(self) -> None:
        """Let the held body go with the velocity the drag gave it."""
        self._held = self._target = None

    def _hold(self, position, velocity) -> None:
        world = self.world
        world.position[self._held] = position
        world.velocity[self._held] = velocity
        world.angular_velocity[self._held] = 0
        self._stale = True

    # --- what a viewer draws and plots ----------------------------------------------------

    def positions(self, blend: bool = False) -> np.ndarray:
        """Centres of the bodies, (N, 3) float64 in m, in the order of ``scene.bodies``.

        ``blend=True`` gives Fiedler's "final touch": the state before the last step blended
        with the current one by `alpha`, so motion looks smooth when the number of steps per
        frame varies (it lags by at most one step).
        """
        current = self.world.position.astype(np.float64)
        if not blend:
            return current
        return (1 - self.alpha) * self._previous.astype(np.float64) + self.alpha * current

    def scene_now(self, blend: bool = False) -> Scene:
        """The scene with its bodies (and kinematic objects) where they are now, for a
        renderer."""
        positions, rotations = drawn_poses(self.scene, self.positions(blend),
                                           self.world.orientation)
        return scene_at(self.scene, positions, self.world.time, rotations)

    def energy(self) -> float:
        """Kinetic (with rotational) plus potential energy -sum m g.x of the bodies still in
        the world (J), zero at the origin."""
        return self.world.energy()

    def momentum(self) -> np.ndarray:
        """Total linear momentum of the bodies still in the world, (3,) float64 in kg m/s."""
        return self.world.momentum().astype(np.float64)

    @property
    def history(self) -> np.ndarray:
        """The last samples for the live plots, (K, 3) float64: time (s), energy (J) and
        momentum magnitude (kg m/s). One at reset and one after each advance or step that
        stepped; at most ``history`` of them."""
        return np.array(self._history, dtype=np.float64).reshape(-1, 3)

    def _sample(self) -> None:
        self._history.append((self.time, self.energy(), float(np.linalg.norm(self.momentum()))))

    # --- stepping -------------------------------------------------------------------------

    def _take(self, steps: int) -> None:
        """Take ``steps`` steps, leading a held body along its path (see `grab`)."""
        if self._held is None:
            self._run(steps - 1)
            self._previous = self.world.position.copy()
            self._run(1)
            return
        dt = self.world.dt
        start = self.world.position[self._held].astype(np.float64)
        velocity = (self._target - start) / (steps * dt)
        for k in range(steps):
            self._hold(start + velocity * (k * dt), velocity)
            self._previous = self.world.position.copy()
            self._run(1)
        self._hold(self._target, velocity)

    def _run(self, steps: int) -> None:
        if steps == 0:
            return
        if self._stale and self.backend == "gpu":
            _send_state(self._stepper)
        self._stale = False
        with np.errstate(over="ignore", invalid="ignore"):   # a blow-up shows in the plots
            self._stepper(steps)


def _user(check, value, name, *bounds):
    """``check(value, name, *bounds)`` from physics.errors, its error as a MarchlabError."""
    try:
        return check(value, name, *bounds)
    except PhysicsError as err:
        raise MarchlabError(str(err)) from None


def _check_gpu(scene: Scene) -> None:
    problem = backend_problem("gpu")
    if problem:
        raise MarchlabError(f"the gpu backend cannot run here: {problem}")
    if physics_settings(scene).solver != "simultaneous":
        raise MarchlabError('the gpu backend steps the "simultaneous" solver only: set '
                            'solver = "simultaneous" in the scene\'s [physics]')


# The fields of gpu_shader.physics.BODY_DTYPE that hold the World's state. The others are the
# shader's scratch and its contact lists, kept so that warm starting carries on as on the CPU.
_WORLD_FIELDS = ("position", "velocity", "spin", "orientation", "radius", "inverse_mass",
                 "inverse_inertia", "restitution", "friction", "in_world")


def _send_state(stepper) -> None:
    """Write the world's state and settings into a `gpu_shader.physics.GpuStepper`'s buffers.

    The stepper uploads the world once and then keeps it on the GPU; a kick, a drag or a slider
    changes the World on the CPU, so the change is sent before the next step.
    """
    from gpu_shader.physics import BODY_DTYPE, upload_bodies, upload_planes
    world = stepper.world
    with stepper.ctx:
        state = np.frombuffer(stepper.bodies.read(), BODY_DTYPE).copy()
        fresh = upload_bodies(world)
        for name in _WORLD_FIELDS:
            state[name] = fresh[name]
        stepper.bodies.write(state.tobytes())
        stepper.planes.write(upload_planes(world).tobytes())
        stepper.set_gravity(world.gravity)


def _release(stepper) -> None:
    """Free a GpuStepper's programs and buffers (moderngl does not free them when collected)."""
    if stepper is not None:
        stepper.release()
