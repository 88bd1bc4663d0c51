"""Shadow maps: the scene's depth seen from the light, looked up from each pixel's surface.

Williams (1978, "Casting curved shadows on curved surfaces") draws the scene once from the
light, keeping only depth: the *shadow map*. A surface point is lit when it is no farther
from the light than the map's depth where it projects; farther, something nearer the light
hides it. Cheap and general, but the map is a picture, and three artefacts follow
(docs/raster-shadows.md measures them against the exact shadows):

- **acne**: a texel holds the depth at its centre, and a surface tilted away from the
  light is deeper than that over part of the texel, so it shadows itself in stripes. A
  *bias* added to the stored depth cures it; one that grows with the tilt, a *slope bias*
  (glPolygonOffset's factor), cures it where it is worst.
- **peter-panning**: too large a bias lights points whose occluder is nearer than the bias,
  so the shadow comes loose from the object standing in it.
- **aliasing**: the shadow's edge follows the texels' staircase; a larger map makes it
  finer, and *percentage-closer filtering* (Reeves, Salesin and Cook 1987) averages the
  test over a few texels to soften it.

The map's view: a directional light looks along its direction with an orthographic
projection fitted to the scene's bounds. A point light (or a spot light, from its position)
gets **one perspective map** looking from the light at the scene, its field of view the
narrowest square frustum that holds every vertex, where the whole scene lies on one side of
the light within `MAX_HALF_ANGLE` of its axis. A light among the objects gets a **cube map**
instead (Gerasimov, "Omnidirectional shadow mapping", GPU Gems 2004): six square maps of
90 degrees, one along each axis, and a point is looked up in the face its direction from
the light leans towards most (`cube_face`). The maps are drawn by the NumPy rasteriser's
own steps (`reference_cpu.rasterise`) and hold float32 depth, as a GPU's depth texture does:
view depth along the light's (or the face's) axis, in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scene_model.camera import Camera, camera_rays, to_camera, view_to_image
from scene_model.geometry import normalize
from scene_model.meshes import TriangleMesh
from scene_model.scene import DirectionalLight

from .rasterise import Raster, clipped_triangles, draw_triangle, project_corners

MAX_HALF_ANGLE = 75.0        # degrees: a wider perspective map would waste most of its texels
MAX_TILT = 10.0              # the slope bias's tan(theta) is clamped here (grazing light)
# A cube map's faces, in `cube_face`'s order (+x, -x, +y, -y, +z, -z): each one's axis and
# the up direction of its square 90-degree frustum.
CUBE_AXES = ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0),
             (0.0, 0.0, 1.0), (0.0, 0.0, -1.0))
CUBE_UPS = ((0.0, 1.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, -1.0), (0.0, 0.0, 1.0),
            (0.0, 1.0, 0.0), (0.0, 1.0, 0.0))
CUBE_FACES = len(CUBE_AXES)


class NeedsCubeMap(ValueError):
    """A point or spot light whose scene one perspective frustum cannot hold."""


@dataclass(frozen=True)
class LightView:
    """How a shadow map sees the scene.

    Attributes
    ----------
    size : int
        The map is size x size texels.
    camera : Camera or None
        A perspective view (point and spot lights), or None for an orthographic one.
    frame : (3, 3) float64 ndarray
        Orthographic only: rows right, up, forward (the light's direction), unit vectors.
    low : (2,) float64 ndarray
        Orthographic only: the (right, up) coordinates (m) of the map's bottom-left corner.
    texel : float
        Orthographic only: the side of a texel (m).
    """
    size: int
    camera: Camera | None = None
    frame: np.ndarray | None = None
    low: np.ndarray | None = None
    texel: float = 0.0


def _basis(forward: np.ndarray) -> np.ndarray:
    """Rows right, up, forward about a unit ``forward``, up near world +y (or -z)."""
    up = np.array([0.0, 1.0, 0.0]) if abs(forward[1]) < 0.99 else np.array([0.0, 0.0, -1.0])
    right = normalize(np.cross(forward, up))
    return np.stack([right, np.cross(right, forward), forward])


def light_view(meshes: list[TriangleMesh], light, size: int) -> LightView:
    """The shadow map's view of ``meshes`` from ``light``, ``size`` x ``size`` texels."""
    points = np.concatenate([m.positions for m in meshes])
    if isinstance(light, DirectionalLight):
        frame = _basis(normalize(np.asarray(light.direction, np.float64)))
        flat = points @ frame[:2].T
        low, high = flat.min(axis=0), flat.max(axis=0)
        side = float(np.max(high - low)) * (1 + 1e-9)
        return LightView(size, frame=frame, low=(low + high) / 2 - side / 2, texel=side / size)
    eye = np.asarray(light.position, np.float64)
    axis = normalize((points.min(axis=0) + points.max(axis=0)) / 2 - eye)
    frame = _basis(axis)
    view = (points - eye) @ frame.T
    if np.any(view[:, 2] <= 0):
        raise NeedsCubeMap("a perspective shadow map needs the whole scene in front of the "
                           "light; this light is among the objects (it needs a cube map)")
    # The square frustum must hold every vertex: tan(fov / 2) >= |x| / z and |y| / z.
    half = math.degrees(math.atan(float(np.max(np.abs(view[:, :2]) / view[:, 2:]))))
    if half > MAX_HALF_ANGLE:
        raise NeedsCubeMap(f"the scene spans {2 * half:.0f} degrees from the light; a "
                           f"perspective shadow map covers at most {2 * MAX_HALF_ANGLE:.0f}")
    camera = Camera(position=tuple(eye), look_at=tuple(eye + axis), up=tuple(frame[1]),
                    fov=2 * half * (1 + 1e-6))
    return LightView(size, camera=camera)


def light_views(meshes: list[TriangleMesh], light, size: int) -> list[LightView]:
    """The maps ``light`` needs: its one view (`light_view`), or, for a point or spot light
    whose scene does not fit one frustum (the light among the objects), the six faces of a
    cube map (`cube_views`)."""
    try:
        return [light_view(meshes, light, size)]
    except NeedsCubeMap:
        return cube_views(light.position, size)


def cube_views(position, size: int) -> list[LightView]:
    """The six 90-degree perspective views of a cube map from ``position``, size x size
    texels each, in `cube_face`'s order."""
    eye = np.asarray(position, np.float64)
    return [LightView(size, camera=Camera(position=tuple(float(v) for v in eye),
                                          look_at=tuple(float(v) for v in eye + axis),
                                          up=up, fov=90.0))
            for axis, up in zip(CUBE_AXES, CUBE_UPS)]


def cube_face(points: np.ndarray, position) -> np.ndarray:
    """(N,) int: the cube map face each of ``points`` (N, 3) falls in, seen from
    ``position``: its largest coordinate axis k of p - position, face 2 k for a positive
    coordinate and 2 k + 1 for a negative one. A square 90-degree frustum holds exactly the
    directions whose largest coordinate is its axis's, so the point lies inside that face's
    map (on its edge where two coordinates tie; the first axis wins)."""
    offset = np.asarray(points, np.float64) - np.asarray(position, np.float64)
    axis = np.argmax(np.abs(offset), axis=-1)
    negative = np.take_along_axis(offset, axis[:, None], axis=-1)[:, 0] < 0
    return 2 * axis + negative


def map_coordinates(view: LightView, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where points (N, 3) fall in the map: (N, 2) x, y in texels from its top-left corner,
    and (N,) their depth along the light's axis (m)."""
    if view.camera is not None:
        local = to_camera(points, view.camera)
        return view_to_image(local, view.camera, view.size, view.size), local[:, 2]
    local = points @ view.frame.T
    x = (local[:, 0] - view.low[0]) / view.texel
    y = view.size - (local[:, 1] - view.low[1]) / view.texel
    return np.stack([x, y], axis=-1), local[:, 2]


def texel_width(view: LightView, depth: np.ndarray) -> np.ndarray:
    """The side (m) of one texel at ``depth`` (N,) along the light's axis."""
    if view.camera is None:
        return np.full(depth.shape, view.texel)
    return 2 * depth * math.tan(math.radians(view.camera.fov) / 2) / view.size


def depth_map(meshes: list[TriangleMesh], view: LightView) -> np.ndarray:
    """The shadow map (S, S) float32: the nearest depth along the light's axis (m) drawn at
    each texel's centre, inf where nothing is. Triangles are filled by the rasteriser's own
    edge functions and top-left rule (`reference_cpu.rasterise.draw_triangle`); with unit
    depths its weights are the image's barycentrics, which is what an orthographic
    projection interpolates with."""
    size = view.size
    depth = np.full((size, size), np.inf, np.float32)
    for mesh in meshes:
        if view.camera is not None:
            corners = (project_corners(c, view.camera, size, size)[:2]
                       for _, c in clipped_triangles(mesh, view.camera))
        else:
            xy, depths = map_coordinates(view, mesh.positions)
            corners = ((xy[t], depths[t]) for t in mesh.triangles)
        for image, z in corners:
            perspective = view.camera is not None
            drawn = draw_triangle(image, z if perspective else np.ones(3), False, (size, size))
            if drawn is None:
                continue
            (x0, y0), inside, weights = drawn
            rows, cols = np.nonzero(inside)
            d = (weights[inside] @ z).astype(np.float32)
            rows, cols = rows + y0, cols + x0
            depth[rows, cols] = np.minimum(depth[rows, cols], d)
    return depth


def surface_points(raster: Raster, camera: Camera) -> np.ndarray:
    """The surface point (H, W, 3) each pixel shows: eye + t d (nan where nothing is)."""
    height, width = raster.depth.shape
    origin, directions = camera_rays(camera, width, height)
    with np.errstate(invalid="ignore"):
        return origin + np.where(raster.hit, raster.depth, np.nan)[..., None] * directions


def shadow_map_visibility(meshes: list[TriangleMesh], raster: Raster, camera: Camera, light,
                          size: int, bias: float, slope_bias: float = 0.0,
                          pcf: int = 1) -> np.ndarray:
    """Visibility (H, W) of one light by a shadow map: 1 lit, 0 shadowed, between with PCF.

    Parameters
    ----------
    meshes : list of TriangleMesh
        Every mesh casts (open ones too: a map does not need a closed surface).
    raster : Raster
        What ``camera`` sees; its depth and normals give each pixel's surface point.
    camera : Camera
    light : PointLight, SpotLight or DirectionalLight
    size : int
        The map's side in texels.
    bias : float
        Metres the stored depth is pushed away from the light before the test.
    slope_bias : float
        Texels of slope: adds slope_bias x (texel width) x tan(theta), the depth a surface
        at angle theta to the light gains across one texel (clamped at `MAX_TILT`).
    pcf : int
        Percentage-closer filtering over pcf x pcf texels (odd); 1 is the plain test.

    Returns
    -------
    (H, W) float64 ndarray
        The fraction of the pcf x pcf tests passed; 1 where nothing is drawn.
    """
    if pcf < 1 or pcf % 2 == 0:
        raise ValueError(f"pcf must be an odd number of texels (got {pcf})")
    views = light_views(meshes, light, size)
    hit = raster.hit
    points = surface_points(raster, camera)[hit]
    normals = raster.normal[hit]
    if isinstance(light, DirectionalLight):
        to_light = -normalize(np.asarray(light.direction, np.float64))
    else:
        to_light = normalize(np.asarray(light.position, np.float64) - points)
    cosine = np.clip(np.abs(np.sum(normals * to_light, axis=-1)), 1e-12, 1.0)
    tilt = np.minimum(np.sqrt(1 - cosine ** 2) / cosine, MAX_TILT)
    # One map, or each point in its cube face's; the filter stays inside the face (its
    # texels clamped at the face's edge, as the GPU's lookup clamps them).
    face = (cube_face(points, light.position) if len(views) == CUBE_FACES
            else np.zeros(len(points), np.int64))
    lit = np.zeros(len(points))
    for k, view in enumerate(views):
        mine = face == k
        if mine.any():
            lit[mine] = _percentage_lit(depth_map(meshes, view), view, points[mine],
                                        tilt[mine], bias, slope_bias, pcf)
    visibility = np.ones(raster.depth.shape)
    visibility[hit] = lit / pcf ** 2
    return visibility


def _percentage_lit(stored, view: LightView, points, tilt, bias, slope_bias, pcf):
    """How many of the pcf x pcf texels round each point's (N,) hold a depth it is no deeper
    than, give or take the bias and slope bias."""
    size = view.size
    image, depth = map_coordinates(view, points)
    allowed = bias + slope_bias * texel_width(view, depth) * tilt
    column, row = (np.floor(image[:, k]).astype(np.int64) for k in (0, 1))
    lit = np.zeros(len(points))
    reach = pcf // 2
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            texel = stored[np.clip(row + dy, 0, size - 1), np.clip(column + dx, 0, size - 1)]
            lit += depth <= texel + allowed
    return lit
