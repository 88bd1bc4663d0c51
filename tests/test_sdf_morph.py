"""The morph node: d = (1 - t) d0 + t d1, a 1-Lipschitz bound that the march never skips.

scene_model.shapes.Morph and reference_cpu.sdf.op_morph. At t = 0 and t = 1 the morph is its
first and its second child exactly; at t = 1/2 it is their mean. Its object id is the first
child's up to t = 1/2 and the second's above, at every point. For t in [0, 1] the mix of two
1-Lipschitz distances is 1-Lipschitz (checked with hypothesis in tests/test_sdf_lipschitz.py),
so |d(p)| never exceeds the distance from p to the surface d = 0 and a ray marched on it stops
at or before the first root of the field along it: checked here against roots found by dense
sampling and bisection. Beyond [0, 1] the constant is |1 - t| + |t| > 1, which is why the
node refuses such t (docs/sphere-tracing.md, "Morph").
"""

from __future__ import annotations

import numpy as np
import pytest
from sdf_reference import first_roots

from reference_cpu import sdf as S
from reference_cpu.march import march
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import box, capsule, sphere, torus
from scene_model.errors import SceneError
from scene_model.shapes import Morph

PAIRS = {
    "sphere-box": (sphere(0.6), box(0.45).rotate(0, 30, 20).at(0.3, 0.1, 0.0)),
    "torus-capsule": (torus(0.6, 0.2).rotate(70, 0, 0), capsule((-0.5, 0, 0), (0.5, 0.4, 0), 0.3)),
    "apart": (sphere(0.5).at(-0.8, 0, 0), box(0.4).at(0.8, 0, 0)),
}
DTYPES = [np.float64, np.float32]


def points(seed, n=20_000):
    """(n, 3) float64: random points in [-2, 2]^3, and points near the shapes' surfaces."""
    rng = np.random.default_rng(seed)
    return np.concatenate([rng.uniform(-2, 2, (n, 3)), rng.normal(scale=0.5, size=(n, 3))])


def field(node, dtype=np.float64, with_ids=False):
    sdf = build_scene_sdf([node], dtype, with_ids=with_ids)
    return lambda p: sdf(p.astype(dtype))


# --- The formula ---------------------------------------------------------------------------

@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("pair", PAIRS, ids=list(PAIRS))
def test_morph_at_t_0_and_1_is_exactly_its_first_and_second_child(pair, dtype):
    first, second = PAIRS[pair]
    p = points(1)
    np.testing.assert_array_equal(field(Morph((first, second), 0.0), dtype)(p)[0],
                                  field(first, dtype)(p)[0], strict=True)
    np.testing.assert_array_equal(field(Morph((first, second), 1.0), dtype)(p)[0],
                                  field(second, dtype)(p)[0], strict=True)


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("pair", PAIRS, ids=list(PAIRS))
def test_morph_at_one_half_is_the_mean_of_the_two_distances_exactly(pair, dtype):
    """(1 - 1/2) d0 + d1 / 2 rounds once, as (d0 + d1) / 2 does: the same float."""
    first, second = PAIRS[pair]
    p = points(2)
    d0, d1 = field(first, dtype)(p)[0], field(second, dtype)(p)[0]
    np.testing.assert_array_equal(field(Morph((first, second), 0.5), dtype)(p)[0],
                                  (d0 + d1) / dtype(2), strict=True)


def test_op_morph_is_the_convex_combination_within_an_ulp():
    rng = np.random.default_rng(3)
    d1, d2, t = rng.normal(size=(3, 10_000))
    t = np.abs(t) % 1.0
    exact = np.array([float((1 - a) * b + a * c) for a, b, c in zip(t, d1, d2)])
    np.testing.assert_allclose(S.op_morph(d1, d2, t), exact, rtol=0, atol=1e-15)


# --- Object ids --------------------------------------------------------------------------

@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("t, expected", [(0.0, 0), (0.25, 0), (0.5, 0), (0.5000001, 1),
                                         (0.75, 1), (1.0, 1)])
def test_object_id_is_the_first_childs_up_to_one_half_then_the_seconds_everywhere(t, expected,
                                                                                  dtype):
    """The weight 1 - t of the first child is at least t's up to t = 1/2 (ties go to the first
    child, as in a union). One id for the whole shape: its material does not flicker."""
    first, second = PAIRS["sphere-box"]
    ids = field(Morph((first, second), t), dtype, with_ids=True)(points(4))[1]
    assert set(np.unique(ids)) == {expected}


def test_a_morph_takes_the_ids_of_its_primitives_depth_first():
    """Ids inside a morph continue depth first: a union of two spheres as the first child holds
    ids 0 and 1 (each where its sphere is nearer), the box, second, id 2."""
    pair = (sphere(0.4).at(-0.3, 0, 0) | sphere(0.4).at(0.3, 0, 0), box(0.5))
    p = np.array([[-0.35, 0.1, 0.0], [0.35, -0.1, 0.0]])
    assert field(Morph(pair, 0.25), with_ids=True)(p)[1].tolist() == [0, 1]
    assert field(Morph(pair, 0.75), with_ids=True)(p)[1].tolist() == [2, 2]


# --- Why t stays in [0, 1] ----------------------------------------------------------------

@pytest.mark.parametrize("t", [2.0, -1.0])
def test_beyond_0_and_1_the_mix_stretches_distances_by_abs_1_minus_t_plus_abs_t(t):
    """Two unit spheres 3 apart: between them the two gradients point opposite ways, so
    (1 - t) d0 + t d1 changes |1 - t| + |t| = 3 times as fast as the point moves. A march on
    it would step three times too far; the node refuses such t."""
    d0 = lambda p: S.sdf_sphere(p - [-1.5, 0, 0], 1.0)            # noqa: E731
    d1 = lambda p: S.sdf_sphere(p - [1.5, 0, 0], 1.0)             # noqa: E731
    x = np.linspace(-1.4, 1.4, 1001)
    p = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)
    values = S.op_morph(d0(p), d1(p), t)
    quotient = np.abs(np.diff(values)) / np.diff(x)
    np.testing.assert_allclose(quotient, abs(1 - t) + abs(t), rtol=1e-9)
    with pytest.raises(SceneError, match=r"^t: must be between 0 and 1 \(got "):
        Morph((sphere(), box()), t)


def test_a_morph_of_two_shapes_apart_vanishes_midway_rather_than_sliding_across():
    """A morph blends distances, not positions. For shapes a gap g apart, d0 + d1 >= g at every
    point (a path from p to the second shape first leaves the first, then crosses the gap), so
    at t = 1/2 the field is at least g / 2 > 0: no surface at all. Here g = 0.7 along x."""
    node = Morph(PAIRS["apart"], 0.5)
    p = points(7)
    assert field(node)(p)[0].min() >= 0.35 - 1e-12
    assert field(node)(np.array([[0.05, 0.0, 0.0]]))[0][0] == pytest.approx(0.35, abs=1e-12)


@pytest.mark.parametrize("count", [1, 3])
def test_a_morph_refuses_other_than_two_children(count):
    with pytest.raises(SceneError) as caught:
        Morph(tuple(sphere() for _ in range(count)), 0.5)
    assert str(caught.value) == f"children: must have exactly 2 children (got {count})"


# --- The march never skips the surface -----------------------------------------------------

EPSILON = 1e-3
REACH = 8.0                  # rays are sampled over [0, REACH]
SAMPLES = 4000
DELTA = REACH / SAMPLES


@pytest.mark.parametrize("mode, omega", [("none", 1.0), ("fixed", 1.9), ("auto", 1.0)])
@pytest.mark.parametrize("t", [0.3, 0.5, 0.8])
@pytest.mark.parametrize("pair", ["sphere-box", "torus-capsule"])
@pytest.mark.parametrize("dtype", DTYPES)
def test_march_stops_at_or_before_the_first_root_of_a_morph(pair, t, mode, omega, dtype):
    """Hit iff the ray has a root, outside a tangent band of rays whose least sampled value is
    within DELTA / 2 + 2 epsilon of 0; never past the root; the field below epsilon where the
    ray stopped."""
    node = Morph(PAIRS[pair], t)
    f = field(node)
    rng = np.random.default_rng(6)
    n = 500
    origins = rng.normal(size=(n, 3))
    origins = 4.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True)
    aim = rng.uniform(-1.2, 1.2, (n, 3))
    directions = aim - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    sdf = build_scene_sdf([node], dtype)
    t_hit, _, hit = march(origins.astype(dtype), directions.astype(dtype), sdf, 2000, EPSILON,
                          REACH, relaxation=mode, omega=omega)
    root, lowest = first_roots(f, origins, directions, REACH, SAMPLES)
    band = np.abs(lowest) < DELTA / 2 + 2 * EPSILON
    has_root = np.isfinite(root)
    assert has_root.sum() >= 50 and (~has_root).sum() >= 50 and band.sum() <= 25
    wrong = (hit != has_root) & ~band
    assert not wrong.any(), f"{wrong.sum()} rays: least sampled values {lowest[wrong][:5]}"
    slack = 1e-9 if dtype == np.float64 else 4e-6
    both = hit & has_root
    assert np.all(t_hit[both] <= root[both] + slack), "a ray stopped past the first root"
    stopped = f(origins[hit] + t_hit[hit, None].astype(np.float64) * directions[hit])[0]
    assert np.all(np.abs(stopped) < EPSILON + slack)
