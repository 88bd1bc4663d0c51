"""Triangle meshes of the scene's parts, for the Embree ground truth, with a bound on their error.

- A **box** is its 12 triangles: exact.
- A **plane** is a square of two triangles around the point below the camera, wide enough to
  hold every hit within the render's ``max_distance``: exact there.
- A **sphere** is an icosphere (an icosahedron whose triangles are split in four, the new
  vertices pushed onto the sphere, again and again). Its vertices lie on the sphere and its
  triangles inside it, so a triangle is at most r - (distance from the centre to its plane) away
  from the sphere: that maximum is the mesh's computed error.
- **Anything else** (tori, cones, CSG, smooth blends, limited repetition) is sampled on a grid
  over its bounding sphere (`scene_model.bounds.bounding_sphere`) and meshed by marching cubes
  (Lorensen and Cline, SIGGRAPH 1987; scikit-image's Lewiner et al. 2003 variant). Its error
  is stated as half a cell diagonal and measured by the caller.

Every mesh is wound so that a triangle (v0, v1, v2) has its right-hand normal
(v1 - v0) x (v2 - v0) pointing out of the solid, where the SDF grows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scene_model.bounds import bounding_sphere
from scene_model.errors import SceneError
from scene_model.geometry import dot
from scene_model.shapes import Box, Plane, Repeat, Sphere

from ..scene_sdf import build_scene_sdf
from .parts import Part

MAX_ICOSPHERE_LEVEL = 7      # 327,680 triangles
MARGIN_CELLS = 2             # grid cells kept between the bounding sphere and the grid's side


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh and how far it may be from the surface it stands for.

    Attributes
    ----------
    vertices : (V, 3) float64 ndarray
    faces : (F, 3) int32 ndarray
        Vertex indices, wound outward.
    bound : float
        Largest distance from a point of the mesh to the true surface: computed for
        tessellated primitives (0 for boxes and planes), half a cell diagonal for marching
        cubes.
    cell : float or None
        Grid spacing of marching cubes; None for a tessellated primitive.
    method : str
        ``"exact"``, ``"icosphere"`` or ``"marching cubes"``.
    """
    vertices: np.ndarray
    faces: np.ndarray
    bound: float
    cell: float | None
    method: str


def face_normals(vertices, faces):
    """Right-hand normals (v1 - v0) x (v2 - v0) of each face, not normalised: (F, 3)."""
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    return np.cross(v1 - v0, v2 - v0)


# --- Tessellated primitives -------------------------------------------------------------------

def box_mesh(half_size) -> Mesh:
    """The 12 triangles of the box |x_k| <= h_k, wound outward."""
    h = np.asarray(half_size, dtype=np.float64)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
    # Each face as a quad of corner indices (index = 4 [x > 0] + 2 [y > 0] + [z > 0]),
    # listed counter-clockwise seen from outside.
    quads = np.array([[0, 1, 3, 2], [4, 6, 7, 5],      # -x, +x
                      [0, 4, 5, 1], [2, 3, 7, 6],      # -y, +y
                      [0, 2, 6, 4], [1, 5, 7, 3]])     # -z, +z
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int32)
    return Mesh(corners, faces, 0.0, None, "exact")


def plane_mesh(normal, offset, around, half_side: float) -> Mesh:
    """The plane n . x = offset as a square of side 2 ``half_side`` centred below ``around``."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / math.sqrt(dot(n, n))
    foot = around - (dot(around, n) - offset) * n
    # Two unit vectors u, v in the plane with u x v = n (Frisvad's branch-free basis would do
    # too; any helper not parallel to n works).
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, n)
    u /= math.sqrt(dot(u, u))
    v = np.cross(n, u)
    corners = foot + half_side * np.array([-u - v, u - v, u + v, -u + v])
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    return Mesh(corners, faces, 0.0, None, "exact")


def icosphere(level: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit icosphere: (vertices (V, 3), faces (F, 3)), 20 4^level faces, wound outward."""
    vertices, faces = _icosahedron()
    for _ in range(level):
        vertices, faces = _split_in_four(vertices, faces)
    return vertices, faces


def _icosahedron():
    """The 12 corners (on the unit sphere) and 20 outward-wound faces of an icosahedron."""
    g = (1 + math.sqrt(5)) / 2                  # the golden ratio: corners at (0, +-1, +-g)...
    vertices = np.array([[-1, g, 0], [1, g, 0], [-1, -g, 0], [1, -g, 0],
                         [0, -1, g], [0, 1, g], [0, -1, -g], [0, 1, -g],
                         [g, 0, -1], [g, 0, 1], [-g, 0, -1], [-g, 0, 1]], dtype=np.float64)
    faces = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
                      [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
                      [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
                      [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int32)
    return vertices / np.linalg.norm(vertices, axis=1, keepdims=True), faces


def _split_in_four(vertices, faces):
    """Each triangle (a, b, c) becomes four through its edge midpoints, pushed to |x| = 1."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    unique, which = np.unique(np.sort(edges, axis=1), axis=0, return_inverse=True)
    middle = vertices[unique[:, 0]] + vertices[unique[:, 1]]
    middle /= np.linalg.norm(middle, axis=1, keepdims=True)
    m = len(vertices) + which.reshape(3, -1)    # midpoints of edges ab, bc, ca of each face
    a, b, c = faces.T
    ab, bc, ca = m
    faces = np.concatenate([np.stack(f, axis=1) for f in
                            ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
    return np.concatenate([vertices, middle]), faces.astype(np.int32)


def sphere_mesh(radius: float, max_error: float) -> Mesh:
    """The coarsest icosphere (up to level `MAX_ICOSPHERE_LEVEL`) within ``max_error`` of the
    sphere of ``radius``, or the finest if none is."""
    unit, faces = _icosahedron()
    for level in range(MAX_ICOSPHERE_LEVEL + 1):
        if level:
            unit, faces = _split_in_four(unit, faces)
        n = face_normals(unit, faces)
        plane_distance = np.abs(dot(n, unit[faces[:, 0]])) / np.sqrt(dot(n, n))
        # Vertices on the sphere, so each flat triangle lies between its plane and the sphere.
        error = radius * (1.0 - float(plane_distance.min()))
        if error <= max_error:
            break
    return Mesh(radius * unit, faces, error, None, "icosphere")


# --- Marching cubes ---------------------------------------------------------------------------

def sdf_mesh(sdf, centre, radius: float, resolution: int) -> Mesh:
    """Marching cubes of the zero set of ``sdf`` inside the sphere (``centre``, ``radius``).

    Parameters
    ----------
    sdf : callable
        Distances (N,) at points (N, 3), float64, negative inside.
    centre : (3,) ndarray
    radius : float
        The solid lies inside this sphere.
    resolution : int
        Cells across the sphere's diameter; the grid adds `MARGIN_CELLS` on every side so that
        the solid's surface closes inside it.
    """
    from skimage.measure import marching_cubes

    cell = 2 * radius / resolution
    points_per_side = resolution + 2 * MARGIN_CELLS + 1
    low = np.asarray(centre, float) - radius - MARGIN_CELLS * cell
    axis = np.arange(points_per_side) * cell
    # The grid is indexed [i, j, k] <-> (x, y, z) = low + cell (i, j, k); sampled one x-slab at
    # a time to keep memory bounded.
    yy, zz = np.meshgrid(axis, axis, indexing="ij")
    volume = np.empty((points_per_side,) * 3, dtype=np.float64)
    for i, x in enumerate(axis):
        slab = np.stack([np.full(yy.size, x), yy.ravel(), zz.ravel()], axis=1) + low
        volume[i] = sdf(slab).reshape(yy.shape)
    if not volume.min() < 0:            # an empty solid: no surface to mesh
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int32), 0.0, cell, "marching cubes")
    # Vertices in grid units (spacing 1): exact small numbers, moved to the world in float64.
    grid_vertices, faces, _, _ = marching_cubes(volume, level=0.0, allow_degenerate=False)
    vertices = low + cell * grid_vertices.astype(np.float64)
    faces = orient_outward(vertices, faces.astype(np.int32), sdf, cell)
    return Mesh(vertices, faces, math.sqrt(3) * cell / 2, cell, "marching cubes")


def orient_outward(vertices, faces, sdf, cell: float):
    """``faces`` wound so their right-hand normals follow the SDF's gradient (outward).

    scikit-image's winding depends on whether the solid holds the larger or the smaller
    values (its ``gradient_direction``); rather than rely on that convention, the face normals
    are compared with central differences of the SDF at the face centroids, and all faces
    are flipped when most disagree.
    """
    n = face_normals(vertices, faces)
    centroids = vertices[faces].mean(axis=1)
    h = cell / 8
    gradient = np.stack([sdf(centroids + h * e) - sdf(centroids - h * e) for e in np.eye(3)],
                        axis=1)
    if np.sum(np.sign(dot(n, gradient))) < 0:
        faces = faces[:, [0, 2, 1]]
    return faces


# --- A part of the scene ----------------------------------------------------------------------

def part_mesh(part: Part, resolution: int, camera_position, reach: float) -> Mesh:
    """The mesh of ``part`` in world coordinates.

    Parameters
    ----------
    part : Part
    resolution : int
        Marching-cubes cells across the part's bounding sphere; tessellated spheres are made
        ten times more accurate than that grid's half cell.
    camera_position : (3,) ndarray
        Where the rays start (a plane's square is centred below it).
    reach : float
        Distance from the camera within which hits must be found (the plane's half side).
    """
    leaf, s = part.leaf, part.scale
    if isinstance(leaf, Box):
        local = box_mesh(leaf.half_size)
    elif isinstance(leaf, Plane):
        local = plane_mesh(leaf.normal, leaf.offset, part.to_local(np.asarray(camera_position)),
                           reach / s)
    elif isinstance(leaf, Sphere):
        local = sphere_mesh(leaf.radius, 0.1 * math.sqrt(3) * leaf.radius / resolution)
    else:
        sphere = bounding_sphere(leaf)
        if sphere is None:
            why = ("repeats forever (give it a count)" if isinstance(leaf, Repeat)
                   and leaf.count is None else "is unbounded (it holds a plane or an "
                                               "infinite repeat)")
            raise SceneError(f"{leaf.kind!r} {why}; the embree method meshes bounded shapes "
                             "only", part.path)
        distance = build_scene_sdf([leaf], np.float64)
        local = sdf_mesh(lambda p: distance(p)[0], sphere[0], sphere[1], resolution)
    cell = None if local.cell is None else local.cell * s
    return Mesh(part.to_world(local.vertices), local.faces, local.bound * s, cell,
                local.method)
