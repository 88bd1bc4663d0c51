"""Image textures: bilinear filtering of a texture in an array of texels, and the mappings
that give a surface point its place in a texture.

The twin of gpu_shader/glsl/texture.glsl, operation for operation, so that the NumPy
reference, the GLSL shader and the OpenCL kernel sample an image the same way (no driver
sampler filters for them). A program's textures lie in one array of texels, the atlas
(`scene_model.environment` says how an environment's images fill it, `scene_model.textures`
how surface textures join them); one texture is four numbers, ``image``: its first row in the
atlas, its width and height in texels, and ``wrap`` (0: clamped at its edges; 1: it repeats
left to right, as a panorama does; 2: it repeats both ways, as a surface texture does).

Surface mappings (docs/phong.md, "Textures"), each in world space:

- cube: the face of the world axis nearest the normal (`major_face`), and the point's
  coordinates on it (`cube_face_coordinates`), divided by the texture's scale;
- triplanar (Geiss 2007, GPU Gems 3, ch. 1): the three faces facing the normal's way,
  blended by |n_i|^k normalised (`triplanar_weights`);
- sphere: the longitude and latitude of the normal (`sphere_uv`).
"""

from __future__ import annotations

import numpy as np


def texture_bilinear(texels, image, u, v):
    """The colour (N, 3) of a texture at (u, v), by bilinear filtering.

    OpenGL 4.6 core spec, section 8.14.2: the four texels around x = u w - 1/2,
    y = v h - 1/2 (texel i covers [i, i + 1), its centre at i + 1/2), weighted by the
    fractions a = x - floor(x) and b = y - floor(y). Texels beyond an edge are the edge's
    own or, where it wraps (left and right with wrap 1, every edge with wrap 2), those of the
    other side (for u and v in [0, 1]).

    Parameters
    ----------
    texels : (R, W, 3) ndarray
        The atlas, row 0 at the top; read in the precision of ``u``.
    image : (4,) or (N, 4) array_like
        First row, width, height, wrap; a row per point where points read different
        textures (a cube map's faces, objects of different materials).
    u, v : (N,) ndarray
        Texture coordinates, (0, 0) the top left corner of the image, (1, 1) its bottom
        right.
    """
    dtype = u.dtype
    first, width, height, wrap = np.moveaxis(
        np.broadcast_to(np.asarray(image, dtype), u.shape + (4,)), -1, 0)
    x = u * width - dtype.type(0.5)
    y = v * height - dtype.type(0.5)
    fx, fy = np.floor(x), np.floor(y)
    a, b = (x - fx)[:, None], (y - fy)[:, None]
    first, width, height = (first.astype(np.int64), width.astype(np.int64),
                            height.astype(np.int64))
    i0 = fx.astype(np.int64)
    i1 = i0 + 1
    wrapping = wrap > 0
    i0 = np.where(wrapping & (i0 < 0), i0 + width, i0)
    i1 = np.where(wrapping & (i1 >= width), i1 - width, i1)
    i0, i1 = np.clip(i0, 0, width - 1), np.clip(i1, 0, width - 1)
    j0 = fy.astype(np.int64)
    j1 = j0 + 1
    both = wrap > 1
    j0 = np.where(both & (j0 < 0), j0 + height, j0)
    j1 = np.where(both & (j1 >= height), j1 - height, j1)
    r0 = first + np.clip(j0, 0, height - 1)
    r1 = first + np.clip(j1, 0, height - 1)
    t00, t10, t01, t11 = (texels[r, i].astype(dtype) for r, i in
                          ((r0, i0), (r0, i1), (r1, i0), (r1, i1)))
    upper = t00 + (t10 - t00) * a
    lower = t01 + (t11 - t01) * a
    return upper + (lower - upper) * b


def texture_repeat(texels, image, u, v):
    """(N, 3): a texture repeated across the plane (wrap 2): `texture_bilinear` at
    (u - floor(u), v - floor(v)), any u and v (N,)."""
    return texture_bilinear(texels, image, u - np.floor(u), v - np.floor(v))


# --- Where a point lies in a texture ----------------------------------------------------------

def major_face(d):
    """(N,) in the precision of ``d`` (N, 3): the cube face 0 to 5 (+x, -x, +y, -y, +z, -z) of
    the largest |component| of each row and its sign, the face a cube map shows along d
    (OpenGL 4.6 core spec, section 8.13). Where two components tie (the spec leaves it open),
    x wins over y and y over z."""
    a = np.abs(d)
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    on_x = (a[:, 0] >= a[:, 1]) & (a[:, 0] >= a[:, 2])
    on_y = ~on_x & (a[:, 1] >= a[:, 2])
    return np.select([on_x, on_y], [np.where(x >= 0, 0, 1), np.where(y >= 0, 2, 3)],
                     np.where(z >= 0, 4, 5)).astype(d.dtype)


def cube_face_coordinates(q, face):
    """The coordinates (sc, tc), each (N,), of the points ``q`` (N, 3) on the cube faces
    ``face`` (N,): table 8.19 of the OpenGL 4.6 core spec (section 8.13), which is what a cube
    map's face shows, upright and unmirrored seen from outside: +x (-z, -y), -x (z, -y),
    +y (x, z), -y (x, -z), +z (x, -y), -z (-x, -y)."""
    x, y, z = q[:, 0], q[:, 1], q[:, 2]
    sc = np.select([face == 0, face == 1, face == 5], [-z, z, -x], x)
    tc = np.select([face == 2, face == 3], [z, -z], -y)
    return sc, tc


def equirect_uv(d):
    """Where on a panorama each direction of ``d`` (N, 3) points: (u, v), each (N,).

    u = atan2(x, -z) / 2 pi + 1/2 around (0.5 straight ahead along -z, 0.75 along +x) and
    v = 1/2 - atan2(y, sqrt(x^2 + z^2)) / pi, which is acos(y / |d|) / pi (0 straight up)
    but needs no unit ``d``. A sphere's texture is the same map of its normal.
    """
    dtype = d.dtype.type
    across = d[:, 0] * d[:, 0] + d[:, 2] * d[:, 2]
    u = np.arctan2(d[:, 0], -d[:, 2]) / dtype(2 * np.pi) + 0.5
    v = 0.5 - np.arctan2(d[:, 1], np.sqrt(across)) / dtype(np.pi)
    return u, v


def triplanar_weights(n, sharpness):
    """(N, 3): the weights of the x, y and z projections at unit normals ``n`` (N, 3):
    w_i = |n_i|^k / (|n_x|^k + |n_y|^k + |n_z|^k), k the ``sharpness`` (N,), after Geiss
    2007 (GPU Gems 3, ch. 1). They sum to 1 and a face facing along an axis takes only that
    axis's projection; larger k narrows the blends between them."""
    w = np.abs(n) ** sharpness[:, None]
    total = w[:, 0] + w[:, 1] + w[:, 2]
    return w / total[:, None]


# --- The surface mappings: (N, 3) colours at points p (N, 3) with unit normals n (N, 3) --------

def texture_cube(texels, image, p, n, scale):
    """The texture on the face of the world axis nearest the normal: `cube_face_coordinates`
    of p on `major_face` (n), divided by ``scale`` (N,), repeated (``image`` wraps both
    ways). Exact for planes and boxes aligned with the axes; its face is a path-label feature,
    as the colour may jump where it changes."""
    sc, tc = cube_face_coordinates(p, major_face(n))
    return texture_repeat(texels, image, sc / scale, tc / scale)


def texture_triplanar(texels, image, p, n, scale, sharpness):
    """The three projections along the axes, on the faces facing the normal's way (the one
    along x is on face +x where n_x >= 0, else on -x, so no side shows mirrored), blended by
    `triplanar_weights`. A projection changes sides only where its weight is 0: the blend is
    continuous."""
    w = triplanar_weights(n, sharpness)
    color = None
    for axis in range(3):
        face = np.where(n[:, axis] >= 0, 2 * axis, 2 * axis + 1).astype(p.dtype)
        sc, tc = cube_face_coordinates(p, face)
        term = w[:, axis:axis + 1] * texture_repeat(texels, image, sc / scale, tc / scale)
        color = term if color is None else color + term
    return color


def sphere_uv(n):
    """Where on a sphere's texture the unit normals ``n`` (N, 3) point: (u, v), each (N,),
    u = atan2(n_x, n_z) / 2 pi + 1/2 and v = acos(n_y) / pi: the middle of the image faces
    +z, u grows eastward (toward +x from +z) and v from the north pole (+y) down, so that the
    image is seen upright and unmirrored from outside. It is `equirect_uv` of (n_x, n_y,
    -n_z): a panorama seen from outside, not from within."""
    return equirect_uv(n * np.array([1, 1, -1], n.dtype))


def texture_sphere(texels, image, n):
    """A sphere's texture: the image wrapped round it once at `sphere_uv` (``image`` wraps
    left and right, its rows clamped at the poles). Its two sides meet at the back (-z)
    without a seam: wrapping filters across it."""
    u, v = sphere_uv(n)
    return texture_bilinear(texels, image, u, v)
