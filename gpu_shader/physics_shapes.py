"""The static shapes of the GPU physics step, written with the renderer's own SDF code.

A `physics.colliders.Shape` holds Python functions; the compute shader needs GLSL. So for each
shape the generator is given the scene node it was built from and writes, with the very code
the renderer marches (`gpu_shader.sdf_code.sdf_functions` and the normal template
glsl/pipeline/normals.glsl):

    real shape_distance_q(vec3 p)     the object's SDF           (Shape.distance)
    int shape_object_id_q(vec3 p)     the primitive it picks     (for Shape.surface)
    vec3 shape_normal_q(vec3 p)       central differences        (Shape.normal)

and then one function of each kind taking the shape's index, which glsl/physics_step.glsl
calls: ``shape_distance``, ``shape_normal``, ``shape_surface`` (restitution and friction of
the primitive's material, as marchlab/colliders.py gives them to the CPU),
``shape_velocity`` (of its surface) and ``shape_lipschitz``, ``shape_normal_step``. The
numbers (the tree's parameters, the coefficients, L and the finite-difference step) are rows
of a parameter block ``P``, as in the renderer, so the text depends only on the trees' shapes.

A shape that a `scene_model.motion.Motion` moves (a kinematic object) keeps the functions
above for the object as given, and gets its pose as rows of ``P`` that the physics step
rewrites before each step (`pose_rows`, the time at the start of the step, as
``Shape.at(world.time)`` on the CPU). With x(t) = R (x - pivot) + pivot + s::

    vec3 shape_local_q(vec3 p)        R^T (p - pivot - s) + pivot: where p is on the
                                      object as given                (Shape.at, ``local``)
    vec3 shape_turn_q(vec3 n)         R n: a normal of it turned where it is now
    vec3 shape_velocity_q(vec3 p)     w x (p - pivot - s) + s'       (motion_velocity)

and its functions by index read ``shape_distance_q(shape_local_q(p))`` and so on. A shape
that does not move is written as if no shape moved (its velocity is 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from reference_cpu.normals import STENCILS
from scene_model.motion import Motion, motion_pose, motion_rates
from scene_model.shapes import primitives

from .dialects import GLSL
from .library import fill_template, load_library
from .parameters import ParameterBlock
from .sdf_code import sdf_functions


@dataclass(frozen=True)
class ShapeCode:
    """The shapes' part of the physics shader and the values of its parameter block.

    Attributes
    ----------
    source : str
        GLSL: the parameter block ``P``, the SDF building blocks used, the per-shape functions
        and the functions by shape index.
    parameters : (R, 4) float32 ndarray
        What ``P`` must hold (R >= 1); the poses of moving shapes at t = 0.
    pose_rows : dict of int to int
        For each shape that moves, by its index q: the first of its `POSE_ROWS` rows of ``P``,
        which `pose_rows` fills in for a time t.
    """
    source: str
    parameters: np.ndarray
    pose_rows: dict = field(default_factory=dict)


# The rows of a moving shape's pose in P, in order (`pose_rows`): the columns of R, pivot + s,
# the pivot, the angular velocity w (rad/s) and the shift's rate s' (m/s).
POSE_NAMES = ("ROTATION_X", "ROTATION_Y", "ROTATION_Z", "CENTRE", "PIVOT", "SPIN",
              "SHIFT_RATE")
POSE_ROWS = len(POSE_NAMES)


def pose_rows(motion: Motion, t: float) -> np.ndarray:
    """The `POSE_ROWS` rows (POSE_ROWS, 4) float32 of P that place a shape moved by ``motion``
    where it is at time ``t`` (s): R, s, w and s' computed in float64 (`motion_pose`,
    `motion_rates`), rounded once."""
    rotation, shift = motion_pose(motion, t)
    spin, shift_rate = motion_rates(motion, t)
    pivot = np.asarray(motion.pivot, np.float64)
    rows = np.zeros((POSE_ROWS, 4))
    rows[:, :3] = [rotation[:, 0], rotation[:, 1], rotation[:, 2], pivot + shift, pivot, spin,
                   shift_rate]
    return rows.astype(np.float32)


def shape_code(nodes, surfaces, lipschitz, normal_step, names=None,
               motions=None) -> ShapeCode:
    """The GLSL of Q static shapes, in the order the world lists them.

    Parameters
    ----------
    nodes : sequence of Q `scene_model.shapes.Node`
        The scene object each shape was built from (marchlab/colliders.py).
    surfaces : sequence of Q pairs of (K_q,) arrays
        Restitution and friction of each primitive of the node, in depth-first order (the
        object ids of `scene_model.shapes.primitives`).
    lipschitz, normal_step : sequence of Q floats
        `physics.colliders.Shape.lipschitz` and ``normal_step`` (m) of each shape.
    names : sequence of Q str, optional
        What the comments call each shape (``Shape.name``).
    motions : sequence of Q `scene_model.motion.Motion` or None, optional
        What moves each shape (``Shape.motion``); None (default) for a still one.
    """
    block = ParameterBlock()
    names = names or [f"shape {q}" for q in range(len(nodes))]
    used: set[str] = set()
    per_shape, surface_rows = [], []
    stencil = [", ".join(GLSL.literal(c) for c in k) for k in STENCILS["central"]]
    for q, node in enumerate(nodes):
        block.named({f"SHAPE{q}_LIPSCHITZ": ("x", lipschitz[q]),
                     f"SHAPE{q}_NORMAL_STEP": ("y", normal_step[q])})
        kind = node.kind or type(node).__name__
        source, node_used, _ = sdf_functions(
            node, block, f"shape_distance_{q}", f"shape_object_id_{q}",
            f"shape {q}, {names[q]} ({kind})")
        used |= node_used
        normal = fill_template("pipeline/normals.glsl", method="'central'", stencil=stencil,
                               function=f"shape_normal_{q}", sdf=f"shape_distance_{q}",
                               step=f"SHAPE{q}_NORMAL_STEP")
        per_shape.append(source + normal)
    for q, node in enumerate(nodes):
        restitution, friction = surfaces[q]
        count = len(list(primitives([node])))
        if len(restitution) != count or len(friction) != count:
            raise ValueError(f"shape {q} has {count} primitives but {len(restitution)} "
                             f"restitutions and {len(friction)} frictions")
        surface_rows.append(len(block.rows))
        for e, mu in zip(restitution, friction):
            block.row([e, mu])
    motions = motions or [None] * len(nodes)
    poses = {}
    for q, motion in enumerate(motions):
        if motion is not None:                  # the pose at t = 0, one named row each
            indices = [block.named({f"SHAPE{q}_{name}": ("xyz", value[:3])})
                       for name, value in zip(POSE_NAMES, pose_rows(motion, 0.0))]
            poses[q] = indices[0]
    rows = max(1, len(block.rows))
    head = ("// The shapes' numbers, one vec4 row each, as the renderer's parameter block\n"
            "// (gpu_shader/parameters.py): SDF parameters by row index, the named rows below,\n"
            "// and (restitution, friction) of each primitive.\n"
            f"layout(std140, binding = 0) uniform Parameters\n{{\n    vec4 P[{rows}];\n}};\n\n"
            + block.defines() + "\n" + CPU_ROUNDING)
    library = load_library("sdf").select(sorted(used)) if used else ""
    source = "\n".join([head, _banner("the SDF building blocks the shapes use (glsl/sdf.glsl)")
                        + library] + [_banner(f"shape {q}: {names[q]}") + text
                                      + (_pose_code(q, names[q]) if q in poses else "")
                                      for q, text in enumerate(per_shape)]
                       + [_banner("the shapes by index")
                          + _by_index(len(nodes), surface_rows, set(poses)),
                          "#undef dot\n#undef length\n"])
    return ShapeCode(source, block.values(np.float32), poses)


# The CPU computes a dot product as (a.x b.x + a.y b.y) + a.z b.z (scene_model.geometry.dot).
# llvmpipe's built-in dot() and length() group or fuse the products differently, so a quarter
# of their results are a rounding apart, and the finite-difference normals, which divide
# such differences by 2 h, differ by 1e-4. In the shapes' code (and only there: the macros
# are undefined after it) both are spelled as the CPU rounds them, as the OpenCL dialect
# spells normalize (gpu_shader/dialects.py); the generated SDF then equals the CPU's bit for
# bit on llvmpipe.
CPU_ROUNDING = """\
// dot and length rounded as the CPU rounds them (scene_model.geometry.dot).
#define dot(a, b) (((a).x * (b).x + (a).y * (b).y) + (a).z * (b).z)
#define length(v) sqrt(dot(v, v))
"""


def _pose_code(q: int, name: str) -> str:
    """``shape_local_q``, ``shape_turn_q`` and ``shape_velocity_q`` of moving shape q."""
    x, y, z, centre, pivot, spin, rate = (f"SHAPE{q}_{n}" for n in POSE_NAMES)
    return (
        f"\n// {name} moves (a kinematic object). Its pose where this step starts, which the\n"
        "// physics step writes into P before each step (physics_shapes.pose_rows):\n"
        f"// the columns of R ({x}, _Y, _Z), pivot + s ({centre}),\n"
        f"// the pivot ({pivot}), w ({spin}, rad/s) and s' ({rate}, m/s).\n\n"
        "// Shape.at (local): the point p of the world is the point R^T (p - pivot - s) + pivot\n"
        "// of the object as given (each component a dot product, rounded as on the CPU).\n"
        f"vec3 shape_local_{q}(vec3 p)\n{{\n"
        f"    vec3 d = p - {centre};\n"
        f"    vec3 turned = vec3(dot(d, {x}), dot(d, {y}),\n"
        f"                       dot(d, {z}));\n"
        f"    return turned + {pivot};\n}}\n\n"
        "// Shape.at: a normal n of the object as given, turned with it: R n.\n"
        f"vec3 shape_turn_{q}(vec3 n)\n{{\n"
        f"    return ({x} * n.x + {y} * n.y) + {z} * n.z;\n}}\n\n"
        "// motion_velocity: the velocity of its point now at p, w x (p - pivot - s) + s'.\n"
        f"vec3 shape_velocity_{q}(vec3 p)\n{{\n"
        f"    vec3 w = {spin}, arm = p - {centre};\n"
        "    return vec3(w.y * arm.z - w.z * arm.y, w.z * arm.x - w.x * arm.z,\n"
        f"                w.x * arm.y - w.y * arm.x) + {rate};\n}}\n\n")


def _by_index(count: int, surface_rows: list[int], moving=frozenset()) -> str:
    """``shape_distance(shape, p)`` and its siblings: a branch per shape; a ``moving`` shape's
    point goes through ``shape_local_q`` and its normal through ``shape_turn_q``."""
    def cases(call):
        return "".join(f"    if (shape == {q}) return {call(q)};\n" for q in range(count))

    def at(q):              # the point p on shape q as given
        return f"shape_local_{q}(p)" if q in moving else "p"

    def turned(q, normal):
        return f"shape_turn_{q}({normal})" if q in moving else normal

    velocities = "".join(f"    if (shape == {q}) return shape_velocity_{q}(p);\n"
                         for q in sorted(moving))
    return (
        "// Shape.distance of shape `shape` at p.\n"
        "real shape_distance(int shape, vec3 p)\n{\n"
        + cases(lambda q: f"shape_distance_{q}({at(q)})") + "    return 0.0;\n}\n\n"
        "// Shape.normal: the unit gradient, zero where it vanishes.\n"
        "vec3 shape_normal(int shape, vec3 p)\n{\n"
        + cases(lambda q: turned(q, f"shape_normal_{q}({at(q)})"))
        + "    return vec3(0.0);\n}\n\n"
        "// Shape.coefficients: (restitution, friction) of the material of the primitive the\n"
        "// SDF picks at p, read by object id from the rows after the shape's first.\n"
        "vec2 shape_surface(int shape, vec3 p)\n{\n"
        + cases(lambda q: f"P[{surface_rows[q]} + shape_object_id_{q}({at(q)})].xy")
        + "    return vec2(0.0);\n}\n\n"
        "// Shape.surface_velocity: the velocity of the surface at p (m/s), 0 if it is still.\n"
        "vec3 shape_velocity(int shape, vec3 p)\n{\n"
        + velocities + "    return vec3(0.0);\n}\n\n"
        "// Shape.lipschitz: L with |d(p) - d(q)| <= L |p - q|.\n"
        "real shape_lipschitz(int shape)\n{\n"
        + cases(lambda q: f"SHAPE{q}_LIPSCHITZ") + "    return 1.0;\n}\n\n"
        "// Shape.normal_step: the finite-difference step of the normal (m).\n"
        "real shape_normal_step(int shape)\n{\n"
        + cases(lambda q: f"SHAPE{q}_NORMAL_STEP") + "    return 0.0;\n}\n")


def _banner(title: str) -> str:
    return f"// ---- {title} " + "-" * max(4, 86 - len(title)) + "\n\n"

