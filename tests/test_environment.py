"""Environment maps in the NumPy reference: which texel a direction sees, and how it is filtered.

The face table is OpenGL's (OpenGL 4.6 core spec, section 8.13, table 8.19), written out here
as the test's own copy; the bilinear filter is checked on images whose filtered value is
known exactly (a linear ramp, one colour), and a cube map and a panorama of one function are
checked against the function. The other backends are held to these same functions by
tests/equivalence/test_environment_backends.py and the equivalence suite.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gpu_shader.generate import generate
from reference_cpu.environment import (background_cubemap, background_equirect, cube_map_face,
                                       environment_direction, equirect_uv)
from reference_cpu.shading import background
from reference_cpu.texture import texture_bilinear
from scene_model.environment import (SUN, cube_face_directions, environment_map,
                                     equirect_directions, studio_radiance, turn)
from scene_model.errors import MarchlabError
from scene_model.scene import RenderSettings, Scene, SkyBackground, StudioBackground

# Table 8.19: major axis -> (face index, sc, tc) as functions of (rx, ry, rz).
GL_TABLE = {
    "+x": (0, lambda x, y, z: -z, lambda x, y, z: -y),
    "-x": (1, lambda x, y, z: z, lambda x, y, z: -y),
    "+y": (2, lambda x, y, z: x, lambda x, y, z: z),
    "-y": (3, lambda x, y, z: x, lambda x, y, z: -z),
    "+z": (4, lambda x, y, z: x, lambda x, y, z: -y),
    "-z": (5, lambda x, y, z: -x, lambda x, y, z: -y),
}
AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0),
        "+z": (0, 0, 1), "-z": (0, 0, -1)}


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_each_axis_direction_sees_the_centre_of_its_face(dtype):
    d = np.array(list(AXES.values()), dtype)
    face, s, t = cube_map_face(d)
    assert face.tolist() == [GL_TABLE[name][0] for name in AXES]
    assert s.tolist() == [0.5] * 6 and t.tolist() == [0.5] * 6
    assert face.dtype == s.dtype == dtype


def test_off_axis_directions_follow_the_gl_table_to_the_last_bit():
    rng = np.random.default_rng(7)
    for name, axis in AXES.items():
        index, sc, tc = GL_TABLE[name]
        d = np.array(axis, float) * 2.0 + rng.uniform(-0.9, 0.9, (50, 3)) * (np.array(axis) == 0)
        face, s, t = cube_map_face(d)
        ma = np.abs(d @ np.abs(axis))
        assert (face == index).all(), name
        np.testing.assert_array_equal(s, 0.5 * (sc(*d.T) / ma + 1))
        np.testing.assert_array_equal(t, 0.5 * (tc(*d.T) / ma + 1))


def test_ties_between_components_go_to_x_then_y():
    d = np.array([[1, 1, 0], [1, -1, 1], [-1, 1, 1], [0, 1, 1], [0, -1, -1], [0.5, 0.5, 0.5]])
    face, _, _ = cube_map_face(d)
    assert face.tolist() == [0, 0, 1, 2, 3, 0]


def test_the_texel_centres_of_a_cube_map_look_up_their_own_texels():
    size = 5
    d = cube_face_directions(size)
    face, s, t = cube_map_face(d.reshape(-1, 3))
    faces, rows, columns = np.indices((6, size, size)).reshape(3, -1)
    np.testing.assert_array_equal(face, faces)
    np.testing.assert_allclose(s * size - 0.5, columns, atol=1e-12)
    np.testing.assert_allclose(t * size - 0.5, rows, atol=1e-12)


def test_the_pixel_centres_of_a_panorama_look_up_their_own_pixels():
    width, height = 16, 8
    u, v = equirect_uv(equirect_directions(width, height).reshape(-1, 3))
    rows, columns = np.indices((height, width)).reshape(2, -1)
    np.testing.assert_allclose(u * width - 0.5, columns, atol=1e-12)
    np.testing.assert_allclose(v * height - 0.5, rows, atol=1e-12)


def test_panorama_centre_looks_along_minus_z_and_its_right_quarter_along_plus_x():
    u, v = equirect_uv(np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
                                 [0.0, -2.0, 0.0]]))
    np.testing.assert_allclose(u[:2], [0.5, 0.75], atol=1e-15)
    np.testing.assert_allclose(v, [0.5, 0.5, 0.0, 1.0], atol=1e-15)


# --- Bilinear filtering ------------------------------------------------------------------------

def ramp(height, width):
    """Texels of a linear ramp, texel (j, i) = (i / W, j / H, (i + 2 j) / (W + 2 H))."""
    j, i = np.indices((height, width), dtype=float)
    return np.stack([i / width, j / height, (i + 2 * j) / (width + 2 * height)], axis=-1)


@pytest.mark.parametrize("dtype, tolerance", [(np.float64, 1e-12), (np.float32, 1e-6)])
def test_bilinear_filtering_of_a_linear_ramp_is_the_ramp(dtype, tolerance):
    height, width = 6, 9
    texels = np.zeros((20, width, 3))
    texels[4:4 + height] = ramp(height, width)         # a texture 4 rows down the atlas
    rng = np.random.default_rng(3)
    # between the outermost texel centres, where no edge is clamped
    u = rng.uniform(0.5 / width, 1 - 0.5 / width, 1000).astype(dtype)
    v = rng.uniform(0.5 / height, 1 - 0.5 / height, 1000).astype(dtype)
    got = texture_bilinear(texels.astype(dtype), (4, width, height, 0), u, v)
    x, y = u.astype(float) * width - 0.5, v.astype(float) * height - 0.5
    expected = np.stack([x / width, y / height, (x + 2 * y) / (width + 2 * height)], axis=-1)
    assert got.dtype == dtype
    np.testing.assert_allclose(got, expected, rtol=0, atol=tolerance)


def test_bilinear_filtering_clamps_at_the_edges_or_wraps_around():
    texels = ramp(2, 4).astype(np.float32)
    u = np.array([0.0, 1.0, 0.0, 1.0])
    v = np.array([0.0, 1.0, 0.0, 1.0])
    clamped = texture_bilinear(texels, (0, 4, 2, 0), u[:2], v[:2])
    np.testing.assert_array_equal(clamped, texels[[0, 1], [0, 3]])       # the corner texels
    wrapped = texture_bilinear(texels, (0, 4, 2, 1), u[2:], v[2:])
    # half way between the first and the last column, at either end of a row
    np.testing.assert_allclose(wrapped, (texels[[0, 1], 0] + texels[[0, 1], 3]) / 2, atol=1e-7)


def test_one_colour_is_that_colour_to_the_bit_wherever_it_is_sampled():
    colour = np.array([0.3, 0.6, 0.9], np.float32)
    texels = np.broadcast_to(colour, (24, 4, 3))
    rng = np.random.default_rng(5)
    d = rng.normal(size=(2000, 3)).astype(np.float32)
    look = np.array([1.0, *turn(30.0)], np.float32)
    got = background_cubemap(d, texels, np.array([0, 4, 4, 0], np.float32), look)
    assert (got == colour).all()


def test_a_cube_map_and_a_panorama_of_one_function_agree_at_the_cube_texel_centres():
    """f(d) = (1 + d) / 2 sampled both ways. The cube map returns f at its own texel centres
    (to rounding, 1e-12); the panorama's bilinear error is O(h^2) inside, and at most half a
    row's step of f next to its top and bottom rows, where v is clamped: |df| <= (pi / 2H) / 2."""
    size, width, height = 16, 512, 256
    f = lambda d: (1 + d) / 2
    cube = f(cube_face_directions(size)).reshape(6 * size, size, 3)
    panorama = f(equirect_directions(width, height))
    d = cube_face_directions(size).reshape(-1, 3)
    look = np.array([1.0, 1.0, 0.0])
    from_cube = background_cubemap(d, cube, np.array([0.0, size, size, 0.0]), look)
    from_panorama = background_equirect(d, panorama, np.array([0.0, width, height, 1.0]), look)
    np.testing.assert_allclose(from_cube, f(d), atol=1e-12)
    inside = np.abs(d[:, 1]) < math.cos(math.pi / height)
    assert np.abs(from_panorama - f(d))[inside].max() < 1e-4
    assert np.abs(from_panorama - f(d)).max() <= math.pi / (2 * height) / 2


# --- Rotation and intensity --------------------------------------------------------------------

def test_a_rotation_of_90_degrees_shows_along_minus_z_what_was_along_plus_x():
    cos_turn, sin_turn = turn(90.0)
    turned = environment_direction(np.array([[0.0, 0.0, -1.0], [0.0, 0.5, 1.0]]),
                                   cos_turn, sin_turn)
    np.testing.assert_allclose(turned, [[1.0, 0.0, 0.0], [-1.0, 0.5, 0.0]], atol=1e-15)


def test_intensity_scales_the_studio_and_rotation_turns_it():
    d = np.random.default_rng(2).normal(size=(500, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    base = background(d, StudioBackground(size=16))
    brighter = background(d, StudioBackground(size=16, intensity=2.5))
    np.testing.assert_allclose(brighter, 2.5 * base, rtol=1e-15)
    c, s = turn(-70.0)           # the world direction that sees d once turned by -70 degrees
    turned = background(d @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]).T,
                        StudioBackground(size=16, rotation=-70.0))
    np.testing.assert_allclose(turned, base, atol=1e-12)


# --- The studio -------------------------------------------------------------------------------

def test_the_studio_is_the_same_array_every_time_and_read_only():
    first = environment_map(StudioBackground(size=8))
    assert environment_map(StudioBackground(size=8, intensity=3.0)) is first
    assert first.texels.shape == (48, 8, 3) and first.texels.dtype == np.float32
    assert first.cube and first.texture == (0.0, 8.0, 8.0, 0.0)
    with pytest.raises(ValueError):
        first.texels[0, 0, 0] = 1.0


def test_the_studio_shows_its_sun_brightest_and_its_floor_below_the_sky():
    sun, up, down = studio_radiance(np.array([SUN, [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]))
    assert sun.min() > 2.0 > up.max()
    assert down.sum() < up.sum()


# --- The generated programs -------------------------------------------------------------------

def test_only_a_program_with_an_environment_holds_texture_code_and_texels():
    sky = Scene(render=RenderSettings(background=SkyBackground()))
    studio = dataclasses.replace(sky, render=RenderSettings(background=StudioBackground(size=4)))
    for dialect in ("glsl", "opencl", "opencl-packets"):
        with_sky, with_studio = generate(sky, 8, 6, dialect), generate(studio, 8, 6, dialect)
        assert with_sky.texels is None and "texture_bilinear" not in with_sky.source
        assert "TEXEL" not in with_sky.source and "texture_bilinear" not in with_sky.features
        assert with_studio.texels.shape == (24, 4, 4)
        assert "texture_bilinear(" in with_studio.source
        assert "background:studio" in with_studio.features


def test_the_uber_shader_refuses_an_environment_in_one_line():
    from gpu_shader.uber import uber_program
    scene = Scene(render=RenderSettings(background=StudioBackground(size=4)))
    with pytest.raises(MarchlabError) as caught:
        uber_program(scene, 8, 6)
    assert "'studio'" in str(caught.value) and "\n" not in str(caught.value)
