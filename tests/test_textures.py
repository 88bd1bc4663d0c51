"""Surface textures: the mappings' formulas, bilinear filtering, and what a render shows.

The mappings (reference_cpu/texture.py; docs/phong.md, "Textures") are checked against their
definitions: triplanar weights sum to 1 and pick one face on a face along an axis, sharp
triplanar tends to the cube mapping, the sphere's coordinates of the six axis directions,
the cube faces upright and unmirrored from outside. Renders check that a constant texture is
a plain colour and that bilinear filtering of a linear ramp gives the ramp back at every hit
point, on every backend present. Files and their errors: tests/test_texture_files.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import render
from required_backends import need_backend
from reference_cpu.texture import (cube_face_coordinates, major_face, sphere_uv, texture_bilinear,
                                   texture_cube, texture_repeat, texture_triplanar,
                                   triplanar_weights)
from scene_model.builder import Camera, Material, RenderSettings, Scene, box, plane, sphere
from scene_model.camera import camera_basis, camera_rays
from scene_model.errors import SceneError
from scene_model.scene import Checker, Texture
from scene_model.textures import texture_image, uv_grid


def unit_vectors(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


# --- The mappings' formulas ------------------------------------------------------------------

def test_triplanar_weights_sum_to_1_within_2e_16_and_pick_the_face_axis_only_along_it():
    rng = np.random.default_rng(7)
    n = unit_vectors(rng, 1000)
    for k in (1.0, 4.0, 64.0):
        w = triplanar_weights(n, np.full(len(n), k))
        assert (w >= 0).all()
        np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=0, atol=4.5e-16)
    axes = np.vstack([np.eye(3), -np.eye(3)])
    w = triplanar_weights(axes, np.full(6, 4.0))
    np.testing.assert_array_equal(w, np.abs(axes))


def test_sharp_triplanar_equals_the_cube_mapping_within_1e_12_near_each_axis():
    """Within 20 degrees of an axis the other weights are at most tan(20)^64 = 1e-28 of it
    at k = 64: the blend is the cube mapping's one projection."""
    rng = np.random.default_rng(3)
    axis = np.vstack([np.eye(3), -np.eye(3)])[rng.integers(0, 6, 500)]
    n = axis + 0.3 * rng.uniform(-1, 1, (500, 3)) * (1 - np.abs(axis))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    near = np.max(np.abs(n), axis=1) >= np.cos(np.radians(20))
    assert near.sum() > 300
    p = rng.uniform(-3, 3, (500, 3))
    texels = uv_grid().astype(np.float64)
    image = (0.0, 32.0, 32.0, 2.0)
    scale = np.full(500, 0.7)
    blended = texture_triplanar(texels, image, p[near], n[near], scale[near],
                                np.full(near.sum(), 64.0))
    np.testing.assert_allclose(blended, texture_cube(texels, image, p[near], n[near],
                                                     scale[near]), rtol=0, atol=1e-12)


def test_sphere_uv_of_the_six_axis_directions():
    """u = atan2(n_x, n_z) / 2 pi + 1/2, v = acos(n_y) / pi: the image's middle faces +z, +x
    a quarter to its right, -x a quarter to its left, -z its two sides; +y the top row's
    edge, -y the bottom's."""
    n = np.array([[0, 0, 1], [1, 0, 0], [-1, 0, 0], [0, 0, -1], [0, 1, 0], [0, -1, 0]], float)
    u, v = sphere_uv(n)
    np.testing.assert_allclose(u[:3], [0.5, 0.75, 0.25], atol=1e-15)
    assert u[3] in (0.0, 1.0)                   # the back, where the two sides meet
    np.testing.assert_allclose(v, [0.5, 0.5, 0.5, 0.5, 0.0, 1.0], atol=1e-15)


@pytest.mark.parametrize("axis", [0, 2])
@pytest.mark.parametrize("sign", [1, -1])
def test_a_side_face_shows_its_texture_upright_and_unmirrored_from_outside(axis, sign):
    """A camera outside the face, looking at it with +y up: sc grows to its right and tc
    downward, at unit rate."""
    outward = np.zeros(3)
    outward[axis] = sign
    forward, right, up = camera_basis(Camera(position=tuple(3 * outward), look_at=(0, 0, 0)))
    face = major_face(outward[None])
    origin = np.zeros((1, 3))
    points = np.vstack([origin, origin + np.asarray(right)[None], origin - np.asarray(up)[None]])
    sc, tc = cube_face_coordinates(points, np.repeat(face, 3))
    np.testing.assert_allclose([sc[1] - sc[0], tc[2] - tc[0]], [1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose([tc[1] - tc[0], sc[2] - sc[0]], [0.0, 0.0], atol=1e-12)


def test_a_repeated_texture_is_continuous_across_its_edges_both_ways():
    """With wrap 2 the texture at u just below 0 and just above it (and so for v) differ by
    the texture's slope over the step, not by a jump from one edge to the other."""
    texels = uv_grid().astype(np.float64)
    image = (0.0, 32.0, 32.0, 2.0)
    h = 1e-9
    below = np.array([-h, 0.3, 1 - h, 0.3])
    above = np.array([h, 0.3, 1 + h, 0.3])
    for u_first in (True, False):
        u, v = (below[:2], below[2:]) if u_first else (below[2:], below[:2])
        a = texture_repeat(texels, image, u, v)
        u, v = (above[:2], above[2:]) if u_first else (above[2:], above[:2])
        b = texture_repeat(texels, image, u, v)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-7)


def test_a_clamped_texture_keeps_its_rows_at_the_edges():
    """wrap 1 (a panorama, a sphere) repeats only left to right: above the top row's centre
    the top row is read, not a blend with the bottom one."""
    texels = np.zeros((2, 1, 3))
    texels[1] = 1.0
    top = texture_bilinear(texels, (0.0, 1.0, 2.0, 1.0), np.array([0.5]), np.array([0.0]))
    wrapped = texture_bilinear(texels, (0.0, 1.0, 2.0, 2.0), np.array([0.5]), np.array([0.0]))
    np.testing.assert_array_equal([top[0, 0], wrapped[0, 0]], [0.0, 0.5])


# --- Scenes ----------------------------------------------------------------------------------

def test_checker_and_texture_together_are_refused_naming_texture():
    with pytest.raises(SceneError) as caught:
        Material(checker=Checker(), texture=Texture())
    assert caught.value.path == ("texture",) and "not both" in str(caught.value)


def test_an_unknown_built_in_image_is_refused_naming_the_built_in_ones():
    with pytest.raises(SceneError, match="no built-in image.*uv_grid") as caught:
        Texture(image="uv_gird")
    assert caught.value.path == ("image",)


BACKENDS = ["numpy", "gpu", "opencl"]


def backend_present(backend: str) -> None:
    if backend != "numpy":
        need_backend(backend)


def ambient_only(material: Material, objects, camera: Camera) -> Scene:
    """No lights, ka = 1 and ambient white: each pixel's colour is its albedo."""
    lit = Material(ka=1.0, kd=0.0, ks=0.0, color=material.color, texture=material.texture)
    return Scene(camera=camera, lights=(), materials={"default": lit}, objects=tuple(objects),
                 render=RenderSettings(ambient=(1.0, 1.0, 1.0), max_distance=40.0))


def write_image(folder, name, texels) -> str:
    path = folder / name
    np.save(path, np.asarray(texels, np.float32))
    return str(path)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mapping", ["triplanar", "uv"])
def test_a_constant_texture_shows_the_plain_colour_within_1e_6(backend, mapping, tmp_path):
    """Bilinear filtering of equal texels is that texel, exactly; the triplanar blend's
    weights sum to 1 within a few ulps; a float32 backend rounds the tint product once."""
    backend_present(backend)
    colour = (0.6, 0.3, 0.15)
    image = write_image(tmp_path, "flat.npy", np.full((4, 8, 3), colour))
    objects = [plane(), sphere(0.7).at(-0.8, 0.7, 0), box(0.5).at(0.9, 0.5, -0.3)]
    camera = Camera(position=(2.5, 2.2, 4.5), look_at=(0, 0.6, 0), fov=50.0)
    textured = ambient_only(Material(texture=Texture(image, mapping=mapping, scale=0.3)),
                            objects, camera)
    plain = ambient_only(Material(color=colour), objects, camera)
    a, b = render(textured, 48, 36, backend=backend), render(plain, 48, 36, backend=backend)
    np.testing.assert_array_equal(a.hit, b.hit)
    assert a.hit.sum() > 1000
    np.testing.assert_allclose(a.color, b.color, rtol=0, atol=1e-6)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_linear_ramp_on_a_plane_is_reproduced_at_every_hit_point_within_1e_5(backend,
                                                                                tmp_path):
    """Bilinear filtering is exact on a linear function: texels that sample a ramp at their
    centres, red = u and green = v, give back u = x / scale and v = z / scale (the floor's
    face +y, `cube_face_coordinates`) at every hit point, away from the last half texel where
    the repeated ramp drops back to 0."""
    backend_present(backend)
    width, height, scale = 16, 8, 4.0
    u, v = (np.arange(width) + 0.5) / width, (np.arange(height) + 0.5) / height
    texels = np.stack(np.broadcast_arrays(u[None, :], v[:, None], 0.0), axis=-1)
    image = write_image(tmp_path, "ramp.npy", texels)
    camera = Camera(position=(2.0, 3.0, 2.0), look_at=(2.0, 0.0, 2.01), fov=60.0)
    scene = ambient_only(Material(texture=Texture(image, mapping="uv", scale=scale)),
                         [plane()], camera)
    frame = render(scene, 40, 30, backend=backend)
    origin, directions = camera_rays(camera, 40, 30)
    p = origin + frame.depth.astype(np.float64)[..., None] * directions
    expected_u, expected_v = p[..., 0] / scale, p[..., 2] / scale
    inside = ((expected_u > 0.5 / width) & (expected_u < 1 - 0.5 / width)
              & (expected_v > 0.5 / height) & (expected_v < 1 - 0.5 / height) & frame.hit)
    assert inside.sum() > 500
    np.testing.assert_allclose(frame.color[inside][:, 0], expected_u[inside], rtol=0, atol=1e-5)
    np.testing.assert_allclose(frame.color[inside][:, 1], expected_v[inside], rtol=0, atol=1e-5)


def test_each_face_of_a_cube_mapped_box_has_a_path_label_of_its_own():
    """The colour may jump where the cube mapping's face changes, so the face is a feature
    of the path label: a box seen on three faces shows three labels, one a face, and a box
    without a texture one."""
    camera = Camera(position=(2.0, 2.2, 2.6), look_at=(0, 0, 0), fov=45.0)
    labels = []
    for texture in (Texture(mapping="uv"), None):
        scene = ambient_only(Material(texture=texture), [box(0.6)], camera)
        frame = render(scene, 48, 36, path_labels=True)
        face = major_face(frame.normal[frame.hit].astype(np.float64))
        labels.append({int(f): set(np.unique(frame.path[frame.hit][face == f]))
                       for f in np.unique(face)})
    textured, plain = labels
    assert sorted(textured) == [0, 2, 4]
    assert all(len(v) == 1 for v in textured.values())
    assert len(set.union(*textured.values())) == 3
    assert len(set.union(*plain.values())) == 1


def test_the_built_in_image_repeats_without_a_seam_and_changes_at_most_0_16_a_texel():
    texels = texture_image(Texture()).texels
    assert texels.shape == (32, 32, 3) and not texels.flags.writeable
    wrapped = np.concatenate([texels, texels[:1]], axis=0)
    assert np.abs(np.diff(wrapped, axis=0)).max() <= 0.16
    wrapped = np.concatenate([texels, texels[:, :1]], axis=1)
    assert np.abs(np.diff(wrapped, axis=1)).max() <= 0.16
