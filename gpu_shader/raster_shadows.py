"""Shadow volumes on the GPU: depth-fail with caps, counted by additive blending.

The same volumes as the NumPy reference (`reference_cpu.shadow_volumes`, whose silhouette
edges and light-facing triangles it reuses), drawn by OpenGL as Everitt and Kilgard draw
them ("Practical and Robust Stenciled Shadow Volumes", 2002): extruded vertices are points
at infinity (w = 0) and the projection has its far plane at infinity
(glsl/raster/shadow_volume.vert), so nothing of a volume is ever clipped away behind.

**The count.** Their algorithm counts in the stencil buffer: with the depth test as usual
and depth writes off, a back face's fragment that *fails* the depth test adds 1, a front
face's subtracts 1. moderngl 5 has no stencil state in its Python interface (no stencil
function or operations, and its depth textures have no stencil bits), so the count is kept
in a float texture instead: additive blending (ONE, ONE) sums +1 (back face) and -1 (front
face) from the fragment shader, and the depth test is set to pass exactly the fragments a
stencil test would count, those not in front of the surface drawn (GEQUAL: LESS fails).
The sum is the stencil value, without its 8-bit wrap-around; small integers are exact in
float32.

**Drawing order.** The scene's depth is drawn first, by the volume program itself, from the
same vertex buffers that hold the volumes: a front cap triangle is the very triangle the
scene pass drew, so it lands on the same depth to the last bit and is counted where it is
the surface drawn, as the depth-fail rule asks. Then, per light, the volumes of every
closed mesh (open ones cast none) into that light's count texture. A directional light's
extruded vertices are all one point at infinity, so its back cap has no area (their
section 5.3): it is drawn, and covers nothing.

**Z-pass where it is exact.** Depth-fail needs the caps, and a point light's back cap at
infinity can cover much of the screen. Counting the other way, z-pass (Heidmann 1991: front
faces *in front of* the surface add 1, back faces subtract 1) gives the same integer on every
pixel whenever the eye is outside the volume and no volume face crosses the near plane, and
then needs no caps at all: a front cap lies on the occluder, so it is never in front of the
depth drawn, and the back cap lies at infinity. Everitt and Kilgard's test for it (section
6) is whether the occluder meets the pyramid from the light to the near plane's rectangle;
`needs_depth_fail` checks it conservatively with the occluder's bounding sphere, volume by
volume, and keeps depth-fail with caps where it may be needed.

**Scissors.** A volume reaches to infinity, but a count matters only on the surfaces drawn,
all inside the meshes' bounding box: each volume is drawn within the screen rectangle of
(its cone over the occluder's box) n (that box) (`shadow_region`, `region_rectangles`), which
halves the cost of the museum's three lights and leaves every count the same to the bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from reference_cpu.back_faces import bounds_a_solid, culled_meshes
from reference_cpu.rasterise import NEAR
from reference_cpu.shadow_volumes import facing_light, light_source, neighbours
from scene_model.camera import Camera, camera_basis
from scene_model.meshes import TriangleMesh

from .context import gl_context
from .library import glsl_file
from .raster import _set_camera

DEPTH_SCALE = 1.0       # m: depth is stored as z / (z + DEPTH_SCALE) (shadow_volume.frag)


@dataclass
class ShadowCounts:
    """What `draw_shadow_counts` leaves on the GPU, rows as image rows (top first).

    Attributes
    ----------
    depth : moderngl.Texture
        The scene's depth, z / (z + `DEPTH_SCALE`) for view depth z; 1.0 where nothing is.
    counts : list of moderngl.Texture
        One single-channel float32 texture per light: the depth-fail stencil count, 0 where
        the surface drawn is lit by that light (and meaningless where nothing is drawn).
    """
    depth: object
    counts: list

    def release(self) -> None:
        for texture in [self.depth, *self.counts]:
            texture.release()


def volume_vertices(mesh: TriangleMesh, light) -> np.ndarray:
    """(2V, 4) float32 homogeneous vertices: the mesh's own (w = 1), then each extruded to
    infinity away from the light (w = 0): p - L for a point light, its direction for a
    directional one."""
    position, direction = light_source(light)
    at_infinity = (mesh.positions - position if position is not None
                   else np.broadcast_to(direction, mesh.positions.shape))
    return np.concatenate([np.c_[mesh.positions, np.ones(len(mesh.positions))],
                           np.c_[at_infinity, np.zeros(len(mesh.positions))]]).astype(np.float32)


def volume_triangles(mesh: TriangleMesh, light, across=None) -> np.ndarray:
    """(T', 3) int32 indices into `volume_vertices`: the front cap (light-facing triangles),
    the sides (each silhouette edge a -> b as the quad b, a, a', b') and the back cap
    (light-averted triangles at infinity), all wound outward, as in the NumPy reference.
    ``across``: the mesh's `neighbours`, if known (they do not change with the light)."""
    return np.concatenate(volume_parts(mesh, light, across)).astype(np.int32)


def volume_parts(mesh: TriangleMesh, light, across=None) -> tuple:
    """`volume_triangles` in its three parts: (front cap, sides, back cap), each (n, 3)."""
    count = len(mesh.positions)
    across = neighbours(mesh) if across is None else across
    if across is None:
        raise ValueError("a shadow volume needs a closed mesh (see neighbours)")
    lit = facing_light(mesh, light)
    # The silhouette edges (reference_cpu.shadow_volumes.silhouette_edges, the neighbours
    # found once per mesh): a light-facing triangle's edge to a light-averted one.
    triangle, k = np.nonzero(lit[:, None] & ~lit[across])
    a, b = mesh.triangles[triangle, k], mesh.triangles[triangle, (k + 1) % 3]
    sides = np.concatenate([np.stack([b, a, a + count], 1),
                            np.stack([b, a + count, b + count], 1)]).reshape(-1, 3)
    return mesh.triangles[lit], sides, mesh.triangles[~lit] + count


def bounding_sphere(mesh: TriangleMesh) -> tuple[np.ndarray, float]:
    """A sphere round the mesh: its bounding box's centre, and the farthest vertex's distance."""
    centre = (mesh.positions.min(axis=0) + mesh.positions.max(axis=0)) / 2
    return centre, float(np.linalg.norm(mesh.positions - centre, axis=1).max())


def needs_depth_fail(sphere, light, camera: Camera, width: int, height: int) -> bool:
    """Whether the volume cast from ``light`` by an occluder inside ``sphere`` (centre,
    radius) may hold the eye or cross the near plane, so that z-pass would miscount.

    A point q lies in a point light's volume when the segment from the light to q passes
    through the occluder (for a directional light, the ray from q towards the light), so
    the volume meets the near plane's rectangle (and the eye behind it) only if the occluder
    meets the pyramid from the light to that rectangle (Everitt and Kilgard 2002, section
    6). The pyramid lies within r of the segment from the light to the eye, r the distance
    from the eye to the rectangle's corners: a sphere farther than its radius plus r from
    that segment misses it. Conservative: True is always safe (depth-fail is exact)."""
    centre, radius = sphere
    eye = np.asarray(camera.position, np.float64)
    half_height = np.tan(np.radians(camera.fov) / 2)
    reach = 2 * NEAR * np.sqrt(1 + half_height ** 2 * (1 + (width / height) ** 2))
    position, direction = light_source(light)
    along = -direction * (1e6 + np.linalg.norm(centre - eye)) if position is None \
        else position - eye                               # eye to light (or far towards it)
    s = np.clip(np.dot(centre - eye, along) / max(np.dot(along, along), 1e-300), 0.0, 1.0)
    return bool(np.linalg.norm(centre - (eye + s * along)) <= radius * (1 + 1e-6) + reach)


# --- Where a volume can count: its scissor rectangle -----------------------------------------
#
# A pixel's count is 1 exactly where the surface drawn there lies inside a volume; every
# surface lies in the receivers' bounding box, so a volume only needs drawing over the pixels
# where (volume) n (receivers' box) n (in front of the near plane) projects. Outside that
# rectangle the count stays the clear's 0, which is what drawing there would have summed to;
# inside it every fragment is drawn as before, so the counts are the same to the bit.

BOX_AXES = np.eye(3)
# The 12 edges of a box (axis a, the other two axes at their low or high side), with the two
# faces that meet there as (axis, side) pairs, side 0 low and 1 high.
BOX_EDGES = [(a, (b, sb), (c, sc)) for a in range(3) for b, c in [[i for i in range(3) if i != a]]
             for sb in (0, 1) for sc in (0, 1)]


def shadow_region(low, high, light, receivers) -> np.ndarray:
    """(n, 3) float64: the corners of a convex polytope that holds every point of the
    receivers' box (``receivers`` = (low, high)) inside the shadow volume that ``light``
    casts from an occluder inside the box ``low`` to ``high``; (0, 3) if there is none.

    The volume lies in the cone from the light's position over the occluder's box (a prism
    along a directional light's direction), bounded by the planes through the light and the
    box's silhouette edges, and behind every box face that faces the light: for such a
    face, n . (o - p0) <= 0 and n . (o - L) < 0 give n . (o + s (o - L) - p0) <= 0 for all
    s >= 0. The corners are the points where three of these planes meet that lie on the
    inner side of all of them (a brute-force vertex enumeration: 20 planes at most)."""
    low, high = np.asarray(low, np.float64), np.asarray(high, np.float64)
    position, direction = light_source(light)
    centre = (low + high) / 2
    normals, offsets = [], []                     # the polytope: normal . x <= offset

    def facing(axis, side):
        n = BOX_AXES[axis] * (1 if side else -1)
        p0 = high if side else low
        return bool(n @ (position - p0) > 0) if position is not None else bool(n @ direction < 0)

    for axis in range(3):
        for side in (0, 1):
            if facing(axis, side):
                n = BOX_AXES[axis] * (1 if side else -1)
                normals.append(n)
                offsets.append(n @ (high if side else low))
    for a, (b, sb), (c, sc) in BOX_EDGES:
        if facing(b, sb) == facing(c, sc):
            continue                              # not on the silhouette
        start = low.copy()                        # the edge's end at low[a]
        start[b], start[c] = (low, high)[sb][b], (low, high)[sc][c]
        along = BOX_AXES[a] * (high[a] - low[a])
        n = np.cross(along, direction if position is None else position - start)
        if n @ (centre - start) > 0:
            n = -n                                # the occluder on the inner side
        if np.linalg.norm(n) > 0:
            normals.append(n)
            offsets.append(n @ start)
    for axis in range(3):                         # the receivers' box
        normals += [BOX_AXES[axis], -BOX_AXES[axis]]
        offsets += [receivers[1][axis], -receivers[0][axis]]
    normals, offsets = np.array(normals), np.array(offsets)
    length = np.linalg.norm(normals, axis=1)
    normals, offsets = normals / length[:, None], offsets / length
    triples = np.array(list(combinations(range(len(normals)), 3)))
    matrices, rights = normals[triples], offsets[triples]
    solvable = np.abs(np.linalg.det(matrices)) > 1e-9
    corners = np.linalg.solve(matrices[solvable], rights[solvable][..., None])[..., 0]
    scale = 1e-9 * (1 + np.abs(corners).max(initial=0.0))
    inside = np.all(corners @ normals.T <= offsets + scale, axis=1)
    return np.unique(corners[inside], axis=0)      # a corner where four planes meet: once


def region_rectangles(regions, camera: Camera, width: int, height: int) -> list[tuple]:
    """The pixels (x, y, w, h) that the convex hull of each region's corners (n, 3) can cover
    in front of the near plane, as scissor rectangles (GL's window, y the image's row: the
    picture is drawn upside down), projected as glsl/raster/mesh.vert projects, with a pixel
    to spare; (0, 0, 0, 0) for one that covers none. A hull that crosses the near plane is
    cut there first: its corners in front, and where the segments between corners in front
    and behind cross it. All regions are projected at once (a frame has dozens)."""
    forward, right, up = camera_basis(camera)
    eye = np.asarray(camera.position, np.float64)
    kept = []
    for points in regions:
        offset = np.asarray(points, np.float64).reshape(-1, 3) - eye
        z = offset @ forward
        front, behind = z >= NEAR, z < NEAR
        if behind.any() and front.any():
            i, j = np.nonzero(front[:, None] & behind[None, :])
            s = ((z[i] - NEAR) / (z[i] - z[j]))[:, None]
            offset = np.concatenate([offset[front], offset[i] + s * (offset[j] - offset[i])])
        kept.append(offset[:0] if behind.all() else offset)
    rectangles = [(0, 0, 0, 0)] * len(kept)
    drawn = [k for k, offset in enumerate(kept) if len(offset)]
    if not drawn:
        return rectangles
    offset = np.concatenate([kept[k] for k in drawn])
    starts = np.cumsum([0] + [len(kept[k]) for k in drawn[:-1]])
    z = np.maximum(offset @ forward, NEAR)
    half_height = np.tan(np.radians(camera.fov) / 2)
    x = ((offset @ right) / (z * half_height * width / height) + 1) * width / 2
    y = (1 - (offset @ up) / (z * half_height)) * height / 2
    low = np.maximum(np.floor(np.c_[np.minimum.reduceat(x, starts),
                                    np.minimum.reduceat(y, starts)]) - 1, 0).astype(int)
    high = np.minimum(np.ceil(np.c_[np.maximum.reduceat(x, starts),
                                    np.maximum.reduceat(y, starts)]) + 1,
                      [width, height]).astype(int)
    size = np.maximum(high - low, 0)
    for k, (x0, y0), (w, h) in zip(drawn, low.tolist(), size.tolist()):
        rectangles[k] = (x0, y0, w, h)
    return rectangles


class ShadowVolumes:
    """The shadow volumes of one list of meshes on one context, kept on the GPU between
    frames: the meshes' depth buffers uploaded once, each light's volumes built again only
    when the light changes (a moved camera needs none: the volumes are in world space), the
    depth and count textures made once per size. `draw` draws a frame's counts.

    Parameters
    ----------
    meshes : list of TriangleMesh
        Every opaque mesh, in world coordinates: all of them write depth, the closed ones
        (`reference_cpu.shadow_volumes.neighbours`) cast.
    ctx : moderngl.Context
    z_pass : bool
        Count by z-pass without caps where that is exact (default); False: depth-fail with
        caps everywhere, the textbook version.
    """

    def __init__(self, meshes: list[TriangleMesh], ctx, z_pass: bool = True):
        self.ctx, self.z_pass = ctx, z_pass
        self.meshes = [m for m in meshes if len(m.triangles)]
        self.across = [neighbours(m) for m in self.meshes]     # None: open, casts nothing
        self.solid = [bounds_a_solid(m, closed=a is not None)     # back faces hidden from
                      for m, a in zip(self.meshes, self.across)]  # outside (back_faces.py)
        self.spheres = [bounding_sphere(m) for m in self.meshes]
        # Bounding boxes, a little larger than the vertices' (rounding): each occluder's, and
        # the receivers' (every mesh drawn), which holds every surface a count is read on.
        self.boxes = [_grown(m.positions.min(axis=0), m.positions.max(axis=0))
                      for m in self.meshes]
        self.receivers = _grown(np.min([b[0] for b in self.boxes] or [np.zeros(3)], axis=0),
                                np.max([b[1] for b in self.boxes] or [np.zeros(3)], axis=0))
        self.program = _program(ctx)
        self.scene = [_upload(ctx, self.program, np.c_[m.positions, np.ones(len(m.positions))],
                              m.triangles) for m in self.meshes]
        self.volumes: dict = {}             # (mesh index, light index): (light, GL objects)
        self.targets: dict = {}             # (W, H, lights): depth, counts, framebuffers

    def draw(self, lights, camera: Camera, width: int, height: int) -> ShadowCounts:
        """Draw the scene's depth and every light's shadow volumes (the textures returned
        belong to this object: drawn again next frame, released by `release`). Each volume
        is counted by z-pass without caps where that is exact (`needs_depth_fail`), else
        by depth-fail with its caps, and only within the rectangle where it can shadow a
        surface (`shadow_region`, `region_rectangles`)."""
        ctx, program = self.ctx, self.program
        depth, counts, scene, fbos = self._target(width, height, len(lights))
        try:
            _set_camera(program, camera, width, height)
            program["depth_scale"].value = DEPTH_SCALE
            scene.use()
            scene.viewport = (0, 0, width, height)
            scene.clear(depth=1.0)
            ctx.enable(ctx.DEPTH_TEST)
            ctx.front_face = "cw"                  # drawn upside down (gpu_shader/raster.py)
            # The lit pass culls the same solids' back faces by the same rule
            # (gpu_shader/raster_render.py), so where a back face would win a silhouette pixel
            # by rounding, both passes drop it and the counts are taken at the depth shown.
            cull = culled_meshes(self.solid, self.boxes, camera, width, height)
            for (_, _, vao), culled in zip(self.scene, cull):  # every mesh writes depth,
                (ctx.enable if culled else ctx.disable)(ctx.CULL_FACE)    # closed or not
                vao.render()
            ctx.disable(ctx.CULL_FACE)             # a volume's sides count either way
            ctx.enable(ctx.BLEND)
            ctx.blend_func = ctx.ONE, ctx.ONE
            ctx.blend_equation = ctx.FUNC_ADD
            for i, (light, fbo) in enumerate(zip(lights, fbos)):
                fbo.use()
                fbo.viewport = (0, 0, width, height)
                fbo.depth_mask = False
                fbo.clear(0.0, 0.0, 0.0, 0.0)
                casters = [k for k in range(len(self.meshes)) if self.across[k] is not None]
                volumes = [self._volume(k, i, light) for k in casters]
                rectangles = region_rectangles([region for _, _, region in volumes], camera,
                                               width, height)
                for k, (vao, (caps, sides), _), rectangle in zip(casters, volumes, rectangles):
                    if rectangle[2] == 0 or rectangle[3] == 0:
                        continue                        # it shadows nothing on the screen
                    fbo.scissor = rectangle
                    sphere = self.spheres[k]
                    if not self.z_pass or needs_depth_fail(sphere, light, camera, width,
                                                           height):
                        ctx.depth_func = ">="          # depth-fail: count where LESS fails
                        program["front_count"].value = -1.0
                        vao.render()
                    else:
                        ctx.depth_func = "<"           # z-pass: count where LESS passes
                        program["front_count"].value = 1.0
                        vao.render(first=3 * caps, vertices=3 * sides)
                fbo.depth_mask = True
                fbo.scissor = None
        finally:
            for fbo in fbos:
                fbo.scissor = None
            ctx.disable(ctx.DEPTH_TEST | ctx.BLEND | ctx.CULL_FACE)
            ctx.depth_func = "<"
            ctx.blend_func = ctx.DEFAULT_BLENDING
            ctx.front_face = "ccw"
        return ShadowCounts(depth, counts)

    def release(self, keep=()) -> None:
        """Free every GL object made here but the textures in ``keep``."""
        made = [o for objects in self.scene for o in objects]
        made += [o for _, (objects, _, _) in self.volumes.values() for o in objects]
        for depth, counts, scene, fbos in self.targets.values():
            made += [*fbos, scene] + [t for t in [depth, *counts] if t not in keep]
        for gl_object in made:
            gl_object.release()
        self.scene, self.volumes, self.targets = [], {}, {}

    def _volume(self, k: int, i: int, light):
        """Mesh k's volume for light i: its vertex array and (front cap, side) triangle
        counts, built again only when that light has changed."""
        key, seen = (k, i), repr(light)
        if key in self.volumes and self.volumes[key][0] != seen:
            for gl_object in self.volumes.pop(key)[1][0]:
                gl_object.release()
        if key not in self.volumes:
            mesh = self.meshes[k]
            caps, sides, back = volume_parts(mesh, light, self.across[k])
            objects = _upload(self.ctx, self.program, volume_vertices(mesh, light),
                              np.concatenate([caps, sides, back]))
            region = shadow_region(*self.boxes[k], light, self.receivers)
            self.volumes[key] = (seen, (objects, (len(caps), len(sides)), region))
        objects, parts, region = self.volumes[key][1]
        return objects[2], parts, region

    def _target(self, width: int, height: int, lights: int):
        key = (width, height, lights)
        if key not in self.targets:
            depth = self.ctx.depth_texture((width, height))
            depth.compare_func = ""              # read as a depth, not a shadow comparison
            counts = [self.ctx.texture((width, height), 1, dtype="f4") for _ in range(lights)]
            self.targets[key] = (depth, counts, self.ctx.framebuffer(depth_attachment=depth),
                                 [self.ctx.framebuffer(color_attachments=[c],
                                                       depth_attachment=depth) for c in counts])
        return self.targets[key]


def draw_shadow_counts(ctx, meshes: list[TriangleMesh], lights, camera: Camera, width: int,
                       height: int) -> ShadowCounts:
    """Draw the scene's depth and every light's shadow volumes; leave the counts on the GPU
    (for a lit pass to sample). The caller releases the returned textures."""
    volumes = ShadowVolumes(meshes, ctx)
    drawn = None
    try:
        drawn = volumes.draw(lights, camera, width, height)
    finally:
        volumes.release(keep=[drawn.depth, *drawn.counts] if drawn else ())
    return drawn


def shadow_volume_visibility(meshes: list[TriangleMesh], lights, camera: Camera, width: int,
                             height: int) -> list[np.ndarray]:
    """The visibility (H, W) of each light, 0 in shadow and 1 lit or where nothing is drawn:
    `reference_cpu.shadow_volumes.shadow_volume_visibility` done by OpenGL for every light."""
    ctx = gl_context()
    with ctx:
        drawn = draw_shadow_counts(ctx, meshes, lights, camera, width, height)
        try:
            depth = np.frombuffer(drawn.depth.read(), np.float32).reshape(height, width)
            counts = [np.frombuffer(c.read(), np.float32).reshape(height, width)
                      for c in drawn.counts]
        finally:
            drawn.release()
    hit = depth < 1.0
    return [np.where(hit & (c != 0), 0.0, 1.0) for c in counts]


def _grown(low, high) -> tuple[np.ndarray, np.ndarray]:
    """A box (low, high) grown by a millionth of its size and a micrometre each way."""
    margin = 1e-6 * (1 + np.abs(high - low).max()) + 1e-6
    return np.asarray(low, np.float64) - margin, np.asarray(high, np.float64) + margin


_programs: dict[int, object] = {}


def _program(ctx):
    """The shadow volume program on ``ctx``, compiled on first use and kept."""
    if id(ctx) not in _programs:
        _programs[id(ctx)] = ctx.program(
            vertex_shader=glsl_file("raster/shadow_volume.vert"),
            fragment_shader=glsl_file("raster/shadow_volume.frag"))
    return _programs[id(ctx)]


def _upload(ctx, program, vertices: np.ndarray, triangles: np.ndarray) -> tuple:
    """Indexed triangles of homogeneous vertices (N, 4) on the GPU: (vbo, ibo, vao)."""
    vbo = ctx.buffer(np.ascontiguousarray(vertices, np.float32).tobytes())
    ibo = ctx.buffer(np.ascontiguousarray(triangles, np.int32).tobytes())
    vao = ctx.vertex_array(program, [(vbo, "4f", "position")], index_buffer=ibo,
                           index_element_size=4)
    return vbo, ibo, vao
