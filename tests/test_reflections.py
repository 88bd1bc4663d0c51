"""Mirror reflections: what a mirror pixel shows, traced analytically in the test.

The floor's material has ka = 1, kd = ks = 0 under a white ambient light and no lights, so its
colour is exactly its albedo wherever it is seen; the mirror has kr = 1 and ka = kd = ks = 0, so
a mirror pixel shows only what its reflected ray sees; the background is a solid colour. For a
primary ray hitting the mirror sphere at p with normal n, the reflected ray r = d - 2 (d.n) n
leaves the (convex) sphere for good, so it hits the floor y = 0 if r_y < 0 and the sky if not.
"""

import dataclasses

import numpy as np
import pytest

import marchlab
from scene_model.builder import (Camera, Material, RenderSettings, Scene, SolidBackground, plane,
                                 sphere)

WIDTH, HEIGHT = 48, 36
CENTRE = np.array([0.0, 1.5, 0.0])
RADIUS = 1.0
FLOOR = np.array([0.2, 0.55, 0.3])
SKY = np.array([0.1, 0.3, 0.85])

SCENE = Scene(
    camera=Camera(position=(0.0, 1.5, 5.0), look_at=(0.0, 1.2, 0.0), fov=35.0),
    render=RenderSettings(epsilon=1e-5, max_steps=512, max_distance=100.0,
                          reflection_depth=1, ambient=(1.0, 1.0, 1.0),
                          background=SolidBackground(tuple(SKY))),
    materials={"floor": Material(color=tuple(FLOOR), ka=1.0, kd=0.0, ks=0.0),
               "mirror": Material(color=(0.7, 0.7, 0.7), ka=0.0, kd=0.0, ks=0.0, kr=1.0)},
    lights=(),
    objects=(plane(material="floor"), sphere(RADIUS, material="mirror").at(*CENTRE)),
)


def with_depth(scene, depth):
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render,
                                                                 reflection_depth=depth))


@pytest.fixture(scope="module")
def mirror_pixels():
    """Pixels whose primary ray clearly hits the sphere, and the y of their reflected ray."""
    origin, d = marchlab.camera_rays(SCENE.camera, WIDTH, HEIGHT)
    oc = origin - CENTRE
    b = d @ oc
    closest = np.sqrt(np.maximum(oc @ oc - b * b, 0))
    disc = b * b - (oc @ oc - RADIUS ** 2)
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    on_sphere = np.isfinite(t) & (closest < RADIUS - 0.01)   # away from the silhouette
    n = (origin + np.where(on_sphere, t, 0)[..., None] * d - CENTRE) / RADIUS
    r = d - 2 * np.sum(d * n, axis=-1, keepdims=True) * n
    return on_sphere, r[..., 1]


def test_mirror_pixels_whose_reflection_points_down_show_the_floor_colour(mirror_pixels):
    on_sphere, r_y = mirror_pixels
    # |r_y| > 0.05: the floor hit is then at most 2.5 / 0.05 = 50 away, inside max_distance.
    down = on_sphere & (r_y < -0.05)
    assert down.sum() > 20
    frame = marchlab.render(SCENE, WIDTH, HEIGHT)
    np.testing.assert_allclose(frame.color[down], np.broadcast_to(FLOOR, frame.color[down].shape),
                               rtol=0, atol=1e-6)


def test_mirror_pixels_whose_reflection_points_up_show_the_background(mirror_pixels):
    on_sphere, r_y = mirror_pixels
    up = on_sphere & (r_y > 0.05)
    assert up.sum() > 20
    frame = marchlab.render(SCENE, WIDTH, HEIGHT)
    np.testing.assert_allclose(frame.color[up], np.broadcast_to(SKY, frame.color[up].shape),
                               rtol=0, atol=1e-6)


def test_reflection_depth_zero_shows_no_reflection(mirror_pixels):
    """Without bounces a mirror pixel is its own shading: ka = kd = ks = 0 and no lights give
    black, while the floor and sky pixels are unchanged."""
    on_sphere, _ = mirror_pixels
    flat = marchlab.render(with_depth(SCENE, 0), WIDTH, HEIGHT)
    mirrored = marchlab.render(SCENE, WIDTH, HEIGHT)
    np.testing.assert_array_equal(flat.color[on_sphere], 0.0)
    off_sphere = ~flat.hit | (flat.object_id == 0)
    np.testing.assert_array_equal(flat.color[off_sphere], mirrored.color[off_sphere])
    assert np.abs(mirrored.color[on_sphere]).min(axis=-1).min() > 0.05


def test_reflections_add_kr_weighted_surface_colours_between_facing_mirrors():
    """Two parallel half-mirrors (kr = 1/2) at z = -2 (red, faces +z) and z = 6 (blue, faces
    -z), the camera between them looking at the red one. Each bounce hits the other mirror and
    adds its ambient colour weighted by the product of the kr so far:
    depth D gives sum_{i=0..D} (1/2)^i albedo_(i mod 2)."""
    red, blue = np.array([0.4, 0.0, 0.0]), np.array([0.0, 0.0, 0.4])
    scene = Scene(
        camera=Camera(position=(0.0, 0.0, 5.0), look_at=(0.3, 0.1, 0.0), fov=30.0),
        render=RenderSettings(epsilon=1e-5, max_steps=256, max_distance=100.0,
                              ambient=(1.0, 1.0, 1.0), background=SolidBackground((0, 1, 0))),
        materials={"red": Material(color=tuple(red), ka=1.0, kd=0.0, ks=0.0, kr=0.5),
                   "blue": Material(color=tuple(blue), ka=1.0, kd=0.0, ks=0.0, kr=0.5)},
        lights=(),
        objects=(plane((0.0, 0.0, 1.0), -2.0, material="red"),
                 plane((0.0, 0.0, -1.0), -6.0, material="blue")),
    )
    colours = []
    for depth in range(4):
        frame = marchlab.render(with_depth(scene, depth), 9, 7)
        expected = sum(0.5 ** i * (red if i % 2 == 0 else blue) for i in range(depth + 1))
        np.testing.assert_allclose(frame.color, np.broadcast_to(expected, frame.color.shape),
                                   rtol=0, atol=1e-6)
        colours.append(frame.color)
    # Depth 2 differs from depth 1 (a second red bounce, weight 1/4: +0.1 in red).
    assert np.all(colours[2][..., 0] - colours[1][..., 0] > 0.09)


def test_partial_mirror_mixes_own_shading_and_reflection_by_kr():
    """A sphere with ka = 1 (albedo a) and kr = 0.4: colour = a + 0.4 * (floor or sky)."""
    albedo = np.array([0.3, 0.2, 0.1])
    materials = dict(SCENE.materials, mirror=Material(color=tuple(albedo), ka=1.0, kd=0.0,
                                                      ks=0.0, kr=0.4))
    scene = dataclasses.replace(SCENE, materials=materials)
    origin, d = marchlab.camera_rays(scene.camera, WIDTH, HEIGHT)
    frame = marchlab.render(scene, WIDTH, HEIGHT)
    oc = origin - CENTRE
    b = d @ oc
    closest = np.sqrt(np.maximum(oc @ oc - b * b, 0))
    t = -b - np.sqrt(np.maximum(b * b - (oc @ oc - RADIUS ** 2), 0))
    n = (origin + t[..., None] * d - CENTRE) / RADIUS
    r_y = (d - 2 * np.sum(d * n, axis=-1, keepdims=True) * n)[..., 1]
    inside = closest < RADIUS - 0.01
    for mask, seen in ((inside & (r_y < -0.05), FLOOR), (inside & (r_y > 0.05), SKY)):
        assert mask.sum() > 20
        np.testing.assert_allclose(frame.color[mask], np.broadcast_to(
            albedo + 0.4 * seen, frame.color[mask].shape), rtol=0, atol=1e-6)
