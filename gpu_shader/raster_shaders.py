"""The lit raster pipeline's shaders: generated for what a scene uses, and the values they read.

`lit_shaders` fills in glsl/raster/lit.frag (the meshes' fragment shader) and
glsl/raster/sky.frag (the skybox's) with the sphere tracer's own GLSL, and gathers the numbers
a frame sets: the material rows, the light arrays, the background's (`LitShaders`).
`_compile` makes programs of them (and of the raster backend's other shaders), each once.
The renderer that draws with them, and `draw`, are in `gpu_shader.raster_lit`.

The same generator makes the shaders of the raster backend's other passes
(`gpu_shader.raster_render`): the mirrored scene behind a flat mirror (``variant="mirror"``),
and the layers of transparent meshes (``variant="peel"`` or ``"sorted"``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import cache

import numpy as np

from scene_model.environment import CUBE_KINDS, ENVIRONMENT_KINDS, environment_map, turn
from scene_model.scene import LIT_SHADING, Background, DirectionalLight, SpotLight
from scene_model.textures import texture_atlas, texture_image

from .dialects import GLSL, STRUCTS
from .generate import BANDS, LIGHT_KINDS, SPECULAR
from .library import fill_template, glsl_file, load_library
from .render import ShaderCompileError, compile_message


# --- The lit pipeline: shaders generated for what the scene uses ------------------------------

# How a textured mesh finds its place in its image, coded in its material rows (0: none): the
# sphere tracer's triplanar projection, or the mesh's own texture coordinates.
MAPPING_CODES = {"triplanar": 1, "uv": 4}
VARIANTS = ("opaque", "mirror", "peel", "sorted")


@dataclass(frozen=True)
class ShadowCount:
    """A light's visibility as a shadow-volume count texture on the GPU
    (`gpu_shader.raster_shadows`): the light reaches the surface where the count is 0."""
    texture: object


@dataclass(frozen=True)
class LitShaders:
    """The lit pipeline's shaders for one scene, and the values they read.

    Attributes
    ----------
    source : str
        The meshes' fragment shader (glsl/raster/lit.frag filled in). Its text depends only
        on what the scene uses (model, kinds of light, patterns, visibility planes), so a
        frame that moves the camera, a light or a colour compiles nothing.
    sky_source : str
        The skybox's fragment shader (glsl/raster/sky.frag); "" for one colour: a clear.
    clear : (3,) float
        The colour the frame is cleared to (the solid background's).
    materials : (K, S, 4) float32 ndarray
        Each object's S material rows (``material`` in the shader).
    uniforms : dict
        Every other number a frame sets, by uniform name: settings, light arrays, the
        background's.
    texels : (R, W, 4) float32 ndarray or None
        The texture atlas: the environment's images, then the textures'.
    """
    source: str
    sky_source: str
    clear: tuple
    materials: np.ndarray
    uniforms: dict
    texels: np.ndarray | None


def lit_shaders(materials, lights, *, ambient=(0.0, 0.0, 0.0), model: str = "phong",
                background=(0.0, 0.0, 0.0), toon_bands: int = 4, visibility=None,
                fog=None, depth_range: float = 100.0, variant: str = "opaque",
                prepass: bool = False) -> LitShaders:
    """The lit pipeline's shaders for a scene (the arguments as `draw`'s; of ``visibility``
    only which lights have a plane, and whether an array, a texture or a `ShadowCount`,
    matters here). ``fog`` is a `scene_model.scene.Fog` (applied where its density > 0),
    ``depth_range`` the distance the "depth" model shows black, and ``variant`` one of
    `VARIANTS`: the plain pass, or one of the raster backend's (`gpu_shader.raster_render`).
    With ``prepass``, the shader reads the scene's depth drawn before it (``scene_depth``,
    a depth texture of z / (z + 1 m)) and skips the shading of fragments well behind it."""
    if model not in ("normals", "depth") and model not in LIT_SHADING:
        raise ValueError(f"unknown shading model {model!r} (one of: "
                         f"{', '.join(LIT_SHADING)}, normals, depth)")
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r} (one of: {', '.join(VARIANTS)})")
    planes = [None] * len(lights) if visibility is None else list(visibility)
    if len(planes) != len(lights):
        raise ValueError(f"expected {len(lights)} visibility planes, got {len(planes)}")
    lit = model in LIT_SHADING                # "normals" and "depth" read no material or light
    # What a mirror shows has its full albedo (checkerboards, textures at the reflected
    # fragment's own uv), as every point the reference shades
    # (reference_cpu/raster_shading.py, shade_points).
    textures = [m.texture if lit else None for m in materials]
    checker = lit and any(m.checker is not None for m in materials)
    mappings = {name: code for name, code in MAPPING_CODES.items()
                if any(t is not None and t.mapping == name for t in textures)}
    environment = (environment_map(background) if isinstance(background, Background)
                   and background.kind in ENVIRONMENT_KINDS else None)
    # One atlas for both programs: the environment's images first (at row 0, where its
    # `texture` says), then each texture's image once (`scene_model.textures.texture_atlas`).
    images = [None if t is None else texture_image(t) for t in textures]
    distinct = list(dict.fromkeys(i for i in images if i is not None))
    first = (environment,) * (environment is not None)
    atlas = texture_atlas(first + tuple(distinct)) if first or distinct else None
    placed = [None if i is None else atlas.image(len(first) + distinct.index(i), 2.0)
              for i in images]                      # surface textures repeat: wrap 2
    stride = 2 + 2 * checker + 3 * bool(mappings)          # rows a material
    rows = np.array([material_rows(m, image, checker, bool(mappings))
                     for m, image in zip(materials, placed)], np.float32).reshape(-1, stride, 4)
    uniforms = {"ambient": tuple(ambient), "toon_bands": float(toon_bands),
                "depth_range": float(depth_range)}
    fogged = lit and fog is not None and fog.density > 0
    if fogged:
        uniforms |= {"fog_color": tuple(fog.color), "fog_density": float(fog.density)}
    described = _lights(lights if lit else [], planes, uniforms)
    source = _lit_source(model, described, checker, mappings, stride, fogged, variant,
                         prepass)
    sky_source, clear = _sky(background, environment, uniforms, variant == "mirror")
    return LitShaders(source, sky_source, clear, rows, uniforms,
                      None if atlas is None else atlas.rgba)


def _lights(lights, planes, uniforms: dict) -> list[dict]:
    """Each light as glsl/pipeline/shade.glsl and glsl/raster/lit.frag take it (index,
    kind, names, own colours, where its visibility comes from); its numbers go into the
    light arrays of ``uniforms``, element i light i's."""
    described, layers = [], 0
    for i, (light, plane) in enumerate(zip(lights, planes)):
        values = light_values(light)
        reads = _light_reads(plane)
        described.append({"index": i, "kind": LIGHT_KINDS[type(light)], "names": list(values),
                          "own": light.separate_colors(), "visibility": reads, "layer": layers})
        layers += reads == "layer"
        for name, value in values.items():
            uniforms.setdefault(f"light_{name.lower()}",
                                np.zeros((len(lights), len(value)), np.float32))[i] = value
    return described


def _lit_source(model: str, lights: list[dict], checker: bool, mappings: dict,
                stride: int, fog: bool = False, variant: str = "opaque",
                prepass: bool = False) -> str:
    """glsl/raster/lit.frag filled in: the library functions the scene's shading calls,
    ``surface_albedo`` (glsl/raster/albedo.glsl) and ``shade_<model>``
    (glsl/pipeline/shade.glsl, the sphere tracer's, without shadow rays)."""
    sections = [("the camera (glsl/camera.glsl)", load_library("camera").select(["camera_ray"]))]
    if lights:
        sections.append(("lights (glsl/lights.glsl)", load_library("lights").select(
            sorted({f"light_{light['kind']}" for light in lights}))))
    wanted = (["shade_normals"] if model == "normals" else ["shade_depth"] if model == "depth"
              else ["checker"] * checker + ["apply_fog"] * fog)
    if lights:
        wanted += ["diffuse", SPECULAR[model]] + ([BANDS[model]] if model in BANDS else [])
    sections.append(("shading (glsl/shading.glsl)", load_library("shading").select(wanted)))
    if mappings:
        needs = ["texture_repeat"] + ["texture_triplanar"] * ("triplanar" in mappings)
        sections.append(("bilinear texture filtering and mappings (glsl/texture.glsl)",
                         load_library("texture").select(needs)))
    if model in LIT_SHADING:
        sections.append(("the albedo (glsl/raster/albedo.glsl)", fill_template(
            "raster/albedo.glsl", checker=checker, mappings=mappings,
            texture_row=2 + 2 * checker if mappings else None)))
        sections.append((f"the {model} model over the lights (glsl/pipeline/shade.glsl)",
                         fill_template("pipeline/shade.glsl", path_labels=False, model=model,
                                       lights=lights, shadows="none", helpers=False,
                                       paired=0, features="0.0")))
    arrays = sorted({(name, "vec2" if name == "CONE" else "vec3")
                     for light in lights for name in light["names"]})
    return fill_template(
        "raster/lit.frag", prelude=GLSL.prelude, texel_reader=GLSL.texels(0, 0),
        structs=GLSL.struct("LightSample", STRUCTS["LightSample"]), planes=_planes_source(),
        model=model, lights=lights, checker=checker, mappings=list(mappings), stride=stride,
        light_arrays=arrays, planes_read=sum(bool(light["visibility"]) for light in lights),
        array_planes=any(light["visibility"] == "layer" for light in lights),
        sections=sections, fog=fog, variant=variant, prepass=prepass)


def _light_reads(plane) -> str:
    """Where a light's visibility comes from: "" (none), "layer" (an array), "count" (a
    `ShadowCount`) or "texture"."""
    return ("" if plane is None else "layer" if isinstance(plane, np.ndarray)
            else "count" if isinstance(plane, ShadowCount) else "texture")


def light_values(light) -> dict[str, tuple]:
    """A light's numbers under the names glsl/pipeline/shade.glsl reads (LIGHTi_<name>),
    as the sphere tracer's program holds them (gpu_shader/generate.py, light_rows)."""
    if type(light) not in LIGHT_KINDS:
        raise ValueError(f"the raster pipeline has no lights of type {type(light).__name__}")
    values = {"RADIANCE": tuple(np.multiply(light.color, light.intensity))}
    if light.separate_colors():
        # RADIANCE is then the diffuse colour; the specular and ambient ones come too.
        ambient, diffuse, specular = light.term_colors()
        values = {"RADIANCE": diffuse, "SPECULAR": specular, "AMBIENT": ambient}
    if isinstance(light, DirectionalLight):
        direction = np.asarray(light.direction, np.float64)
        return {"TO_LIGHT": tuple(-direction / np.linalg.norm(direction))} | values
    values |= {"POSITION": light.position,
               "ATTENUATION": (light.constant, light.linear, light.quadratic)}
    if isinstance(light, SpotLight):
        axis = np.asarray(light.direction, np.float64)
        cos_inner = math.cos(math.radians(light.inner_angle))
        cos_outer = math.cos(math.radians(light.outer_angle))
        values |= {"AXIS": tuple(axis / np.linalg.norm(axis)),
                   "CONE": (cos_outer, cos_inner - cos_outer)}
    return values


def material_rows(m, image, checker: bool, textured: bool) -> list[tuple]:
    """One object's material rows, laid out as glsl/pipeline/materials.glsl's: (color, ka),
    (kd, ks, shininess, opacity 1 - transparency); with checkerboards, (color_a, scale),
    (color_b, 1 if checkered); with textures, its image in the atlas (first row, width,
    height, wrap; None without), (tint, scale), (mapping code, sharpness, 0, 0)."""
    rows = [(*m.color, m.ka), (m.kd, m.ks, m.shininess, 1.0 - m.transparency)]
    if checker:
        c = m.checker
        rows += ([(*c.color_a, c.scale), (*c.color_b, 1.0)] if c
                 else [(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0)])
    if textured:
        t = m.texture
        rows += ([image, (*t.tint, t.scale), (MAPPING_CODES[t.mapping], t.sharpness, 0.0, 0.0)]
                 if image else [(0.0, 1.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 0.0)])
    return rows


def _sky(background, environment, uniforms: dict, mirrored: bool = False) -> tuple[str, tuple]:
    """The skybox's fragment shader ("" for one colour) and the colour to clear to; the
    background's numbers go into ``uniforms``."""
    if not isinstance(background, Background):
        return "", tuple(background)
    kind, sampler = background.kind, ""
    if kind == "solid":
        return "", tuple(background.color)
    sections = [("the camera (glsl/camera.glsl)", load_library("camera").select(["camera_ray"]))]
    if kind == "sky":
        uniforms |= {"background_bottom": background.bottom, "background_top": background.top}
        sections.append(("shading (glsl/shading.glsl)",
                         load_library("shading").select(["background_sky"])))
    else:
        uniforms |= {"environment_texture": environment.texture,
                     "environment_look": (background.intensity, *turn(background.rotation))}
        sampler = "cubemap" if kind in CUBE_KINDS else "equirect"
        source = load_library("environment").select([f"background_{sampler}"])
        texture = load_library("texture")
        # The texture functions the environment's call (the cube face rule, equirect_uv).
        needs = [f for f in texture.names() if re.search(rf"\b{f}\s*\(", source)]
        sections += [("bilinear texture filtering (glsl/texture.glsl)", texture.select(needs)),
                     ("environment maps (glsl/environment.glsl)", source)]
    sections.append(("the background (glsl/pipeline/background.glsl)",
                     fill_template("pipeline/background.glsl", kind=kind, sampler=sampler)))
    return fill_template("raster/sky.frag", prelude=GLSL.prelude, kind=kind, mirrored=mirrored,
                         texel_reader=GLSL.texels(0, 0), sections=sections), (0.0, 0.0, 0.0)


@cache
def _planes_source() -> str:
    """glsl/raster/mesh.frag as a function of the lit shader: without its #version line (the
    prelude has one) and with its main renamed write_planes."""
    body = glsl_file("raster/mesh.frag").split("\n", 1)[1]
    return body.replace("void main()", "void write_planes()")


# --- Programs: each pair of sources compiled once on a context ------------------------------

_compiled: dict[tuple, object] = {}


def _compile(ctx, vertex: str, fragment: str):
    """The program of ``vertex`` and ``fragment`` sources on ``ctx``, compiled on first use
    and kept: a scene's structure compiles once, whatever its numbers."""
    key = (id(ctx), vertex, fragment)
    if key not in _compiled:
        try:
            _compiled[key] = ctx.program(vertex_shader=vertex, fragment_shader=fragment)
        except Exception as err:           # the driver's log, with the lines it names
            raise ShaderCompileError(compile_message(str(err), fragment)) from None
    return _compiled[key]
