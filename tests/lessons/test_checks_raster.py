"""The self-checks of lesson 09's exercises (marchlab.check.raster).

As for every graphics check: marchlab's own function passes; a plausibly wrong one (a flipped
cross product, affine interpolation, unsigned areas...) fails with its likely cause; one that
raises or is still a template fails without the check raising. And the functions the checks
compare with are the right ones: the ray caster's attribute is the rasteriser's
perspective-correct weighting, pixel by pixel.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import check
from marchlab.check import graphics, physics, raster
from marchlab.check.raster import (_areas, _direction_cases, _edge_cases, _faces,
                                   _triangle_cases, ray_cast_attribute, reference_cube_face)
from reference_cpu.rasterise import SUBPIXELS, draw_triangle, edge
from reference_cpu.truth.mesh_cast import barycentric

REFERENCES = {"edge_function": edge, "perspective_correct": ray_cast_attribute,
              "barycentric": barycentric, "cube_face": reference_cube_face}
PAIRED = lambda axis, negative: 2 * axis + negative    # noqa: E731  (the faces' numbering)


def affine(w, z, a):
    return np.einsum("ni,nia->na", w, a)


def over(w, z, a, power=1, normalise=True):
    """sum w a / z^power, divided by sum w / z^power when ``normalise``."""
    top = np.einsum("ni,nia->na", w / z ** power, a)
    return top / (w / z ** power).sum(axis=1)[:, None] if normalise else top


# (check, a plausible wrong answer, words the verdict must contain)
WRONG = [
    ("edge_function", lambda ax, ay, bx, by, px, py: (px - ax) * (by - ay) - (py - ay) * (bx - ax),
     "the sign is flipped"),
    ("edge_function", lambda ax, ay, bx, by, px, py: (bx - ax) * (py - ay) + (by - ay) * (px - ax),
     "a 2D cross product subtracts"),
    ("edge_function", lambda ax, ay, bx, by, px, py: (bx - ax) * (px - ax) + (by - ay) * (py - ay),
     "that is the dot product"),
    ("edge_function", lambda ax, ay, bx, by, px, py: edge(ax, ay, bx, by, px, py)
     / np.hypot(bx - ax, by - ay), "no division by the edge's length"),
    ("perspective_correct", affine, "affine interpolation"),
    ("perspective_correct", lambda w, z, a: over(w, z, a, power=-1), "do not multiply"),
    ("perspective_correct", lambda w, z, a: over(w, z, a, normalise=False),
     "divide it by sum b_i / z_i"),
    ("perspective_correct", lambda w, z, a: over(w, z, a, normalise=False)
     * (w * z).sum(axis=1)[:, None], "not sum b_i z_i"),
    ("perspective_correct", lambda w, z, a: over(w, z, a, power=2), "divide by z once"),
    ("barycentric", lambda p, a, b, c: _areas(p, a, b, c, signed=False), "lost their sign"),
    ("barycentric", lambda p, a, b, c: _areas(p, a, b, c)[:, [1, 2, 0]], "(w_b, w_c, w_a)"),
    ("barycentric", lambda p, a, b, c: _areas(p, a, b, c)[:, [2, 0, 1]], "(w_c, w_a, w_b)"),
    ("barycentric", lambda p, a, b, c: _areas(p, a, b, c, total=np.ones(len(p))),
     "divide by the area of the whole triangle"),
    ("barycentric", lambda p, a, b, c: _areas(p, a, b, c) / 2, "measured the same way"),
    ("cube_face", lambda d: _faces(d, PAIRED, signed_axis=True), "not their signed values"),
    ("cube_face", lambda d: _faces(d, PAIRED, largest=False), "not the smallest"),
    ("cube_face", lambda d: _faces(d, PAIRED, negative_even=True), "(+x is face 0)"),
    ("cube_face", lambda d: _faces(d, lambda axis, negative: axis + 3 * negative),
     "yours are numbered +x, +y, +z, -x, -y, -z"),
]


def run(name, function, capsys=None):
    """Run one check; with capsys, also assert that it printed exactly its message."""
    result = getattr(check, name)(function)
    if capsys is not None:
        assert capsys.readouterr().out == result.message + "\n"
    return result


def test_every_raster_check_is_exported_tested_and_named_once():
    assert set(raster.__all__) == set(REFERENCES) == {name for name, _, _ in WRONG}
    for name in raster.__all__:
        assert getattr(check, name) is getattr(raster, name)
    assert not set(raster.__all__) & (set(graphics.__all__) | set(physics.__all__))


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_reference_function_passes_its_own_check(name, capsys):
    result = run(name, REFERENCES[name], capsys)
    assert result.passed and bool(result)
    assert result.samples >= 500
    assert result.max_error == 0.0              # the same function on the same inputs
    assert result.message.startswith(f"{name}: passed.")


@pytest.mark.parametrize("name, wrong, cause", WRONG, ids=[w[0] for w in WRONG])
def test_plausible_mistake_fails_with_its_likely_cause(name, wrong, cause, capsys):
    result = run(name, wrong, capsys)
    assert not result.passed and not bool(result)
    flat = " ".join(result.message.split())
    assert flat.startswith(f"{name}: not yet. For ")           # the first bad input, quoted
    assert "Likely cause" in flat and cause in flat, flat


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_a_function_that_raises_is_reported_not_raised(name, capsys):
    def broken(*args):
        raise ValueError("operands could not be broadcast")

    result = run(name, broken, capsys)
    assert not result.passed
    assert "raised ValueError: operands could not be broadcast" in " ".join(result.message.split())


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_an_exercise_template_gets_a_not_yet_message(name, capsys):
    def template(*args):
        raise NotImplementedError("write it here")

    result = run(name, template, capsys)
    assert result.message.startswith(f"{name}: not yet. Your function still raises "
                                     "NotImplementedError")


def test_correct_rewrites_pass_within_the_tolerance():
    """The same answers reached another way: the cross product as u^T J v (J a quarter
    turn), the depth first and then the attribute, and two weights by least squares."""
    def edge_cross(ax, ay, bx, by, px, py):
        u, v = np.stack([bx - ax, by - ay], -1), np.stack([px - ax, py - ay], -1)
        return np.einsum("ni,ij,nj->n", u, np.array([[0, 1], [-1, 0]]), v)   # u^T J v

    def depth_first(weights, z, attributes):
        depth = 1 / np.sum(weights / z, axis=1)
        return depth[:, None] * np.einsum("ni,nia->na", weights / z, attributes)

    def solved(p, a, b, c):
        # p - a = w_b (b - a) + w_c (c - a): two unknowns, three equations (consistent).
        m = np.stack([b - a, c - a], axis=-1)                     # (N, 3, 2)
        w_bc = np.array([np.linalg.lstsq(m[i], (p - a)[i], rcond=None)[0]
                         for i in range(len(p))])
        return np.column_stack([1 - w_bc.sum(axis=1), w_bc])

    def by_comparisons(d):
        # The face by comparing sizes two at a time, and the sign by a choice: no argmax.
        x, y, z = np.abs(d).T
        axis = np.where((x >= y) & (x >= z), 0, np.where(y >= z, 1, 2))
        return np.choose(axis, [np.where(d[:, 0] < 0, 1, 0), np.where(d[:, 1] < 0, 3, 2),
                                np.where(d[:, 2] < 0, 5, 4)])

    for name, function in (("edge_function", edge_cross), ("perspective_correct", depth_first),
                           ("barycentric", solved), ("cube_face", by_comparisons)):
        result = run(name, function)
        assert result.passed and result.max_error <= graphics.TOLERANCE, name


@pytest.mark.parametrize("corners, z", [
    ([[10.3, 4.1], [70.8, 30.2], [22.5, 55.9]], [1.0, 9.0, 3.0]),
    ([[3.0, 60.0], [90.2, 58.7], [40.1, 2.2]], [0.3, 0.3, 40.0]),
])
def test_ray_cast_attribute_is_the_rasterisers_perspective_correct_weighting(corners, z):
    """On every pixel a triangle covers, the check's reference fed with the pixel centre's
    image barycentrics and the corners' depths gives the rasteriser's own weights
    (`draw_triangle`) to 1e-12: the check judges the formula the rasteriser uses."""
    image, z = np.array(corners), np.array(z)
    (x0, y0), inside, weights = draw_triangle(image, z)
    rows, cols = np.nonzero(inside)
    x, y = cols + x0 + 0.5, rows + y0 + 0.5
    (ax, ay), (bx, by), (cx, cy) = image
    area = edge(ax, ay, bx, by, cx, cy)
    screen = np.stack([edge(bx, by, cx, cy, x, y), edge(cx, cy, ax, ay, x, y),
                       edge(ax, ay, bx, by, x, y)], axis=-1) / area
    n = len(rows)
    assert n > 500
    found = ray_cast_attribute(screen, np.tile(z, (n, 1)), np.tile(np.eye(3), (n, 1, 1)))
    np.testing.assert_allclose(found, weights[inside], rtol=0, atol=1e-12)


def test_ray_cast_attribute_is_affine_when_the_depths_are_equal():
    rng = np.random.default_rng(3)
    w = rng.dirichlet(np.ones(3), 200)
    a = rng.normal(size=(200, 3, 2))
    z = np.full((200, 3), 4.2)
    np.testing.assert_allclose(ray_cast_attribute(w, z, a), affine(w, z, a), atol=1e-13)


def test_edge_cases_include_points_on_the_edge_and_the_rasterisers_integers():
    """A quarter of the points lie on their edge's line (where the top-left rule decides),
    and half the parameter sets are in fixed point, as `draw_triangle` evaluates them."""
    case = _edge_cases(np.random.default_rng(0))
    values = edge(*case)
    scale = np.hypot(case[2] - case[0], case[3] - case[1]) ** 2
    assert np.sum(np.abs(values) <= 1e-9 * scale) >= len(values) // 4
    fixed = raster._fixed_point(case)
    assert all(v.dtype == np.int64 for v in fixed)
    np.testing.assert_array_equal(fixed[0], np.round(case[0] * SUBPIXELS))


def test_barycentric_cases_are_on_their_planes_half_of_them_outside():
    p, a, b, c = _triangle_cases(np.random.default_rng(0))
    w = barycentric(p, a, b, c)
    np.testing.assert_allclose(w[:, :1] * a + w[:, 1:2] * b + w[:, 2:] * c, p, atol=1e-12)
    outside = (w < 0).any(axis=1)
    assert outside.sum() == len(p) // 2
    np.testing.assert_allclose(w.sum(axis=1), 1, atol=1e-12)


def test_direction_cases_lean_towards_every_face_and_near_the_cubes_edges_but_never_on_them():
    (d,) = _direction_cases(np.random.default_rng(0))
    faces = reference_cube_face(d)
    assert set(np.unique(faces)) == set(range(6))
    size = np.sort(np.abs(d), axis=1)
    ratio = size[:, 1] / size[:, 2]                   # second largest over largest
    assert np.sum(ratio > 0.98) >= len(d) // 8 and ratio.max() < 1.0
