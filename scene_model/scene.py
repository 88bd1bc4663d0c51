"""The scene as plain data: camera, render settings, materials, lights, the SDF tree and bodies.

A `Scene` is what every backend reads and none owns. It is immutable: change a copy with
``dataclasses.replace``. `marchlab.load_scene` / `marchlab.save_scene` move it to and from TOML;
docs/scene-format.md describes every field (generated from the ``doc`` strings below).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from typing import ClassVar, Literal

from .bodies import FRICTION, Body, PhysicsSettings, body_node
from .motion import Motion, posed_objects
from .keyframes import Keyframes, Orbit
from .errors import SceneError
from .sampling import MAX_SAMPLES, SamplePattern
from .fields import (DIRECTION, POINT, SIZE, Color, Each, Range, Record, Rule, Vec3,
                     color_range, number_text, param, unit_interval)
from .shapes import Node, children, primitives
from .mesh_objects import MeshObject, mesh_material_names


@dataclass(frozen=True)
class Camera(Record):
    """A pinhole camera; the ray of each pixel is defined under "The camera" above."""
    position: Vec3 = param((0.0, 1.0, 5.0), "Eye position.", POINT)
    look_at: Vec3 = param((0.0, 0.0, 0.0), "Point the camera looks at.", POINT)
    up: Vec3 = param((0.0, 1.0, 0.0), "Approximate up direction.", DIRECTION)
    fov: float = param(60.0, "Vertical field of view in degrees.", Range(1e-3, 179.0))

    def check(self):
        forward = [a - b for a, b in zip(self.look_at, self.position)]
        if not any(forward):
            raise SceneError("must differ from position", ("look_at",))
        cross = _cross(forward, self.up)
        if math.hypot(*cross) <= 1e-9 * math.hypot(*forward) * math.hypot(*self.up):
            raise SceneError("must not be parallel to the view direction", ("up",))


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


# --- Materials -------------------------------------------------------------------------------

@dataclass(frozen=True)
class Checker(Record):
    """Checkerboard albedo in the xz-plane: squares of side ``scale`` (for floors)."""
    color_a: Color = param((0.9, 0.9, 0.9), "Colour of the squares where floor(x/s)+floor(z/s) "
                                            "is even.", color_range)
    color_b: Color = param((0.2, 0.2, 0.2), "Colour of the other squares.", color_range)
    scale: float = param(1.0, "Side of a square.", SIZE)


# Built-in images a Texture may name instead of a file (scene_model/textures.py makes them).
BUILTIN_TEXTURES = ("uv_grid",)


def _is_file_name(value: str) -> bool:
    """Whether a Texture's ``image`` names a file (it has an extension or a folder), not a
    built-in image."""
    return "." in os.path.basename(value) or os.sep in value or "/" in value


@dataclass(frozen=True)
class Texture(Record):
    """An image on a surface in place of the material's colour, filtered bilinearly and
    repeated every ``scale`` world units (docs/phong.md, "Textures"): mapped by ``triplanar``
    projection along the three world axes, blended by the normal (Geiss 2007), or by ``uv``,
    a sphere's latitude and longitude and, on any other primitive, the projection along the
    world axis nearest its normal (exact on planes and boxes aligned with the axes)."""
    image: str = param("uv_grid", "An image file (relative to the scene file; PNG, JPEG, "
                                  "TIFF or a .npy array, as an environment's), or a built-in "
                                  "image: uv_grid.",
                       Rule(lambda v: bool(v.strip()), "must name an image file or a "
                                                       "built-in image", "a file or uv_grid"))
    mapping: Literal["triplanar", "uv"] = param("triplanar", "triplanar (three projections "
                                                             "blended by the normal) or uv.")
    scale: float = param(1.0, "World units per repeat of the image (a sphere's uv wraps "
                              "it around once).", SIZE)
    sharpness: float = param(4.0, "Triplanar: the exponent k of the blend weights |n_i|^k "
                                  "(larger: narrower blends between the projections).",
                             Range(1.0, 64.0))
    tint: Color = param((1.0, 1.0, 1.0), "Multiplier of the image's linear colours.",
                        color_range)

    def check(self):
        if not _is_file_name(self.image) and self.image not in BUILTIN_TEXTURES:
            raise SceneError(f"is no built-in image (built-in: {', '.join(BUILTIN_TEXTURES)}"
                             f"; a file needs its extension) (got {self.image!r})", ("image",))

    def relative_to(self, folder) -> "Texture":
        """This texture with its image file read relative to ``folder`` (a built-in image
        stays as it is)."""
        if self.image in BUILTIN_TEXTURES:
            return self
        return dataclasses.replace(self, image=_joined(folder, self.image))


@dataclass(frozen=True)
class Material(Record):
    """Phong material (Phong 1975; mirror and glass weights after Whitted 1980): colour, the
    ambient/diffuse/specular/mirror weights, and for glass its transparency, index of
    refraction and absorption."""
    color: Color = param((0.8, 0.8, 0.8), "Albedo (linear RGB).", color_range)
    ka: float = param(0.1, "Ambient weight.", unit_interval)
    kd: float = param(0.8, "Diffuse weight.", unit_interval)
    ks: float = param(0.3, "Specular weight.", unit_interval)
    shininess: float = param(32.0, "Specular exponent alpha.", Range(1.0, 10000.0))
    kr: float = param(0.0, "Mirror reflectivity: weight of the reflected colour.", unit_interval)
    transparency: float = param(0.0, "Glass: the weight of the light through the surface, "
                                     "split by Fresnel between reflection and refraction (0: "
                                     "opaque).", unit_interval)
    ior: float = param(1.5, "Glass: index of refraction of the solid (air outside is 1).",
                       Range(1.0, 4.0))
    absorption: Color = param((0.0, 0.0, 0.0), "Glass: Beer-Lambert absorption per metre "
                                                "travelled inside, per channel.",
                              Each(Range(0.0, 1e3)))
    checker: Checker | None = param(None, "Optional checker pattern replacing ``color``.")
    texture: Texture | None = param(None, "Optional image replacing ``color`` (not with "
                                          "``checker``).")
    shading: Shading | None = param(None, "This object's shading model where the render's "
                                          "is a lit one (phong, blinn_phong, toon, stripes); "
                                          "absent: the render's.")
    restitution: float | None = param(None, "Coefficient of restitution of a static object of "
                                            "this material, for the bodies; absent: "
                                            "[physics] plane_restitution.", unit_interval)
    friction: float | None = param(None, "Coefficient of friction of a static object of this "
                                         "material, for the bodies; absent: [physics] "
                                         "plane_friction.", FRICTION)

    def check(self):
        if self.checker is not None and self.texture is not None:
            raise SceneError("give checker or texture, not both: each replaces color",
                             ("texture",))


# --- Lights ----------------------------------------------------------------------------------

INTENSITY = Range(0.0, 1e6)
# With constant > 0 and linear, quadratic >= 0, the attenuation 1 / (constant + linear d +
# quadratic d^2) is at most 1 / constant <= 1000 for every distance d >= 0: never 1 / 0.
CONSTANT = Range(1e-3, 1e6, positive=True)
ATTENUATION = Range(0.0, 1e6)
SPOT_EDGE = 0.1       # degrees: the narrowest soft edge of a spot light


class Light(Record):
    """Base of the light types; ``kind`` is the ``type`` in a scene file.

    A light sends ``color`` x ``intensity`` to the diffuse and specular terms. It may instead
    give separate ``ambient``, ``diffuse`` and ``specular`` colours, each also multiplied by
    ``intensity``, as the lights of OpenGL 1.x and LearnOpenGL do ("Lighting maps",
    "Multiple lights"): a missing one of diffuse and specular is ``color``, a missing ambient
    is none. A light's ambient term lights every point it reaches, shadowed or not, fading
    with distance as the rest does (not with a spot light's cone).
    """
    kind: ClassVar[str] = ""

    def separate_colors(self) -> bool:
        """Whether the light gives an ambient, diffuse or specular colour of its own."""
        return any(getattr(self, k) is not None for k in ("ambient", "diffuse", "specular"))

    def term_colors(self) -> tuple[tuple, tuple, tuple]:
        """(ambient, diffuse, specular) colours times intensity; ambient 0 where absent."""
        pick = lambda c: tuple(self.intensity * x for x in (c or self.color))
        ambient = tuple(self.intensity * x for x in self.ambient) if self.ambient else (0.0,) * 3
        return ambient, pick(self.diffuse), pick(self.specular)


def _term(name: str):
    """The field of a light's own ambient, diffuse or specular colour."""
    return param(None, f"Colour of the light's {name} term (times intensity); absent: "
                       + ("none." if name == "ambient" else "``color``."), color_range)


@dataclass(frozen=True)
class PointLight(Light):
    """Light from a point, fading as 1 / (constant + linear d + quadratic d^2) (LearnOpenGL,
    "Light casters")."""
    kind: ClassVar[str] = "point"
    position: Vec3 = param((0.0, 5.0, 0.0), "Position.", POINT)
    color: Color = param((1.0, 1.0, 1.0), "Colour.", color_range)
    intensity: float = param(1.0, "Multiplier of the colour.", INTENSITY)
    constant: float = param(1.0, "Constant attenuation term; more than 0, so the attenuation "
                                 "is at most 1 / constant.", CONSTANT)
    linear: float = param(0.0, "Linear attenuation term.", ATTENUATION)
    quadratic: float = param(0.0, "Quadratic attenuation term.", ATTENUATION)
    ambient: Color | None = _term("ambient")
    diffuse: Color | None = _term("diffuse")
    specular: Color | None = _term("specular")


@dataclass(frozen=True)
class DirectionalLight(Light):
    """Light from infinitely far away, travelling along ``direction`` (like the sun)."""
    kind: ClassVar[str] = "directional"
    direction: Vec3 = param((-0.4, -1.0, -0.6), "Direction the light travels in.", DIRECTION)
    color: Color = param((1.0, 1.0, 1.0), "Colour.", color_range)
    intensity: float = param(1.0, "Multiplier of the colour.", INTENSITY)
    ambient: Color | None = _term("ambient")
    diffuse: Color | None = _term("diffuse")
    specular: Color | None = _term("specular")


@dataclass(frozen=True)
class SpotLight(Light):
    """Point light limited to a cone with a soft edge between two angles (LearnOpenGL, "Light
    casters")."""
    kind: ClassVar[str] = "spot"
    position: Vec3 = param((0.0, 5.0, 0.0), "Position.", POINT)
    direction: Vec3 = param((0.0, -1.0, 0.0), "Axis of the cone, away from the light.",
                            DIRECTION)
    color: Color = param((1.0, 1.0, 1.0), "Colour.", color_range)
    intensity: float = param(1.0, "Multiplier of the colour.", INTENSITY)
    inner_angle: float = param(20.0, "Half-angle in degrees inside which the light is full; "
                                     f"at least {SPOT_EDGE} less than outer_angle.",
                               Range(0.0, 89.0))
    outer_angle: float = param(30.0, "Half-angle in degrees outside which the light is zero.",
                               Range(0.0, 90.0, lo_open=True, hi_open=True))
    constant: float = param(1.0, "Constant attenuation term; more than 0, so the attenuation "
                                 "is at most 1 / constant.", CONSTANT)
    linear: float = param(0.0, "Linear attenuation term.", ATTENUATION)
    quadratic: float = param(0.0, "Quadratic attenuation term.", ATTENUATION)
    ambient: Color | None = _term("ambient")
    diffuse: Color | None = _term("diffuse")
    specular: Color | None = _term("specular")

    def check(self):
        # The soft edge divides by cos(inner) - cos(outer); float32 must still tell them apart.
        if self.inner_angle > self.outer_angle - SPOT_EDGE:
            raise SceneError(f"must be less than outer_angle {self.outer_angle} by at least "
                             f"{SPOT_EDGE} degrees (got {self.inner_angle})", ("inner_angle",))


# --- Background, fog, render settings ----------------------------------------------------------

class Background(Record):
    """Base of the background types: what a ray that hits nothing sees."""
    kind: ClassVar[str] = ""

    def relative_to(self, folder) -> "Background":
        """This background with its image files read relative to ``folder`` (a scene file's
        own folder); one without files is returned as it is."""
        return self


@dataclass(frozen=True)
class SolidBackground(Background):
    """One colour everywhere."""
    kind: ClassVar[str] = "solid"
    color: Color = param((0.0, 0.0, 0.0), "Colour.", color_range)


@dataclass(frozen=True)
class SkyBackground(Background):
    """Vertical gradient: ``bottom`` looking straight down, ``top`` looking straight up."""
    kind: ClassVar[str] = "sky"
    bottom: Color = param((0.85, 0.9, 1.0), "Colour for a ray pointing straight down.",
                          color_range)
    top: Color = param((0.35, 0.55, 0.9), "Colour for a ray pointing straight up.", color_range)


# The environment maps (scene_model/environment.py turns them into texels): what every miss
# sees, mirrors included. Their two numbers are a frame's, not the images'. Image files: PNG,
# JPEG or TIFF of 8 or 16 bits (sRGB, decoded to linear), or floats (a 32-bit TIFF, a .npy
# array), taken as linear.

def _exposure():
    return param(1.0, "Multiplier of the image's linear colours.", INTENSITY)


def _turn():
    return param(0.0, "Degrees the environment is turned about +y (+x toward -z).",
                 Range(-360.0, 360.0))


CUBE_FACES = ("+x", "-x", "+y", "-y", "+z", "-z")


def _joined(folder, path: str) -> str:
    """``path`` read relative to ``folder``; an absolute path stays as it is, to the letter."""
    return path if os.path.isabs(path) else os.path.normpath(os.path.join(folder, path))


@dataclass(frozen=True)
class CubeMapBackground(Background):
    """A cube map: six square images of one size, looked up by the ray's direction as OpenGL
    does (OpenGL 4.6 core spec, section 8.13) and filtered bilinearly."""
    kind: ClassVar[str] = "cubemap"
    faces: tuple[str, ...] = param(
        ("px.png", "nx.png", "py.png", "ny.png", "pz.png", "nz.png"),
        "Six image files, in the order +x, -x, +y, -y, +z, -z (relative to the scene file).",
        Rule(lambda v: len(v) == 6 and all(p.strip() for p in v),
             "must list six image files (+x, -x, +y, -y, +z, -z)", "6 files"))
    intensity: float = _exposure()
    rotation: float = _turn()

    def relative_to(self, folder) -> "CubeMapBackground":
        return dataclasses.replace(self, faces=tuple(_joined(folder, p) for p in self.faces))


@dataclass(frozen=True)
class EquirectBackground(Background):
    """An equirectangular (latitude-longitude) panorama: one image, 360 degrees around and
    180 degrees top to bottom, its centre straight ahead along -z."""
    kind: ClassVar[str] = "equirect"
    image: str = param("panorama.png", "The image file (relative to the scene file).",
                       Rule(lambda v: bool(v.strip()), "must name an image file", "a file"))
    intensity: float = _exposure()
    rotation: float = _turn()

    def relative_to(self, folder) -> "EquirectBackground":
        return dataclasses.replace(self, image=_joined(folder, self.image))


@dataclass(frozen=True)
class StudioBackground(Background):
    """marchlab's own cube map, computed, not loaded (scene_model/environment.py): a grey
    floor, a sky with a sun and four coloured soft boxes, so that a mirror shows where it
    looks."""
    kind: ClassVar[str] = "studio"
    size: int = param(64, "Texels along each side of a cube face.", Range(2, 256))
    intensity: float = _exposure()
    rotation: float = _turn()


@dataclass(frozen=True)
class Fog(Record):
    """Exponential distance fog: colour mixed in by 1 - exp(-density t)."""
    color: Color = param((0.8, 0.85, 0.9), "Fog colour.", color_range)
    density: float = param(0.0, "Extinction per metre (0: no fog).", Range(0.0, 100.0))


# A ray still marching after 100 000 steps is creeping along a surface: more steps change
# nothing visible and only cost time. Each mirror bounce is a whole march more.
MAX_STEPS = 100_000
MAX_REFLECTION_DEPTH = 16


Shading = Literal["phong", "blinn_phong", "toon", "stripes", "normals", "depth", "steps"]
# The lit models: the others show a buffer (normals, depth, steps) instead of light.
LIT_SHADING = ("phong", "blinn_phong", "toon", "stripes")


@dataclass(frozen=True)
class RenderSettings(Record):
    """How rays are marched and shaded; every backend honours these identically."""
    max_steps: int = param(256, "Most SDF evaluations along one ray.", Range(1, MAX_STEPS))
    epsilon: float = param(1e-3, "A ray hits where |distance| < epsilon; less than "
                                 "max_distance.", Range(1e-9, 1.0, positive=True))
    max_distance: float = param(100.0, "A ray misses beyond this distance.",
                                Range(1e-3, 1e7, positive=True))
    relaxation: Literal["none", "fixed", "auto"] = param(
        "none", "Over-relaxed steps: none (Hart's plain steps), fixed (omega times the "
                "distance, Keinert et al. 2014) or auto (omega from the field's slope along "
                "the ray, Ban & Valasek 2023); both step back when two consecutive spheres "
                "do not overlap.")
    omega: float = param(1.2, "Relaxation factor of relaxation = \"fixed\".", Range(1.0, 2.0))
    bounding_spheres: bool = param(False, "Leave out of each ray's march the objects whose "
                                          "bounding sphere it misses (Whitted 1980).")
    prepass: Literal["none", "cone"] = param(
        "none", "Cone-marching pre-pass: none, or cone (one cone per prepass_tile x "
                "prepass_tile pixels is marched first, and each pixel's ray starts where its "
                "tile's cone got to; only empty space is skipped, docs/sphere-tracing.md).")
    prepass_tile: int = param(8, "Cone pre-pass: the tile's width and height in pixels.",
                              Range(2, 64))
    samples: int = param(1, "Anti-aliasing: n x n rays per pixel, its colour their mean "
                            "(1: one ray through the centre; scene_model/sampling.py).",
                         Range(1, MAX_SAMPLES))
    sample_pattern: SamplePattern = param(
        "regular", "Anti-aliasing: where the n x n samples go, a regular grid or the rotated "
                   "grid (RGSS), whose samples all differ in x and in y.")
    normal_method: Literal["central", "tetrahedron"] = param(
        "central", "Gradient estimate: central differences (6 evaluations) or Quilez's "
                   "tetrahedron (4).")
    normal_step: float = param(1e-3, "Finite-difference step h of the normal estimate.",
                               Range(1e-9, 1.0, positive=True))
    shadows: Literal["none", "hard", "soft"] = param("none", "Shadow rays toward each light.")
    shadow_skip_own: bool = param(True, "Hard shadow rays leave out the convex object they "
                                        "start on: leaving it outward, they cannot meet it "
                                        "again (docs/sphere-tracing.md, \"Shadow rays that "
                                        "skip their own object\").")
    penumbra_k: float = param(8.0, "Soft shadows: sharpness k of the penumbra (larger: harder).",
                              Range(0.1, 1000.0, positive=True))
    surface_offset: float = param(0.01, "Secondary rays start this far out along the normal.",
                                  Range(0.0, 1.0))
    reflection_depth: int = param(0, "Depth of the ray tree: mirror and glass bounces "
                                     "after the first hit.", Range(0, MAX_REFLECTION_DEPTH))
    fresnel: Literal["exact", "schlick"] = param(
        "exact", "Glass: Fresnel's equations, or Schlick's approximation of them.")
    shadow_method: Literal["volumes", "map"] = param(
        "volumes", "Meshes: how the raster backends find shadows, by shadow volumes (exact: "
                   "the pixels a shadow ray finds) or by a shadow map (a depth picture from "
                   "the light, with its acne, peter-panning and aliasing; "
                   "docs/raster-shadows.md). The embree backend casts shadow rays.")
    shadow_map_size: int = param(2048, "Meshes, shadow map: texels along each side (of each "
                                       "of a cube map's six faces, for a point or spot light "
                                       "among the objects).", Range(16, 8192))
    shadow_bias: float = param(1e-3, "Meshes, shadow map: metres a stored depth is pushed "
                                     "away from the light before the test (against acne).",
                               Range(0.0, 10.0))
    shadow_slope_bias: float = param(1.5, "Meshes, shadow map: more bias on surfaces tilted "
                                          "from the light, in texels of slope.",
                                     Range(0.0, 100.0))
    shadow_pcf: int = param(1, "Meshes, shadow map: percentage-closer filtering over n x n "
                               "texels (odd; 1: the plain test).",
                            Rule(lambda v: 1 <= v <= 15 and v % 2 == 1,
                                 "must be an odd number from 1 to 15", "1, 3, ..., 15"))
    blending: Literal["depth_peeling", "sorted"] = param(
        "depth_peeling", "Meshes: how transparent surfaces are blended over what is behind "
                         "them, peeled nearest first (order-independent, Everitt 2001) or "
                         "sorted back to front by triangle (the painter's algorithm).")
    peel_layers: int = param(4, "Meshes, depth peeling: the most transparent surfaces "
                                "composited on one pixel.", Range(1, 64))
    shading: Shading = param("phong", "Shading mode.")
    toon_bands: int = param(4, "Toon and stripes shading: number of brightness bands, or of "
                               "stripes (an 8-bit image shows at most 256).", Range(2, 256))
    ambient: Color = param((1.0, 1.0, 1.0), "Ambient light colour i_a.", color_range)
    dither: bool = param(False, "Ordered (8x8 Bayer) dithering of the 8-bit image: a fine "
                                "pattern instead of bands in smooth gradients.")
    gamma: float = param(2.2, "Display gamma applied when an image is saved.",
                         Range(0.1, 10.0, positive=True))
    fog: Fog = param(factory=Fog, doc="Distance fog.")
    background: Background = param(factory=SkyBackground, doc="What a miss sees.")

    def check(self):
        if self.epsilon >= self.max_distance:
            raise SceneError(f"must be less than max_distance {number_text(self.max_distance)} "
                             f"(got {number_text(self.epsilon)})", ("epsilon",))


def _default_lights():
    return (DirectionalLight(),)


def _default_materials():
    return {"default": Material()}


@dataclass(frozen=True)
class Scene(Record):
    """Everything a renderer needs. ``objects`` are joined by union; ``bodies`` are drawn as
    spheres after them and moved by the physics step."""
    description: str = param("", "One line shown by ``marchlab scenes``.")
    camera: Camera = param(factory=Camera, doc="The camera.")
    render: RenderSettings = param(factory=RenderSettings, doc="Render settings.")
    materials: dict[str, Material] = param(factory=_default_materials,
                                           doc="Materials by name.")
    lights: tuple[Light, ...] = param(factory=_default_lights, doc="Light sources.")
    objects: tuple[Node, ...] = param((), "The shapes; their union is the scene.")
    meshes: tuple[MeshObject, ...] = param((), "Triangle meshes, drawn by the raster backends "
                                               "(numpy-raster, raster, embree) instead of "
                                               "objects (docs/rasterisation.md).")
    physics: PhysicsSettings | None = param(None, "How bodies are simulated; absent: the "
                                                  "defaults of [physics].")
    bodies: tuple[Body, ...] = param((), "Dynamic spheres, simulated and drawn.")
    motions: tuple[Motion, ...] = param((), "Kinematic objects: objects moved along a "
                                            "prescribed path, which push the bodies.")
    keyframes: tuple[Keyframes, ...] = param((), "Animated fields: any number or 3-vector "
                                                  "of the scene, given at key times.")
    orbit: Orbit | None = param(None, "The camera turning about what it looks at; absent: "
                                      "it stays.")

    def _repr_html_(self) -> str:
        """A notebook shows a scene as a short summary (its objects as a tree, its lights and
        materials with colour swatches, the main render settings), not as every field: the
        model renders nothing itself, so ``marchlab.render(scene, ...)`` draws it."""
        from html import escape

        def swatch(color):
            rgb = ",".join(str(round(min(max(c, 0.0), 1.0) * 255)) for c in color)
            return (f'<span style="display:inline-block;width:0.9em;height:0.9em;'
                    f'background:rgb({rgb});border:1px solid #888"></span>')

        def tree(node, depth=0):
            material = getattr(node, "material", None)
            line = "&nbsp;" * 4 * depth + escape(node.kind) + (
                f" <i>{escape(material)}</i>" if material else "")
            return [line] + [row for child in children(node) for row in tree(child, depth + 1)]

        r = self.render
        rows = [f"<b>{escape(self.description or 'scene')}</b>",
                "objects:<br>" + "<br>".join(row for node in self.objects
                                             for row in tree(node)),
                "lights: " + ", ".join(f"{swatch(light.color)} {escape(light.kind)}"
                                       for light in self.lights),
                "materials: " + ", ".join(f"{swatch(m.color)} {escape(name)}"
                                          for name, m in self.materials.items()),
                f"render: {escape(r.shading)} shading, {escape(r.shadows)} shadows, "
                f"reflection depth {r.reflection_depth}, epsilon {r.epsilon:g}, "
                f"max_steps {r.max_steps}"]
        if self.bodies:
            rows.append(f"bodies: {len(self.bodies)}")
        return '<div style="font-family:monospace">' + "<br>".join(rows) + "</div>"

    def check(self):
        known = ", ".join(sorted(self.materials)) or "none"
        for index, prim in enumerate(primitives(self.objects)):
            if prim.material not in self.materials:
                raise SceneError(f"primitive {index} ({prim.kind}) uses unknown material "
                                 f"{prim.material!r} (defined: {known})", ("materials",))
        for path, name in mesh_material_names(self.meshes):
            if name not in self.materials:
                raise SceneError(f"unknown material {name!r} (defined: {known})", path)
        for index, body in enumerate(self.bodies):
            if body.material not in self.materials:
                raise SceneError(f"unknown material {body.material!r} (defined: {known})",
                                 ("bodies", index, "material"))
        moved = set()
        for index, motion in enumerate(self.motions):
            if motion.object >= len(self.objects):
                raise SceneError(f"there is no objects[{motion.object}] to move (the scene has "
                                 f"{len(self.objects)} objects)", ("motions", index, "object"))
            if motion.object in moved:
                raise SceneError(f"objects[{motion.object}] already has a motion",
                                 ("motions", index, "object"))
            moved.add(motion.object)


# --- Bodies in the scene ------------------------------------------------------------------

def scene_objects(scene: Scene, positions=None) -> tuple[Node, ...]:
    """The objects a renderer draws: the scene's objects, then one object per body.

    The bodies come last, so the object id of every static object (its depth-first index)
    is the same with or without bodies.

    Parameters
    ----------
    scene : Scene
    positions : (N, 3) array_like, optional
        Centres of the N bodies (default: their positions in the scene).
    """
    if positions is None:
        positions = [None] * len(scene.bodies)
    elif len(positions) != len(scene.bodies):
        raise ValueError(f"expected {len(scene.bodies)} positions, got {len(positions)}")
    return scene.objects + tuple(body_node(body, p) for body, p in zip(scene.bodies, positions))


def scene_at(scene: Scene, positions, time: float | None = None, rotations=None) -> Scene:
    """``scene`` with its bodies moved to ``positions`` ((N, 3), one row per body) and turned
    to ``rotations`` ((N, 3) Euler degrees, optional: a box's or capsule's pose) and, at
    ``time`` (s), its kinematic objects where their motions have them (`motion.posed_objects`;
    the motions are then done with and dropped, so the result is a still).

    Only numbers change, so a generated shader's text (and the GPU's compiled program) is
    the same for every time step.
    """
    if len(positions) != len(scene.bodies):
        raise ValueError(f"expected {len(scene.bodies)} positions, got {len(positions)}")
    if rotations is None:
        rotations = [body.rotation for body in scene.bodies]
    elif len(rotations) != len(scene.bodies):
        raise ValueError(f"expected {len(scene.bodies)} rotations, got {len(rotations)}")
    bodies = tuple(dataclasses.replace(body, position=tuple(float(c) for c in p),
                                       rotation=tuple(float(a) for a in turn))
                   for body, p, turn in zip(scene.bodies, positions, rotations))
    if time is None or not scene.motions:
        return dataclasses.replace(scene, bodies=bodies)
    return dataclasses.replace(scene, bodies=bodies, motions=(),
                               objects=posed_objects(scene.objects, scene.motions, time))


def shading_modes(scene: Scene) -> list[str]:
    """The shading model of every primitive, in object-id order: its material's ``shading``
    where it gives one and the render's is lit; else the render's. (A render shading of
    normals, depth or steps shows that buffer everywhere: a debugging view.)"""
    mode = scene.render.shading
    chosen = [scene.materials[p.material].shading for p in primitives(scene.objects)]
    return [(c or mode) if mode in LIT_SHADING else mode for c in chosen]


def rendered_scene(scene: Scene) -> Scene:
    """``scene`` with its bodies turned into objects (and none left as bodies), as a renderer
    wants it; a scene without bodies is returned unchanged."""
    if not scene.bodies:
        return scene
    return dataclasses.replace(scene, objects=scene_objects(scene), bodies=())
