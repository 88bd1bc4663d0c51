"""The exact SDFs are 1-Lipschitz: |f(p) - f(q)| <= |p - q|, checked with hypothesis.

Sphere tracing steps a ray forward by f(p); that is safe only if no surface is nearer than f(p),
which for an exact distance follows from |f(p) - f(q)| <= |p - q|. Every exact primitive, the
hard CSG operators over them (min and max of 1-Lipschitz functions are 1-Lipschitz), the morph
(a mix with weights 1 - t and t, both >= 0 and summing to 1) and the rigid and uniform-scale
transforms must keep this property. (The morph is not an exact distance, only a bound; what
it promises beyond this one is tested in test_sdf_morph.py.)

The smooth operators are left out on purpose. Inside the blend they are not the distance to the
blended surface, only a bound on it, and the toolkit promises no more than that (sdf.py says
"a bound, not an exact distance"); what they do promise -- equal to the hard operator where the
two distances differ by at least k, and at most k / 4 away from it -- is tested in
test_sdf_csg.py. (Quilez's polynomial smooth minimum happens to be 1-Lipschitz as well:
its gradient h grad d1 + (1 - h) grad d2 is a convex combination. That is a further claim, not
made here.)

Each hypothesis example checks a segment drawn by hypothesis (which it can shrink to a small
counterexample): its two ends, and the consecutive points of a fine walk along it, which catches
a jump of the field wherever the segment crosses one; and a batch of pairs, near and far, from a
seeded generator it also draws, to cover more of space per example.
"""

from __future__ import annotations

import numpy as np
from hypothesis import assume, given
from hypothesis import strategies as st

from reference_cpu import sdf as S
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Plane,
                                Pyramid, RoundBox, Sphere, Torus)

RELATIVE, ABSOLUTE = 1e-9, 1e-12    # slack for rounding: |f(p) - f(q)| <= |p - q| (1 + 1e-9) + 1e-12

coordinate = st.floats(-4, 4, allow_nan=False, allow_infinity=False)
point = st.tuples(coordinate, coordinate, coordinate)
length = st.floats(0.05, 3.0)                     # radii, half-sizes, heights
angle = st.floats(-180, 180)
nonzero_vector = point.filter(lambda v: np.linalg.norm(v) > 1e-3)


@st.composite
def point_pairs(draw, walk_steps=1024, batch=64):
    """(p, q) : two (N, 3) float64 arrays of pairs of points to compare.

    Hypothesis draws a segment from p0 to q0: q0 anywhere in [-4, 4]^3, or p0 plus a step of
    1e-6 to 1 along a drawn direction. The pairs are p0 and q0 themselves, the consecutive
    points of a walk of ``walk_steps`` equal steps from p0 to q0 (so that a jump of the field
    anywhere the segment crosses is caught), and ``batch`` pairs from a drawn seed: p uniform in
    [-4, 4]^3, q = p plus a Gaussian step whose size spans 1e-6 to 3.
    """
    p0 = np.array(draw(point))
    if draw(st.booleans()):
        q0 = np.array(draw(point))
    else:
        direction = np.array(draw(nonzero_vector))
        q0 = p0 + draw(st.floats(1e-6, 1.0)) * direction / np.linalg.norm(direction)
    walk = p0 + np.linspace(0.0, 1.0, walk_steps + 1)[:, None] * (q0 - p0)
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    p = rng.uniform(-4, 4, (batch, 3))
    q = p + rng.normal(size=(batch, 3)) * 10 ** rng.uniform(-6, 0.5, (batch, 1))
    return np.vstack([p0, walk[:-1], p]), np.vstack([q0, walk[1:], q])


def assert_1_lipschitz(f, p, q):
    """|f(p) - f(q)| <= |p - q| (1 + 1e-9) + 1e-12 for every row; f maps (N, 3) to (N,)."""
    change = np.abs(f(p) - f(q))
    allowed = np.linalg.norm(p - q, axis=-1) * (1 + RELATIVE) + ABSOLUTE
    worst = np.argmax(change - allowed)
    assert change[worst] <= allowed[worst], (
        f"|f(p) - f(q)| = {change[worst]!r} > |p - q| (1 + 1e-9) + 1e-12 = {allowed[worst]!r} "
        f"at p = {p[worst].tolist()}, q = {q[worst].tolist()}")


def scene(node):
    """The distance function of a one-node scene, in float64."""
    sdf = build_scene_sdf([node])
    return lambda p: sdf(p)[0]


# --- Primitives ------------------------------------------------------------------------------------
# Each primitive is the Node that build_scene_sdf evaluates; a Node checks its parameters (the
# round box's radius at most its smallest half-size, a capsule's ends distinct).

@st.composite
def primitives(draw):
    """Any exact primitive with parameters in sensible positive ranges."""
    kind = draw(st.sampled_from(["sphere", "box", "round_box", "plane", "torus",
                                 "capped_cylinder", "capsule", "cone", "pyramid", "disk",
                                 "hex_prism"]))
    if kind == "sphere":
        return Sphere(draw(length))
    if kind == "box":
        return Box((draw(length), draw(length), draw(length)))
    if kind == "round_box":
        half = (draw(length), draw(length), draw(length))
        return RoundBox(half, draw(st.floats(0.01, 1.0)) * min(half))
    if kind == "plane":
        return Plane(draw(nonzero_vector), draw(st.floats(-3, 3)))
    if kind == "torus":
        return Torus(draw(length), draw(length))
    if kind == "capped_cylinder":
        return CappedCylinder(draw(length), draw(length))
    if kind == "capsule":
        a = draw(point)
        b = draw(point.filter(lambda b: np.linalg.norm(np.subtract(a, b)) > 1e-3))
        return Capsule(a, b, draw(length))
    if kind == "pyramid":
        return Pyramid(draw(length), draw(length))
    if kind == "disk":
        radius = draw(length)
        return Disk(radius, draw(st.floats(0.01, 1.0)) * 2 * radius)
    if kind == "hex_prism":
        return HexPrism(draw(length), draw(length))
    return Cone(draw(length), draw(length))


@given(shape=primitives(), pairs=point_pairs())
def test_every_exact_primitive_is_1_lipschitz(shape, pairs):
    assert_1_lipschitz(scene(shape), *pairs)


# The primitives once more, called directly from reference_cpu/sdf.py (no scene tree in between),
# one test each so that a failure names the formula.

@given(radius=length, pairs=point_pairs())
def test_sdf_sphere_is_1_lipschitz(radius, pairs):
    assert_1_lipschitz(lambda p: S.sdf_sphere(p, radius), *pairs)


@given(half=st.tuples(length, length, length), pairs=point_pairs())
def test_sdf_box_is_1_lipschitz(half, pairs):
    assert_1_lipschitz(lambda p: S.sdf_box(p, np.array(half)), *pairs)


@given(half=st.tuples(length, length, length), fraction=st.floats(0, 1), pairs=point_pairs())
def test_sdf_round_box_is_1_lipschitz(half, fraction, pairs):
    radius = fraction * min(half)
    assert_1_lipschitz(lambda p: S.sdf_round_box(p, np.array(half), radius), *pairs)


@given(normal=nonzero_vector, offset=st.floats(-3, 3), pairs=point_pairs())
def test_sdf_plane_is_1_lipschitz(normal, offset, pairs):
    assert_1_lipschitz(lambda p: S.sdf_plane(p, np.array(normal), offset), *pairs)


@given(major=length, minor=length, pairs=point_pairs())
def test_sdf_torus_is_1_lipschitz(major, minor, pairs):
    assert_1_lipschitz(lambda p: S.sdf_torus(p, major, minor), *pairs)


@given(radius=length, half_height=length, pairs=point_pairs())
def test_sdf_capped_cylinder_is_1_lipschitz(radius, half_height, pairs):
    assert_1_lipschitz(lambda p: S.sdf_capped_cylinder(p, radius, half_height), *pairs)


@given(a=point, b=point, radius=length, pairs=point_pairs())
def test_sdf_capsule_is_1_lipschitz(a, b, radius, pairs):
    a, b = np.array(a), np.array(b)
    assume(np.linalg.norm(b - a) > 1e-3)     # a == b is a sphere; Capsule rejects it
    assert_1_lipschitz(lambda p: S.sdf_capsule(p, a, b, radius), *pairs)


@given(radius=length, height=length, pairs=point_pairs())
def test_sdf_cone_is_1_lipschitz(radius, height, pairs):
    assert_1_lipschitz(lambda p: S.sdf_cone(p, radius, height), *pairs)


@given(base=length, height=length, pairs=point_pairs())
def test_sdf_pyramid_is_1_lipschitz(base, height, pairs):
    assert_1_lipschitz(lambda p: S.sdf_pyramid(p, base, height), *pairs)


@given(radius=length, fraction=st.floats(0, 1), pairs=point_pairs())
def test_sdf_disk_is_1_lipschitz(radius, fraction, pairs):
    assert_1_lipschitz(lambda p: S.sdf_disk(p, radius, fraction * 2 * radius), *pairs)


@given(apothem=length, half_length=length, pairs=point_pairs())
def test_sdf_hex_prism_is_1_lipschitz(apothem, half_length, pairs):
    assert_1_lipschitz(lambda p: S.sdf_hex_prism(p, apothem, half_length), *pairs)


# --- Hard CSG: min and max of 1-Lipschitz functions are 1-Lipschitz ------------------------------
# Primitives are centred on the origin; the second is moved by a drawn offset so that the two
# overlap in varied ways.

@given(a=primitives(), b=primitives(), offset=point, pairs=point_pairs())
def test_union_of_exact_primitives_is_1_lipschitz(a, b, offset, pairs):
    fa, fb = scene(a), scene(b.at(*offset))
    assert_1_lipschitz(lambda p: S.op_union(fa(p), fb(p)), *pairs)


@given(a=primitives(), b=primitives(), offset=point, pairs=point_pairs())
def test_intersection_of_exact_primitives_is_1_lipschitz(a, b, offset, pairs):
    fa, fb = scene(a), scene(b.at(*offset))
    assert_1_lipschitz(lambda p: S.op_intersection(fa(p), fb(p)), *pairs)


@given(a=primitives(), b=primitives(), offset=point, pairs=point_pairs())
def test_subtraction_of_exact_primitives_is_1_lipschitz(a, b, offset, pairs):
    fa, fb = scene(a), scene(b.at(*offset))
    assert_1_lipschitz(lambda p: S.op_subtraction(fa(p), fb(p)), *pairs)


@given(a=primitives(), b=primitives(), c=primitives(), offset=point, pairs=point_pairs())
def test_csg_tree_built_with_operators_is_1_lipschitz(a, b, c, offset, pairs):
    """(a | b.at(offset)) & c - b: the same operators through scene_model.shapes and the scene."""
    assert_1_lipschitz(scene(((a | b.at(*offset)) & c) - b), *pairs)


# --- Morph: |(1 - t)(a(p) - a(q)) + t (b(p) - b(q))| <= (1 - t)|p - q| + t |p - q| --------------

@given(a=primitives(), b=primitives(), offset=point, t=st.floats(0, 1), pairs=point_pairs())
def test_morph_of_exact_primitives_is_1_lipschitz(a, b, offset, t, pairs):
    assert_1_lipschitz(scene(a.morph(b.at(*offset), t)), *pairs)


# --- Transforms: rigid motions and uniform scale keep the Lipschitz constant ---------------------

@given(shape=primitives(), offset=point, pairs=point_pairs())
def test_translated_primitive_is_1_lipschitz(shape, offset, pairs):
    assert_1_lipschitz(scene(shape.at(*offset)), *pairs)


@given(shape=primitives(), angles=st.tuples(angle, angle, angle), pairs=point_pairs())
def test_rotated_primitive_is_1_lipschitz(shape, angles, pairs):
    assert_1_lipschitz(scene(shape.rotate(*angles)), *pairs)


@given(shape=primitives(), factor=st.floats(0.1, 10.0), pairs=point_pairs())
def test_uniformly_scaled_primitive_is_1_lipschitz(shape, factor, pairs):
    """s f(p / s) has the Lipschitz constant of f: the distance is multiplied back by s."""
    assert_1_lipschitz(scene(shape.scale(factor)), *pairs)


@given(shape=primitives(), factor=st.floats(0.1, 10.0), angles=st.tuples(angle, angle, angle),
       offset=point, pairs=point_pairs())
def test_scaled_rotated_translated_primitive_is_1_lipschitz(shape, factor, angles, offset, pairs):
    assert_1_lipschitz(scene(shape.scale(factor).rotate(*angles).at(*offset)), *pairs)
