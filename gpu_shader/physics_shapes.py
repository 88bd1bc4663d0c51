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
the primitive's material, as marchlab/colliders.py gives them to the CPU) and
``shape_lipschitz``, ``shape_normal_step``. The numbers (the tree's parameters, the
coefficients, L and the finite-difference step) are rows of a parameter block ``P``, as in the
renderer, so the text depends only on the trees' shapes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reference_cpu.normals import STENCILS
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
        What ``P`` must hold (R >= 1).
    """
    source: str
    parameters: np.ndarray


def shape_code(nodes, surfaces, lipschitz, normal_step, names=None) -> ShapeCode:
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
    rows = max(1, len(block.rows))
    head = ("// The shapes' numbers, one vec4 row each, as the renderer's parameter block\n"
            "// (gpu_shader/parameters.py): SDF parameters by row index, the named rows below,\n"
            "// and (restitution, friction) of each primitive.\n"
            f"layout(std140, binding = 0) uniform Parameters\n{{\n    vec4 P[{rows}];\n}};\n\n"
            + block.defines() + "\n" + CPU_ROUNDING)
    library = load_library("sdf").select(sorted(used)) if used else ""
    source = "\n".join([head, _banner("the SDF building blocks the shapes use (glsl/sdf.glsl)")
                        + library] + [_banner(f"shape {q}: {names[q]}") + text
                                      for q, text in enumerate(per_shape)]
                       + [_banner("the shapes by index") + _by_index(len(nodes), surface_rows),
                          "#undef dot\n#undef length\n"])
    return ShapeCode(source, block.values(np.float32))


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


def _by_index(count: int, surface_rows: list[int]) -> str:
    """``shape_distance(shape, p)`` and its siblings: a branch per shape."""
    def cases(call):
        return "".join(f"    if (shape == {q}) return {call(q)};\n" for q in range(count))
    return (
        "// Shape.distance of shape `shape` at p.\n"
        "real shape_distance(int shape, vec3 p)\n{\n"
        + cases(lambda q: f"shape_distance_{q}(p)") + "    return 0.0;\n}\n\n"
        "// Shape.normal: the unit gradient, zero where it vanishes.\n"
        "vec3 shape_normal(int shape, vec3 p)\n{\n"
        + cases(lambda q: f"shape_normal_{q}(p)") + "    return vec3(0.0);\n}\n\n"
        "// Shape.coefficients: (restitution, friction) of the material of the primitive the\n"
        "// SDF picks at p, read by object id from the rows after the shape's first.\n"
        "vec2 shape_surface(int shape, vec3 p)\n{\n"
        + cases(lambda q: f"P[{surface_rows[q]} + shape_object_id_{q}(p)].xy")
        + "    return vec2(0.0);\n}\n\n"
        "// Shape.lipschitz: L with |d(p) - d(q)| <= L |p - q|.\n"
        "real shape_lipschitz(int shape)\n{\n"
        + cases(lambda q: f"SHAPE{q}_LIPSCHITZ") + "    return 1.0;\n}\n\n"
        "// Shape.normal_step: the finite-difference step of the normal (m).\n"
        "real shape_normal_step(int shape)\n{\n"
        + cases(lambda q: f"SHAPE{q}_NORMAL_STEP") + "    return 0.0;\n}\n")


def _banner(title: str) -> str:
    return f"// ---- {title} " + "-" * max(4, 86 - len(title)) + "\n\n"

