"""Environment backgrounds: what a ray that hits nothing sees in a cube map or a panorama.

The twin of gpu_shader/glsl/environment.glsl, operation for operation. The texels come from
`scene_model.environment.environment_map` (a cube map's six faces stacked, or the panorama)
and are filtered by `reference_cpu.texture.texture_bilinear`.
"""

from __future__ import annotations

import numpy as np

from scene_model.environment import environment_map, turn

from .texture import cube_face_coordinates, equirect_uv, major_face, texture_bilinear


def environment_direction(d, cos_turn, sin_turn):
    """(N, 3): the direction of the environment that rays along ``d`` (N, 3) see, ``d``
    turned by -rotation about +y (a rotation of 90 degrees shows, looking along -z, what was
    along +x)."""
    x = cos_turn * d[:, 0] - sin_turn * d[:, 2]
    z = sin_turn * d[:, 0] + cos_turn * d[:, 2]
    return np.stack([x, d[:, 1], z], axis=1)


def cube_map_face(d):
    """The cube face each direction of ``d`` (N, 3) points at and where on it.

    Returns (face, s, t), each (N,) in the precision of ``d``: face 0 to 5 for +x, -x, +y,
    -y, +z, -z (`major_face`: the largest |component| ma, ties to x, then y), and s, t in
    [0, 1] from the face's top left corner: with the face coordinates sc, tc of d
    (`cube_face_coordinates`), s = (sc / |ma| + 1) / 2 and t = (tc / |ma| + 1) / 2 (OpenGL
    4.6 core spec, section 8.13, "Cube Map Texture Selection", table 8.19).
    """
    face = major_face(d)
    sc, tc = cube_face_coordinates(d, face)
    a = np.abs(d)
    ma = np.select([face < 2, face < 4], [a[:, 0], a[:, 1]], a[:, 2])
    return face, 0.5 * (sc / ma + 1), 0.5 * (tc / ma + 1)


def background_cubemap(direction, texels, image, look):
    """(N, 3): a cube map seen along ``direction`` (N, 3): the face's texture (face f starts
    f times the width below the first) sampled at (s, t), times the intensity. ``image``
    is the first face's texture (first row, width, height, wrap), ``look`` the background's
    (intensity, cos, sin of its rotation), both in the precision of ``direction``."""
    d = environment_direction(direction, look[1], look[2])
    face, s, t = cube_map_face(d)
    side = np.zeros((len(d), 4), d.dtype)
    side[:] = image
    side[:, 0] = image[0] + face * image[1]
    return look[0] * texture_bilinear(texels, side, s, t)


def background_equirect(direction, texels, image, look):
    """(N, 3): a panorama seen along ``direction`` (N, 3), times the intensity (arguments
    as for `background_cubemap`)."""
    d = environment_direction(direction, look[1], look[2])
    u, v = equirect_uv(d)
    return look[0] * texture_bilinear(texels, image, u, v)


def background_environment(direction, bg):
    """(N, 3): what rays along ``direction`` (N, 3) see of the environment background
    ``bg`` (``cubemap``, ``equirect`` or ``studio``), in the precision of ``direction``."""
    dtype = direction.dtype
    env = environment_map(bg)
    image = np.asarray(env.texture, dtype)
    look = np.asarray((bg.intensity, *turn(bg.rotation)), np.float64).astype(dtype)
    sample = background_cubemap if env.cube else background_equirect
    return sample(direction, env.texels, image, look)
