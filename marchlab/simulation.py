"""From a scene to a physics world and back: the bodies stepped, then drawn frame by frame.

`build_world` reads the scene's ``[physics]`` settings, its ``[[bodies]]`` and its floor and
walls into a `physics.World`; `physics.simulate` steps it; `scene_model.scene.scene_at` puts the
recorded centres back into the scene for a renderer. `frame_plan` decides which steps become
frames: the time step stays fixed, the frame rate only chooses how often to look.

Which objects the bodies collide with: every top-level object of ``objects``. A plane moved
only by ``translate`` wrappers (the ``position`` shorthand) is an exact static plane of the
world; every other object (a box, a bowl carved by a subtraction, pegs made by repetition, a
rotated plane) is a static shape given by the renderer's own SDF (marchlab/colliders.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from physics import PhysicsError
import physics
from physics.errors import choice
from physics.quaternions import rotation_matrices
from scene_model.bodies import PhysicsSettings
from scene_model.errors import MarchlabError, SceneError
from scene_model.geometry import quaternion_from_matrix, rotation_matrix
from scene_model.motion import euler_degrees
from scene_model.scene import Scene

from .budget import check_physics
from .colliders import (body_solid, primitive_coefficients, scene_shapes, shape_objects,
                        static_planes)

PROGRESS_STEPS = 64        # physics steps between two progress reports


def _cpu_stepper(world: physics.World, scene: Scene | None = None):
    return world.step


def _gpu_stepper(world: physics.World, scene: Scene | None = None):
    from gpu_shader.physics import GpuStepper       # imported on use: it needs moderngl
    if scene is None:                               # no shapes, or GpuStepper refuses
        return GpuStepper(world)
    # The shader collides with the renderer's own code for each shape's scene object.
    settings = physics_settings(scene)
    nodes = shape_objects(scene)
    return GpuStepper(world, shape_nodes=nodes,
                      shape_surfaces=[primitive_coefficients(node, scene, settings)
                                      for node in nodes])


# The implementations of the physics step, by name: the CPU ground truth and the GPU compute
# shader checked against it. Each is a function of the world (and of the scene it was built
# from, which the GPU needs to write its shapes' code) returning ``step(n)``, which advances
# the world n steps and leaves its state readable (the GPU reads it back only then).
STEPPERS = {"cpu": _cpu_stepper, "gpu": _gpu_stepper}


def simulate(world: physics.World, seconds: float, record_every: int = 1,
             backend: str = "cpu", scene: Scene | None = None) -> physics.Trajectory:
    """`physics.simulate` with the step of ``backend``: "cpu" (`physics.World.step`) or "gpu"
    (`gpu_shader.physics.GpuStepper`: float32 worlds with the simultaneous solver only).
    ``scene``: the scene `build_world` made the world from; the gpu backend needs it for a
    world with shapes.

    Raises
    ------
    PhysicsError
        An unknown backend, or a world the backend cannot step.
    """
    step = STEPPERS[choice(backend, "backend", list(STEPPERS))](world, scene)
    return physics.simulate(world, seconds, record_every=record_every, step=step)


def physics_settings(scene: Scene) -> PhysicsSettings:
    """The scene's ``[physics]`` table, or its defaults if the scene has none."""
    return scene.physics or PhysicsSettings()


def build_world(scene: Scene, dtype=np.float64) -> physics.World:
    """A `physics.World` holding the scene's bodies (in order), its static planes and every
    other top-level object as a static shape (`marchlab.colliders.scene_shapes`).

    Parameters
    ----------
    scene : Scene
    dtype : {numpy.float64, numpy.float32}
        Precision of the world's state and arithmetic.

    Raises
    ------
    SceneError
        If the physics module refuses a value (say a mass that overflows to infinity), named
        by the field path of the body or setting that holds it.
    """
    settings = physics_settings(scene)
    try:
        world = physics.World(gravity=settings.gravity, dt=settings.dt,
                              integrator=settings.integrator, solver=settings.solver,
                              dtype=dtype, seed=settings.seed)
    except PhysicsError as err:
        raise SceneError(str(err), ("physics",)) from None
    for index, body in enumerate(scene.bodies):
        # A body's own value wins; without one, [physics] supplies restitution, friction and
        # the density its mass comes from.
        mass, density = body.mass, body.density
        if mass is None and density is None:
            density = settings.density
        try:
            # physics refuses a mass or moment of inertia that is not finite (with its
            # inverse) in the world's precision; the error is named by the body here.
            common = dict(velocity=body.velocity, angular_velocity=body.angular_velocity,
                          mass=mass, density=density,
                          restitution=_either(body.restitution, settings.restitution),
                          friction=_either(body.friction, settings.friction))
            turn = quaternion_from_matrix(rotation_matrix(body.rotation))
            with np.errstate(over="ignore", divide="ignore"):
                if body.shape == "box":
                    world.add_box(body.position, body.half_size, orientation=turn, **common)
                elif body.shape == "capsule":
                    world.add_capsule(body.position, body.half_length, body.radius,
                                      orientation=turn, **common)
                elif body.shape == "convex":
                    # The world moves the centre of mass along the principal axes; the
                    # scene places the solid's own origin and axes.
                    solid = body_solid(body.solid)
                    rotation = rotation_matrix(body.rotation)
                    world.add_convex(np.asarray(body.position) + rotation @ solid.centroid,
                                     solid, quaternion_from_matrix(rotation @ solid.axes),
                                     **common)
                else:
                    world.add_sphere(body.position, radius=body.radius, **common)
        except PhysicsError as err:
            raise SceneError(str(err), ("bodies", index)) from None
    for normal, offset in static_planes(scene):
        world.add_plane(normal, offset, restitution=settings.plane_restitution,
                        friction=settings.plane_friction)
    for shape in scene_shapes(scene, settings, dtype):
        world.add_shape(shape)
    return world


def _either(value, default):
    return default if value is None else value


def drawn_poses(scene: Scene, centres, orientations):
    """Where the renderers draw the bodies of ``scene`` whose world has them at ``centres``
    (N, 3) turned by ``orientations`` (N, 4): positions (N, 3) and Euler degrees (N, 3) for
    `scene_model.scene.scene_at`. A sphere, box or capsule is drawn at its centre; a convex
    body's solid has its own origin and axes where the world's centre of mass and principal
    axes put them (`build_world` did the reverse)."""
    centres = np.array(centres, np.float64).reshape(-1, 3)
    turns = rotation_matrices(np.asarray(orientations, np.float64).reshape(-1, 4))
    for index, body in enumerate(scene.bodies):
        if body.shape == "convex":
            solid = body_solid(body.solid)
            turns[index] = turns[index] @ solid.axes.T
            centres[index] -= turns[index] @ solid.centroid
    return centres, _degrees(turns)


def body_rotations(orientations) -> np.ndarray:
    """Euler angles (N, 3) in degrees (R = Rz Ry Rx, as a scene's rotate node) of the
    orientations (N, 4) of a world's bodies, for `scene_model.scene.scene_at`."""
    return _degrees(rotation_matrices(np.asarray(orientations, np.float64).reshape(-1, 4)))


def _degrees(matrices) -> np.ndarray:
    """Euler angles (N, 3) in degrees of rotation matrices (N, 3, 3)."""
    return np.array([euler_degrees(matrix) for matrix in matrices]).reshape(-1, 3)


@dataclass(frozen=True)
class FramePlan:
    """Which steps of a fixed-dt simulation become frames of an animation.

    Attributes
    ----------
    record_every : int
        Steps between two frames: round(1 / (fps dt)), at least 1.
    frames : int
        Number of frames: round(seconds fps), at least 1. Frame k shows step k record_every.
    frame_seconds : float
        Simulated time between two frames, record_every dt (s); equals 1/fps only when 1/fps
        is a multiple of dt.
    exact : bool
        Whether 1/fps is a multiple of dt (to 1e-9 relative).
    """
    record_every: int
    frames: int
    frame_seconds: float
    exact: bool

    @property
    def steps(self) -> int:
        """Steps from the first frame to the last."""
        return (self.frames - 1) * self.record_every


def frame_plan(dt: float, fps: float, seconds: float) -> FramePlan:
    """Plan ``seconds`` of animation at ``fps`` frames per second from steps of ``dt``.

    The plan is only counted, not checked against a budget (`marchlab.budget`): a plan of a
    billion frames is a plan, `simulate_scene` refuses to carry it out.

    Raises
    ------
    MarchlabError
        A number that is not positive and finite, less than one frame, or more frames or
        steps between frames than a float can count.
    """
    for name, value in (("fps", fps), ("seconds", seconds), ("dt", dt)):
        if not (math.isfinite(value) and value > 0):
            raise MarchlabError(f"{name} must be a positive number (got {value!r})")
    if not math.isfinite(seconds * fps):
        raise MarchlabError(f"{seconds!r} s at {fps!r} frames per second is more frames than "
                            "can be counted")
    frames = round(seconds * fps)
    if frames < 1:
        raise MarchlabError(f"{seconds!r} s at {fps!r} frames per second is less than one "
                            "frame")
    steps_per_frame = 1 / (fps * dt) if fps * dt > 0 else math.inf
    if not math.isfinite(steps_per_frame):
        raise MarchlabError(f"1/fps = {1 / fps:.6g} s is more steps of dt = {dt:.6g} s than "
                            "can be counted")
    record_every = max(1, round(steps_per_frame))
    exact = math.isclose(record_every * dt, 1 / fps, rel_tol=1e-9)
    return FramePlan(record_every, frames, record_every * dt, exact)


def simulate_scene(scene: Scene, plan: FramePlan, dtype=np.float64, *,
                   allow_large: bool = False,
                   progress: Callable[[int, int], None] | None = None,
                   world: physics.World | None = None) -> physics.Trajectory:
    """Step the scene's world and record one state per frame of ``plan`` (frames records).

    Parameters
    ----------
    scene : Scene
    plan : FramePlan
        From `frame_plan`.
    dtype : {numpy.float64, numpy.float32}
    allow_large : bool
        Go ahead beyond `marchlab.budget.MAX_BODY_STEPS` (steps x bodies), otherwise refused.
    progress : callable, optional
        Called as ``progress(steps done, plan.steps)`` every `PROGRESS_STEPS` steps.
    world : physics.World, optional
        The world to step (say one resumed from a saved state, `physics.load_state`); it is
        left in its final state. Default: a fresh `build_world(scene, dtype)`.

    Raises
    ------
    SceneError
        From `build_world`.
    BudgetError
        A plan of more steps x bodies than the budget, unless ``allow_large``.
    MarchlabError
        If the state stops being finite (values so large that the arithmetic overflows).
    """
    check_physics(plan.steps, len(scene.bodies), allow_large)
    world = build_world(scene, dtype) if world is None else world
    done = 0

    def step(n: int) -> None:
        # The same steps as world.step(n), in slices short enough to show progress.
        nonlocal done
        for start in range(0, n, PROGRESS_STEPS):
            count = min(PROGRESS_STEPS, n - start)
            world.step(count)
            done += count
            if progress is not None:
                progress(done, plan.steps)

    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):   # checked below
        trajectory = physics.simulate(world, plan.steps * world.dt,
                                      record_every=plan.record_every, step=step)
    finite = np.all(np.isfinite(trajectory.positions), axis=(1, 2))
    if not finite.all():
        time = trajectory.times[np.argmin(finite)]
        raise MarchlabError(f"the simulation overflowed (positions not finite at t = {time:.6g} "
                            "s); check the sizes in [physics] and [[bodies]]")
    return trajectory
