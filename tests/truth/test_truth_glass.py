"""Glass against exact optics: closed forms, and the exact ray tree of reference_cpu/truth/glass.py.

The exact tree intersects spheres and boxes analytically; the reference marches. The closed
forms check the exact tree (and the optics of reference_cpu/refraction.py); the reference
must then converge to the exact tree as its epsilon and surface offset shrink.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import marchlab
from reference_cpu import refraction
from reference_cpu.truth.glass import glass_colors, glass_leaves
from scene_model.builder import (Camera, Material, RenderSettings, Scene, SkyBackground,
                                 SolidBackground, box, sphere)
from scene_model.camera import camera_rays
from scene_model.errors import SceneError

IOR = 1.5
SKY = SkyBackground(bottom=(0.9, 0.2, 0.1), top=(0.1, 0.3, 1.0))


def glass(**kw) -> Material:
    """A pure dielectric: no ambient, diffuse or specular term."""
    return Material(**dict(dict(ka=0.0, kd=0.0, ks=0.0, transparency=1.0, ior=IOR), **kw))


def scene_of(objects, material, eps=1e-7, offset=1e-6, depth=8, bg=SKY, **render) -> Scene:
    return Scene(camera=Camera(position=(0, 0.3, 4), look_at=(0, 0, 0), fov=40),
                 render=RenderSettings(epsilon=eps, surface_offset=offset, normal_step=1e-5,
                                       reflection_depth=depth, max_steps=2000, background=bg,
                                       **render),
                 materials={"default": material}, objects=tuple(objects))


def one_ray(x: float, direction=(0.0, 0.0, -1.0)):
    """A ray from z = 4 at height 0, offset x from the axis, with the given direction."""
    return np.array([x, 0.0, 4.0]), np.array([direction], float)


# --- The optics: Snell, Fresnel ---------------------------------------------------------------

def test_refraction_obeys_snell_sine_law_to_1e_15():
    rng = np.random.default_rng(3)
    angle = rng.uniform(0, math.pi / 2 - 1e-3, 200)
    d = np.stack([np.sin(angle), np.zeros_like(angle), -np.cos(angle)], axis=1)
    n = np.tile([0.0, 0.0, 1.0], (200, 1))
    _, n_facing, cos_i = refraction.facing(d, n)
    t, cos_t, total = refraction.refract(d, n_facing, cos_i, np.full(200, 1 / IOR))
    assert not total.any()
    np.testing.assert_allclose(np.hypot(t[:, 0], t[:, 1]), np.sin(angle) / IOR, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(-t[:, 2], cos_t, atol=1e-15)


def test_total_internal_reflection_begins_at_the_critical_angle_to_1e_9_rad():
    critical = math.asin(1 / IOR)
    angle = np.array([critical - 1e-9, critical + 1e-9, math.pi / 2])
    cos_i = np.cos(angle)
    d = np.stack([np.sin(angle), np.zeros(3), cos_i], axis=1)     # inside, toward +z
    n_facing = np.tile([0.0, 0.0, -1.0], (3, 1))
    _, cos_t, total = refraction.refract(d, n_facing, cos_i, np.full(3, IOR))
    assert total.tolist() == [False, True, True]
    f = refraction.fresnel("exact", cos_i, cos_t, np.full(3, IOR), np.ones(3), total)
    assert f[1] == f[2] == 1.0
    assert 0.99 < f[0] < 1.0           # all but a sliver is reflected just below it


@pytest.mark.parametrize("model", ["exact", "schlick"])
def test_fresnel_at_normal_incidence_is_r0(model):
    one = np.ones(1)
    f = refraction.fresnel(model, one, one, one, one * IOR, np.zeros(1, bool))
    assert f[0] == pytest.approx(((IOR - 1) / (IOR + 1)) ** 2, abs=1e-15)


def test_fresnel_exact_reflects_everything_at_grazing_entry():
    cos_i = np.array([1e-12])
    k = refraction.refract_k(cos_i, np.array([1 / IOR]))
    f = refraction.fresnel("exact", cos_i, np.sqrt(k), np.ones(1), np.full(1, IOR),
                           np.zeros(1, bool))
    assert f[0] == pytest.approx(1.0, abs=1e-11)


def test_fresnel_exact_is_zero_between_equal_indices_but_schlick_is_not():
    cos = np.array([1.0, 0.5, 0.1])
    one, no = np.ones(3), np.zeros(3, bool)
    assert np.all(refraction.fresnel("exact", cos, cos, one, one, no) == 0)
    np.testing.assert_allclose(refraction.fresnel("schlick", cos, cos, one, one, no),
                               (1 - cos) ** 5, rtol=1e-15)


# --- The exact tree against closed forms -----------------------------------------------------

@pytest.mark.parametrize("b", [0.0, 0.3, 0.7, 0.95])
def test_exact_tree_bends_a_ray_through_a_sphere_by_2_theta_i_minus_theta_t(b):
    """A ray at impact parameter b through a sphere of radius 1: the ray refracted in and out
    turns by 2 (theta_i - theta_t) toward the axis, after a chord of 2 cos theta_t."""
    scene = scene_of([sphere(1.0)], glass(), depth=2)
    origin, d = one_ray(b)
    leaves = glass_leaves(scene, origin, d)
    through = np.argmax(leaves.weight[:, 0])        # (1 - F)^2: the brightest leaf
    theta_i = math.asin(b)
    theta_t = math.asin(b / IOR)
    turn = 2 * (theta_i - theta_t)
    expected = np.array([-math.sin(turn), 0.0, -math.cos(turn)])
    np.testing.assert_allclose(leaves.direction[through], expected, atol=1e-12)
    assert leaves.inside[through] == pytest.approx(2 * math.cos(theta_t), abs=1e-12)


@pytest.mark.parametrize("angle", [0.0, 20.0, 50.0])
def test_exact_tree_shifts_a_ray_through_a_slab_without_turning_it(angle):
    """Through a slab of thickness L the ray leaves parallel to how it came, after L / cos
    theta_t inside."""
    thickness = 0.4
    a = math.radians(angle)
    scene = scene_of([box(3.0, 3.0, thickness / 2)], glass(), depth=2)
    origin, d = one_ray(-4.0 * math.tan(a), (math.sin(a), 0.0, -math.cos(a)))  # to the middle
    leaves = glass_leaves(scene, origin, d)
    through = np.argmax(leaves.weight[:, 0] * (leaves.direction[:, 2] < 0))
    np.testing.assert_allclose(leaves.direction[through], d[0], atol=1e-12)
    theta_t = math.asin(math.sin(a) / IOR)
    assert leaves.inside[through] == pytest.approx(thickness / math.cos(theta_t), abs=1e-12)


def test_exact_tree_refuses_a_material_that_shades():
    scene = scene_of([sphere(1.0)], glass(kd=0.5))
    with pytest.raises(SceneError, match="pure dielectrics"):
        glass_leaves(scene, *one_ray(0.0))


# --- The reference against closed forms and the exact tree ----------------------------------

def test_reference_slab_transmits_and_reflects_by_the_geometric_series_to_1e_4():
    """A slab at normal incidence before a white background: the camera sees R, plus
    (1 - R)^2 R^(k-1) e^{-k sigma L} for the light that crosses the slab k = 1, 2, ... times
    and leaves (by the back for odd k, the front for even k, both toward white):
    R + (1 - R)^2 e^{-sigma L} / (1 - R e^{-sigma L}). The terms the tree leaves out (weight
    below MIN_RAY_WEIGHT) are below 1e-4."""
    sigma, thickness = np.array([0.8, 0.3, 0.0]), 0.5
    r = ((IOR - 1) / (IOR + 1)) ** 2
    scene = dataclasses.replace(
        scene_of([box(2.0, 2.0, thickness / 2)], glass(absorption=tuple(sigma)), depth=10,
                 bg=SolidBackground(color=(1.0, 1.0, 1.0))),
        camera=Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov=30))
    frame = marchlab.render(scene, 3, 3, precision="float64")
    e = np.exp(-sigma * thickness)
    np.testing.assert_allclose(frame.color[1, 1], r + (1 - r) ** 2 * e / (1 - r * e), atol=1e-4)


GLASS_SCENE = [sphere(1.0), box(0.6, 0.3, 0.1).rotate(10, 30, 0).at(1.0, 0.8, -1.0)]


@pytest.mark.parametrize("eps, offset, tolerance", [(1e-5, 1e-4, 2e-3), (1e-7, 1e-6, 3e-5)])
def test_reference_glass_converges_to_the_exact_tree(eps, offset, tolerance):
    """A tinted ball and a tilted block, 64 x 48, float64: every pixel's colour within the
    tolerance of the exact tree's (measured 1.2e-3 and 1.3e-5: a hundred times closer for a
    hundred times finer epsilon and offset)."""
    scene = scene_of(GLASS_SCENE, glass(absorption=(0.4, 0.1, 0.0)), eps=eps, offset=offset,
                     depth=6, shadows="none")
    width, height = 64, 48
    frame = marchlab.render(scene, width, height, precision="float64")
    origin, d = camera_rays(scene.camera, width, height, np.float64)
    exact = np.clip(glass_colors(scene, origin, d.reshape(-1, 3)), 0, 1).reshape(height, width, 3)
    assert np.abs(frame.color - exact).max() < tolerance


def test_glass_of_index_one_is_invisible():
    """Index 1 and no shading: the exact Fresnel equations reflect nothing and Snell bends
    nothing, so the image is the scene without the ball (within its march's epsilon)."""
    floor = box(3.0, 0.1, 3.0).at(0, -1.2, 0)
    behind = [floor, box(0.5).rotate(0, 30, 0).at(0.3, 0.0, -2.0)]
    lit = Material(color=(0.8, 0.5, 0.3))
    base = scene_of(behind, lit, eps=1e-6, offset=1e-5, depth=4)
    with_ball = dataclasses.replace(
        base, objects=base.objects + (sphere(1.0, material="clear").at(0, 0, 0.5),),
        materials={"default": lit, "clear": glass(ior=1.0)})
    a = marchlab.render(base, 48, 36, precision="float64")
    b = marchlab.render(with_ball, 48, 36, precision="float64")
    assert np.abs(a.color - b.color).max() < 1e-4


def test_a_ray_tangent_to_a_glass_ball_sees_what_the_exact_tree_sees():
    """The camera's middle column grazes the ball's side: no NaN, and each pixel within 1e-2
    of the exact tree (a grazing ray meets the ball within epsilon / cos i of its edge)."""
    scene = dataclasses.replace(
        scene_of([sphere(1.0)], glass(), eps=1e-7, offset=1e-6, depth=4),
        camera=Camera(position=(1.0, 0.0, 4.0), look_at=(1.0, 0.0, 0.0), fov=10))
    frame = marchlab.render(scene, 9, 9, precision="float64")
    origin, d = camera_rays(scene.camera, 9, 9, np.float64)
    exact = np.clip(glass_colors(scene, origin, d.reshape(-1, 3)), 0, 1).reshape(9, 9, 3)
    assert np.isfinite(frame.color).all()
    assert np.abs(frame.color - exact).max() < 1e-2
