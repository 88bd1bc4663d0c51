"""Triangle meshes as plain data: procedural primitives with normals and texture coordinates.

The raster half of real-time graphics draws triangles, not distance fields. A mesh here is
four arrays: vertex positions, unit normals and (u, v) texture coordinates, and triangles
as triples of vertex indices. Every generator winds its triangles **outward**: the right-hand
normal (v1 - v0) x (v2 - v0) of a triangle points out of the solid (or up, for a plane), the
side its vertex normals face. A rasteriser needs that to tell front faces from back faces;
shadow volumes need it to tell the silhouette.

Curved surfaces are parametric grids: a point p(u, v) for u, v in [0, 1], with the grid's
orientation chosen so that dp/du x dp/dv points outward. A vertex on a seam (u = 0 and
u = 1) is stored twice, with the same position and different texture coordinates; at a pole
or an apex the triangles that would have no area are left out. The edges of a closed
mesh, compared by position, then pair up exactly: each is used once in each direction
(tests/test_meshes.py).

Transforms follow the usual rule: positions by the matrix M, normals by the inverse
transpose of its 3 x 3 part (then normalised), and a matrix with a negative determinant
(a mirror) reverses the winding so that it stays outward. A `MeshNode` places a mesh (or a
group) relative to its parent, so a hierarchy composes: a node's world matrix is its parent's
times its own, M_world = M_parent T R S (a mobile's arm turns with the arm above it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .geometry import normalize, rotation_matrix


@dataclass(frozen=True)
class TriangleMesh:
    """A triangle mesh.

    Attributes
    ----------
    positions : (V, 3) float64 ndarray
        Vertex positions (m).
    normals : (V, 3) float64 ndarray
        Unit vertex normals, pointing out of the surface.
    uvs : (V, 2) float64 ndarray
        Texture coordinates, (0, 0) at the texture's bottom left.
    triangles : (T, 3) int64 ndarray
        Vertex indices of each triangle, wound outward.
    """
    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    triangles: np.ndarray

    def face_normals(self) -> np.ndarray:
        """Right-hand normals (v1 - v0) x (v2 - v0) of the triangles, unit length: (T, 3)."""
        v0, v1, v2 = (self.positions[self.triangles[:, k]] for k in range(3))
        return normalize(np.cross(v1 - v0, v2 - v0))


def smooth_groups(mesh: TriangleMesh) -> np.ndarray:
    """(T,) int64: labels of the pieces across which a picture of the mesh is smooth.

    Two triangles are joined where they share an edge, both its vertices: their normals
    and texture coordinates agree along it. An edge whose two corners appear in another
    triangle as *other* vertices at the same positions is a crease: the attributes may jump
    there (a cube's edges, where each face keeps vertices of its own; a cone's side at its
    apex, where each triangle has an apex vertex with its own normal; a sphere's uv seam).
    A triangle on a crease keeps a label of its own; the others take their joined patch's.
    """
    triangles = mesh.triangles
    count = len(triangles)
    at = np.unique(mesh.positions, axis=0, return_inverse=True)[1].reshape(-1)
    corners = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    by_index = _edge_keys(np.sort(corners, axis=1), len(mesh.positions))
    by_place = _edge_keys(np.sort(at[corners], axis=1), len(mesh.positions))
    owner = np.repeat(np.arange(count), 3)                        # the triangle of each edge
    # A crease: one edge in space made of two different pairs of vertices.
    places, first = np.unique(by_place, return_inverse=True)
    pairs = np.unique(np.stack([first, by_index], axis=1), axis=0)[:, 0]
    crease = np.bincount(pairs, minlength=len(places))[first] > 1
    on_crease = np.zeros(count, bool)
    on_crease[owner[crease]] = True
    label = np.arange(count)
    edge = np.unique(by_index, return_inverse=True)[1]
    while True:                          # each triangle takes its lowest neighbour's label
        lowest = np.full(edge.max(initial=0) + 1, count)
        np.minimum.at(lowest, edge, label[owner])
        joined = label.copy()
        np.minimum.at(joined, owner, lowest[edge])
        joined = joined[joined]                                   # follow chains at once
        if np.array_equal(joined, label):
            break
        label = joined
    return np.where(on_crease, count + np.arange(count), label)


def _edge_keys(pairs: np.ndarray, base: int) -> np.ndarray:
    """One int64 per sorted vertex pair (E, 2)."""
    return pairs[:, 0].astype(np.int64) * base + pairs[:, 1]


def parametric(point, normal, u_segments: int, v_segments: int,
               u_wraps: bool = False) -> TriangleMesh:
    """The grid mesh of a parametric surface.

    Parameters
    ----------
    point, normal : callable
        ``point(u, v)`` and ``normal(u, v)`` for arrays u, v of one shape S give (S..., 3)
        positions and unit normals; dp/du x dp/dv must point outward.
    u_segments, v_segments : int
        Grid cells along u and v (at least 1; at least 3 along a wrapping u).
    u_wraps : bool
        Whether u = 1 is u = 0 again (a longitude): the last column's positions and normals
        are then the first's, exactly, and only the texture coordinates differ.

    Returns
    -------
    TriangleMesh
        (u_segments + 1) (v_segments + 1) vertices, two triangles a cell, less those of no
        area (at a pole, where a row of the grid is one point).
    """
    i = np.arange(u_segments + 1)
    j = np.arange(v_segments + 1)
    u = i / u_segments
    v = j / v_segments
    # On a wrapping grid the last column is computed at u = 0, so the seam is closed exactly.
    u_position = (i % u_segments) / u_segments if u_wraps else u
    uu, vv = np.meshgrid(u_position, v, indexing="ij")
    positions = point(uu, vv).reshape(-1, 3)
    normals = normal(uu, vv).reshape(-1, 3)
    uvs = np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1).reshape(-1, 2)
    index = (i[:, None] * (v_segments + 1) + j[None, :])
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()        # (i, j), (i + 1, j)
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()          # (i + 1, j + 1), (i, j + 1)
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return _without_slivers(TriangleMesh(positions, normals, uvs, triangles.astype(np.int64)))


def _without_slivers(mesh: TriangleMesh) -> TriangleMesh:
    """``mesh`` without the triangles two of whose corners are one point."""
    p = mesh.positions[mesh.triangles]
    same = (np.all(p[:, 0] == p[:, 1], axis=1) | np.all(p[:, 1] == p[:, 2], axis=1)
            | np.all(p[:, 2] == p[:, 0], axis=1))
    return TriangleMesh(mesh.positions, mesh.normals, mesh.uvs, mesh.triangles[~same])


def merged(*meshes: TriangleMesh) -> TriangleMesh:
    """One mesh holding all of ``meshes`` (their vertices are not shared)."""
    first = np.cumsum([0] + [len(m.positions) for m in meshes[:-1]])
    return TriangleMesh(np.concatenate([m.positions for m in meshes]),
                        np.concatenate([m.normals for m in meshes]),
                        np.concatenate([m.uvs for m in meshes]),
                        np.concatenate([m.triangles + f for m, f in zip(meshes, first)]))


def flipped(mesh: TriangleMesh) -> TriangleMesh:
    """``mesh`` seen from its other side: normals negated, winding reversed."""
    return TriangleMesh(mesh.positions, -mesh.normals, mesh.uvs, mesh.triangles[:, ::-1].copy())


def transformed(mesh: TriangleMesh, matrix) -> TriangleMesh:
    """``mesh`` moved by the 4 x 4 affine ``matrix`` (a column vector convention: p' = M p).

    Normals go by the inverse transpose of the 3 x 3 part, which keeps them perpendicular to
    the surface under a non-uniform scale; a mirror (negative determinant) reverses the
    winding so that it stays outward.
    """
    m = np.asarray(matrix, np.float64)
    linear, offset = m[:3, :3], m[:3, 3]
    positions = mesh.positions @ linear.T + offset
    normals = normalize(mesh.normals @ np.linalg.inv(linear))     # (M^-T n)^T = n^T M^-1
    triangles = mesh.triangles if np.linalg.det(linear) > 0 else mesh.triangles[:, ::-1].copy()
    return TriangleMesh(positions, normals, mesh.uvs, triangles)


# --- the primitives ----------------------------------------------------------------------------

def plane(width: float = 1.0, depth: float = 1.0, subdivisions: int = 1) -> TriangleMesh:
    """A width x depth rectangle in y = 0 facing +y, centred on the origin, split into
    ``subdivisions`` x ``subdivisions`` cells; u runs along +x, v along -z."""
    def point(u, v):
        return np.stack([(u - 0.5) * width, np.zeros_like(u), (0.5 - v) * depth], axis=-1)

    def normal(u, v):
        return np.broadcast_to(np.array([0.0, 1.0, 0.0]), u.shape + (3,)).copy()

    return parametric(point, normal, subdivisions, subdivisions)


# The cube's faces: (outward normal N, u direction U, v direction V) with U x V = N.
_CUBE_FACES = (((1, 0, 0), (0, 0, -1), (0, 1, 0)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
               ((0, 1, 0), (1, 0, 0), (0, 0, -1)), ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
               ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (-1, 0, 0), (0, 1, 0)))


def _cube_faces(subdivisions: int, to_surface) -> TriangleMesh:
    """The six faces of the cube [-1, 1]^3 as grids, each point p of the face of outward
    normal n mapped by ``to_surface(p, n) -> (positions, normals)``; each face has the
    whole uv square."""
    faces = []
    for n, u_axis, v_axis in _CUBE_FACES:
        n, u_axis, v_axis = (np.array(a, np.float64) for a in (n, u_axis, v_axis))

        def surface(u, v, n=n, u_axis=u_axis, v_axis=v_axis):
            p = n + (2 * u - 1)[..., None] * u_axis + (2 * v - 1)[..., None] * v_axis
            return to_surface(p, np.broadcast_to(n, p.shape))

        faces.append(parametric(lambda u, v, f=surface: f(u, v)[0],
                                lambda u, v, f=surface: f(u, v)[1],
                                subdivisions, subdivisions))
    return merged(*faces)


def cube(size: float = 1.0, subdivisions: int = 1) -> TriangleMesh:
    """A cube of side ``size`` centred on the origin: 6 faces of their own vertices (a
    corner has three normals, one a face), each with the whole uv square."""
    return _cube_faces(subdivisions, lambda p, n: (p * (size / 2), n.copy()))


def cube_sphere(radius: float = 1.0, subdivisions: int = 8) -> TriangleMesh:
    """A sphere made from a subdivided cube whose points are pushed onto it: cells of more
    even size than a UV sphere's, and no poles."""
    def to_surface(p, n):
        unit = normalize(p)
        return radius * unit, unit
    return _cube_faces(subdivisions, to_surface)


def uv_sphere(radius: float = 1.0, segments: int = 32, rings: int = 16) -> TriangleMesh:
    """A sphere of longitude segments and latitude rings; u is the longitude (0 at +x,
    turning towards -z), v the latitude from the south pole (0) to the north (1)."""
    def normal(u, v):
        phi, theta = 2 * np.pi * u, np.pi * (v - 0.5)
        # The poles exactly: cos(+-pi/2) is 6e-17 in floating point, not 0.
        ring = np.where((v == 0) | (v == 1), 0.0, np.cos(theta))
        return np.stack([ring * np.cos(phi), np.sin(theta), -ring * np.sin(phi)], axis=-1)

    return parametric(lambda u, v: radius * normal(u, v), normal, segments, rings, u_wraps=True)


def torus(major: float = 1.0, minor: float = 0.25, segments: int = 32,
          sides: int = 16) -> TriangleMesh:
    """A torus around the y axis: the circle of radius ``major`` swept by a tube of radius
    ``minor``; u goes round the axis, v round the tube."""
    def parts(u, v):
        phi, theta = 2 * np.pi * u, 2 * np.pi * v
        n = np.stack([np.cos(theta) * np.cos(phi), np.sin(theta),
                      -np.cos(theta) * np.sin(phi)], axis=-1)
        centre = major * np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], axis=-1)
        return centre + minor * n, n

    # Both angles wrap; v's seam is closed by computing it at v mod 1 as well.
    return parametric(lambda u, v: parts(u, v % 1.0)[0], lambda u, v: parts(u, v % 1.0)[1],
                      segments, sides, u_wraps=True)


def disk(radius: float = 1.0, segments: int = 32) -> TriangleMesh:
    """A disk in y = 0 facing +y: a fan of triangles around its centre; uv maps the unit
    square's inscribed circle onto it."""
    phi = 2 * np.pi * np.arange(segments) / segments
    ring = np.stack([radius * np.cos(phi), np.zeros(segments), -radius * np.sin(phi)], axis=1)
    positions = np.concatenate([np.zeros((1, 3)), ring])
    normals = np.tile([0.0, 1.0, 0.0], (segments + 1, 1))
    uvs = np.concatenate([[[0.5, 0.5]],
                          np.stack([0.5 + 0.5 * np.cos(phi), 0.5 + 0.5 * np.sin(phi)], 1)])
    k = np.arange(segments)
    triangles = np.stack([np.zeros(segments, np.int64), 1 + k, 1 + (k + 1) % segments], 1)
    return TriangleMesh(positions, normals, uvs, triangles)


def _shifted(mesh: TriangleMesh, y: float) -> TriangleMesh:
    return TriangleMesh(mesh.positions + [0.0, y, 0.0], mesh.normals, mesh.uvs, mesh.triangles)


def cylinder(radius: float = 0.5, height: float = 1.0, segments: int = 32) -> TriangleMesh:
    """A closed cylinder around the y axis from y = -height/2 to height/2: a side and two
    disks, each of its own vertices (the rim has two normals)."""
    def normal(u, v):
        phi = 2 * np.pi * u
        return np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], axis=-1)

    def point(u, v):
        return radius * normal(u, v) + np.stack([0 * u, (v - 0.5) * height, 0 * u], -1)

    side = parametric(point, normal, segments, 1, u_wraps=True)
    top = _shifted(disk(radius, segments), height / 2)
    bottom = _shifted(flipped(disk(radius, segments)), -height / 2)
    return merged(side, top, bottom)


def cone(radius: float = 0.5, height: float = 1.0, segments: int = 32) -> TriangleMesh:
    """A closed cone around the y axis, its base disk at y = 0 and its apex at y = height.
    The side's normals are the cone's, (h cos, r, -h sin) / sqrt(h^2 + r^2), at the apex too
    (one vertex per segment there, each with its own)."""
    slant = math.hypot(height, radius)

    def normal(u, v):
        phi = 2 * np.pi * u
        return np.stack([height * np.cos(phi), np.full_like(phi, radius),
                         -height * np.sin(phi)], axis=-1) / slant

    def point(u, v):
        phi = 2 * np.pi * u
        r = np.where(v == 1, 0.0, (1 - v) * radius)          # the apex exactly
        return np.stack([r * np.cos(phi), v * height, -r * np.sin(phi)], axis=-1)

    side = parametric(point, normal, segments, 1, u_wraps=True)
    return merged(side, flipped(disk(radius, segments)))


def pyramid(base: float = 1.0, height: float = 1.0) -> TriangleMesh:
    """A square pyramid: base ``base`` x ``base`` in y = 0 facing -y, apex at y = height;
    four flat sides, each of its own vertices."""
    h = base / 2
    corners = np.array([[h, 0, h], [h, 0, -h], [-h, 0, -h], [-h, 0, h]], np.float64)
    apex = np.array([0.0, height, 0.0])
    sides = []
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        n = normalize(np.cross(b - a, apex - a))
        sides.append(TriangleMesh(np.stack([a, b, apex]), np.tile(n, (3, 1)),
                                  np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]),
                                  np.array([[0, 1, 2]], np.int64)))
    bottom = TriangleMesh(corners, np.tile([0.0, -1.0, 0.0], (4, 1)),
                          np.array([[1.0, 1.0], [1.0, 0.0], [0.0, 0.0], [0.0, 1.0]]),
                          np.array([[0, 3, 2], [0, 2, 1]], np.int64))
    return merged(*sides, bottom)


PRIMITIVES = {"plane": plane, "cube": cube, "cube_sphere": cube_sphere, "uv_sphere": uv_sphere,
              "disk": disk, "cylinder": cylinder, "cone": cone, "pyramid": pyramid,
              "torus": torus}


# --- the transform hierarchy -------------------------------------------------------------------

@dataclass(frozen=True)
class MeshNode:
    """A node of a transform hierarchy, placed relative to its parent.

    Attributes
    ----------
    mesh : TriangleMesh or None
        What the node draws; None for a group that only places its children.
    translate : (3,) float
        Where its origin is in its parent's frame (m).
    rotate : (3,) float
        Euler angles in degrees, turned about x, then y, then z (`geometry.rotation_matrix`,
        as the SDF tree's Rotate node).
    scale : float or (3,) float
        Scale along its own axes, applied first.
    children : tuple of MeshNode
        Placed in this node's frame.
    """
    mesh: TriangleMesh | None = None
    translate: tuple = (0.0, 0.0, 0.0)
    rotate: tuple = (0.0, 0.0, 0.0)
    scale: float | tuple = 1.0
    children: tuple = ()


def local_matrix(node: MeshNode) -> np.ndarray:
    """The node's 4 x 4 matrix in its parent's frame: T R S (scale, then turn, then move)."""
    m = np.eye(4)
    m[:3, :3] = rotation_matrix(node.rotate) * np.broadcast_to(
        np.asarray(node.scale, np.float64), (3,))
    m[:3, 3] = node.translate
    return m


def world_meshes(node: MeshNode, parent=None) -> list[TriangleMesh]:
    """Every mesh of the hierarchy under ``node``, in world coordinates, depth first (a
    node's own mesh before its children's): mesh k of the list is object k of a picture.
    ``parent`` is the 4 x 4 world matrix of the node's parent (the identity at the root)."""
    world = (np.eye(4) if parent is None else np.asarray(parent, np.float64)) @ local_matrix(node)
    meshes = [] if node.mesh is None else [transformed(node.mesh, world)]
    for child in node.children:
        meshes += world_meshes(child, world)
    return meshes
