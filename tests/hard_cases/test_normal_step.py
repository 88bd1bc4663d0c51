"""A normal step too small for float32: how the normal's error grows as h shrinks.

The normal is n = normalize(sum_k k f(p + h k)) (docs: Normals). Two errors compete:

- truncation, from the curvature the stencil spans: for the central stencil it is
  second order (the Taylor remainder h^2 f''' / 6), for the tetrahedron first order (its
  four offsets are not symmetric); measured in float64 on a unit sphere: at most 0.14 h^2
  and 0.29 h radians;
- rounding: each sample of f near |p| ~ 1 carries an error of about one float32 spacing
  (2^-24 relative, from rounding p + h k and the distance itself), and the differences are
  divided by about 2h: an angle of order 2^-24 / h. It is negligible in float64 (2^-53 / h)
  and grows without bound in float32: about 1e-4 rad at h = 1e-3, 0.1 at 1e-6, and at
  h = 1e-9 every p + h k rounds back to p, the differences vanish and so does the normal.

Expected: the float32 error stays within truncation + 2^-22 / h (four spacings; measured
1.4 to 1.9 times 2^-24 / h, on every backend) and does grow (at h = 1e-6 it is at least
2^-26 / h); where the estimate is zero the contract returns the zero vector, never NaN,
and the shading then has no diffuse or specular term but stays finite. The error series
is reported at the end of the run.
"""

from __future__ import annotations

import numpy as np
import pytest

from reference_cpu.normals import STENCILS, estimate_normal
from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.builder import Camera, PointLight, RenderSettings, Scene, sphere

from .conftest import pixel_rays, unit

CENTRE = np.array([0.3, -0.2, 0.5])
STEPS = [1e-3, 1e-4, 1e-5, 1e-6]
ROUNDING = {np.dtype("float32"): 2.0 ** -22, np.dtype("float64"): 2.0 ** -51}


def truncation(h, method):
    """Measured truncation bound on a unit sphere, with 10% margin (module docstring)."""
    return 1.1 * (0.14 * h * h if method == "central" else 0.29 * h)


def angle(normals, exact):
    """Angle in radians between the directions of ``normals`` (non-zero) and ``exact``,
    computed without the cancellation of arccos near 1."""
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    return np.arctan2(np.linalg.norm(np.cross(n, exact), axis=1), np.sum(n * exact, axis=1))


def surface_points(dtype, n=4000):
    rng = np.random.default_rng(5)
    p = (CENTRE + unit(rng.normal(size=(n, 3)))).astype(dtype)
    return p, unit(p.astype(np.float64) - CENTRE)


@pytest.mark.parametrize("method", list(STENCILS))
def test_normal_error_stays_within_truncation_plus_rounding_and_grows_like_1_over_h(
        dtype, method, report):
    p, exact = surface_points(dtype)
    sdf = build_scene_sdf([sphere(1.0).at(*CENTRE)], dtype)
    errors = []
    for h in STEPS:
        normals = estimate_normal(sdf, p, dtype.type(h), method).astype(np.float64)
        error = angle(normals, exact).max()
        errors.append(error)
        assert error <= truncation(h, method) + ROUNDING[dtype] / h, (h, error)
        report(f"{dtype} {method} normal error at h = {h:g} (rad)", float(error))
    if dtype == np.float32:
        assert errors[-1] >= 2.0 ** -26 / STEPS[-1]          # it grows: measured 0.093 rad
        assert errors[-1] > 30 * errors[0]
    else:
        assert errors[-1] <= truncation(STEPS[-1], method) + 1e-8


@pytest.mark.parametrize("method", list(STENCILS))
def test_step_below_the_float32_spacing_gives_zero_normals_not_nan(method):
    """h = 1e-9 is below half the spacing of coordinates above 0.017: p + h k rounds back to
    p for every offset, all samples are equal and the normal is the zero vector."""
    p, _ = surface_points(np.dtype("float32"))
    sdf = build_scene_sdf([sphere(1.0).at(*CENTRE)], np.float32)
    h = np.float32(1e-9)
    normals = estimate_normal(sdf, p, h, method)
    assert not np.isnan(normals).any()
    offsets = STENCILS[method].astype(np.float32)
    collapsed = np.all([(p + h * k == p).all(axis=1) for k in offsets], axis=0)
    assert collapsed.mean() > 0.85       # measured: 90% (central), 95% (tetrahedron)
    assert np.all(normals[collapsed] == 0)
    length = np.linalg.norm(normals[~collapsed].astype(np.float64), axis=1)
    assert np.all((length == 0) | (np.abs(length - 1) < 1e-6))


def sphere_scene(h, method):
    return Scene(camera=Camera(position=(0.5, 0.8, 3.5), look_at=tuple(CENTRE), fov=45.0),
                 render=RenderSettings(normal_step=h, normal_method=method),
                 objects=(sphere(1.0).at(*CENTRE),),
                 lights=(PointLight(position=(2.0, 4.0, 3.0)),))


@pytest.mark.parametrize("h", [1e-3, 1e-5, 1e-7, 1e-9])
@pytest.mark.parametrize("method", list(STENCILS))
def test_every_backend_normal_error_is_bounded_by_the_rounding_of_its_precision(renderer,
                                                                               method, h):
    """The rendered normals against the exact gradient at the point each ray stopped;
    zero normals (h below the spacing) shade without NaN."""
    scene = sphere_scene(h, method)
    frame = renderer.draw(scene, 48, 36)
    origin, directions = pixel_rays(scene, 48, 36)
    hit = frame.hit
    assert hit.sum() >= 500
    stop = origin + frame.depth[hit, None].astype(np.float64) * directions[hit] - CENTRE
    exact = stop / np.linalg.norm(stop, axis=1, keepdims=True)
    normals = frame.normal[hit].astype(np.float64)
    zero = np.all(normals == 0, axis=1)
    if renderer.precision == "float64" or h >= 1e-5:
        assert not zero.any()
    if renderer.precision == "float32" and h == 1e-9:
        assert zero.all()                           # measured: every pixel
    # The coordinates reach 1.5 here: one more factor of 2 on the spacing.
    bound = truncation(h, method) + 2 * ROUNDING[renderer.dtype] / h
    error = angle(normals[~zero], exact[~zero]) if (~zero).any() else np.zeros(1)
    assert error.max() <= min(bound, np.pi), f"{renderer}: {error.max():.3g} > {bound:.3g}"
