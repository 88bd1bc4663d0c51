"""The scene as plain data: camera, render settings, materials, lights, the SDF tree and bodies.

A `Scene` is what every backend reads and none owns. It is immutable: change a copy with
``dataclasses.replace``. `marchlab.load_scene` / `marchlab.save_scene` move it to and from TOML;
docs/scene-format.md describes every field (generated from the ``doc`` strings below).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar, Literal

from .bodies import FRICTION, Body, PhysicsSettings, body_node
from .motion import Motion, posed_objects
from .keyframes import Keyframes, Orbit
from .errors import SceneError
from .fields import (DIRECTION, POINT, SIZE, Color, Range, Record, Vec3, color_range, number_text,
                     param, unit_interval)
from .shapes import Node, children, primitives


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


@dataclass(frozen=True)
class Material(Record):
    """Phong material (Phong 1975; mirror weight after Whitted 1980): colour and the
    ambient/diffuse/specular/mirror weights."""
    color: Color = param((0.8, 0.8, 0.8), "Albedo (linear RGB).", color_range)
    ka: float = param(0.1, "Ambient weight.", unit_interval)
    kd: float = param(0.8, "Diffuse weight.", unit_interval)
    ks: float = param(0.3, "Specular weight.", unit_interval)
    shininess: float = param(32.0, "Specular exponent alpha.", Range(1.0, 10000.0))
    kr: float = param(0.0, "Mirror reflectivity: weight of the reflected colour.", unit_interval)
    checker: Checker | None = param(None, "Optional checker pattern replacing ``color``.")
    restitution: float | None = param(None, "Coefficient of restitution of a static object of "
                                            "this material, for the bodies; absent: "
                                            "[physics] plane_restitution.", unit_interval)
    friction: float | None = param(None, "Coefficient of friction of a static object of this "
                                         "material, for the bodies; absent: [physics] "
                                         "plane_friction.", FRICTION)


# --- Lights ----------------------------------------------------------------------------------

INTENSITY = Range(0.0, 1e6)
# With constant > 0 and linear, quadratic >= 0, the attenuation 1 / (constant + linear d +
# quadratic d^2) is at most 1 / constant <= 1000 for every distance d >= 0: never 1 / 0.
CONSTANT = Range(1e-3, 1e6, positive=True)
ATTENUATION = Range(0.0, 1e6)
SPOT_EDGE = 0.1       # degrees: the narrowest soft edge of a spot light


class Light(Record):
    """Base of the light types; ``kind`` is the ``type`` in a scene file."""
    kind: ClassVar[str] = ""


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


@dataclass(frozen=True)
class DirectionalLight(Light):
    """Light from infinitely far away, travelling along ``direction`` (like the sun)."""
    kind: ClassVar[str] = "directional"
    direction: Vec3 = param((-0.4, -1.0, -0.6), "Direction the light travels in.", DIRECTION)
    color: Color = param((1.0, 1.0, 1.0), "Colour.", color_range)
    intensity: float = param(1.0, "Multiplier of the colour.", INTENSITY)


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

    def check(self):
        # The soft edge divides by cos(inner) - cos(outer); float32 must still tell them apart.
        if self.inner_angle > self.outer_angle - SPOT_EDGE:
            raise SceneError(f"must be less than outer_angle {self.outer_angle} by at least "
                             f"{SPOT_EDGE} degrees (got {self.inner_angle})", ("inner_angle",))


# --- Background, fog, render settings ----------------------------------------------------------

class Background(Record):
    """Base of the background types: what a ray that hits nothing sees."""
    kind: ClassVar[str] = ""


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


@dataclass(frozen=True)
class Fog(Record):
    """Exponential distance fog: colour mixed in by 1 - exp(-density t)."""
    color: Color = param((0.8, 0.85, 0.9), "Fog colour.", color_range)
    density: float = param(0.0, "Extinction per metre (0: no fog).", Range(0.0, 100.0))


# A ray still marching after 100 000 steps is creeping along a surface: more steps change
# nothing visible and only cost time. Each mirror bounce is a whole march more.
MAX_STEPS = 100_000
MAX_REFLECTION_DEPTH = 16


Shading = Literal["phong", "blinn_phong", "toon", "normals", "depth", "steps"]


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
    normal_method: Literal["central", "tetrahedron"] = param(
        "central", "Gradient estimate: central differences (6 evaluations) or Quilez's "
                   "tetrahedron (4).")
    normal_step: float = param(1e-3, "Finite-difference step h of the normal estimate.",
                               Range(1e-9, 1.0, positive=True))
    shadows: Literal["none", "hard", "soft"] = param("none", "Shadow rays toward each light.")
    penumbra_k: float = param(8.0, "Soft shadows: sharpness k of the penumbra (larger: harder).",
                              Range(0.1, 1000.0, positive=True))
    surface_offset: float = param(0.01, "Secondary rays start this far out along the normal.",
                                  Range(0.0, 1.0))
    reflection_depth: int = param(0, "Mirror bounces after the first hit.",
                                  Range(0, MAX_REFLECTION_DEPTH))
    shading: Shading = param("phong", "Shading mode.")
    toon_bands: int = param(4, "Toon shading: number of brightness bands (an 8-bit image "
                               "shows at most 256).", Range(2, 256))
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


def rendered_scene(scene: Scene) -> Scene:
    """``scene`` with its bodies turned into objects (and none left as bodies), as a renderer
    wants it; a scene without bodies is returned unchanged."""
    if not scene.bodies:
        return scene
    return dataclasses.replace(scene, objects=scene_objects(scene), bodies=())
