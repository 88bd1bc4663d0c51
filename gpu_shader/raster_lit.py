"""The lit raster pipeline on the GPU: triangle meshes drawn and shaded in one draw.

`gpu_shader.raster` finds what each pixel shows; here a fragment shader generated for the
scene (glsl/raster/lit.frag) writes those planes, then the colour, with the sphere tracer's
own GLSL (glsl/lights.glsl, shading.glsl, texture.glsl and the shading template
glsl/pipeline/shade.glsl), so that it equals `reference_cpu.raster_shading.shade_raster`
(tests/gpu/test_raster_lit.py). Pixels no triangle covers show the background, drawn last as
a skybox (glsl/raster/sky.frag).

The same generator makes the shaders of the raster backend's other passes
(`gpu_shader.raster_render`): the mirrored scene behind a flat mirror (``variant="mirror"``),
and the layers of transparent meshes (``variant="peel"`` or ``"sorted"``).
"""

from __future__ import annotations

import contextlib
import math
import re
from dataclasses import dataclass
from functools import cache

import numpy as np

from reference_cpu.rasterise import Raster
from scene_model.camera import Camera
from scene_model.environment import CUBE_KINDS, ENVIRONMENT_KINDS, environment_map, turn
from scene_model.meshes import TriangleMesh
from scene_model.scene import LIT_SHADING, Background, DirectionalLight, SpotLight
from scene_model.textures import texture_atlas, texture_image

from .context import gl_context
from .dialects import GLSL, STRUCTS
from .generate import BANDS, LIGHT_KINDS, SPECULAR
from .library import fill_template, glsl_file, load_library
from .raster import _raster, _set_camera
from .render import ShaderCompileError, compile_message


# --- The lit pipeline: shaders generated for what the scene uses ------------------------------

# How a textured mesh finds its place in its image, coded in its material rows (0: none): the
# sphere tracer's triplanar projection, or the mesh's own texture coordinates.
MAPPING_CODES = {"triplanar": 1, "uv": 4}
ATLAS_UNIT, PLANES_UNIT, FIRST_PLANE_UNIT = 1, 2, 3        # texture units
PASS_UNIT = 12          # the first of the textures a pass reads (`RasterRenderer.draw_pass`)
VARIANTS = ("opaque", "mirror", "peel", "sorted")
KEPT_SHADERS = 16       # `RasterRenderer.shaders` keeps this many generated sets at most


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


# --- Drawing: buffers uploaded once, a frame sets uniforms and draws -------------------------

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


def _set_uniforms(program, values: dict) -> None:
    """Write ``values`` (by uniform name, numbers or arrays) into those of ``program`` that
    it reads. The compiler drops the rest, and the end of an array after the last element
    read (a light array of lights 0 and 1 that only light 0 needs has one element)."""
    for name, value in values.items():
        if name in program:
            uniform = program[name]
            if uniform.gl_type in (0x1404, 0x8B56):      # GL_INT, GL_BOOL
                uniform.value = int(value)
                continue
            value = np.asarray(value, np.float32).ravel()
            program[name].write(value[:uniform.array_length * uniform.dimension].tobytes())


class RasterRenderer:
    """The lit raster pipeline on one context, for one list of meshes: their vertex and index
    buffers uploaded once, so that a frame sets uniforms, draws and (`draw`) reads back.

    Parameters
    ----------
    meshes : list of TriangleMesh
        Mesh k is object k, drawn with ``materials[k]`` (a mesh without triangles is skipped).
    ctx : moderngl.Context, optional
        Default: the process's (`gpu_shader.context.gl_context`).
    """

    def __init__(self, meshes: list[TriangleMesh], ctx=None):
        self.ctx = ctx or gl_context()
        self.meshes = list(meshes)
        with self.ctx:
            self.buffers = [(self.ctx.buffer(np.concatenate(
                [m.positions, m.normals, m.uvs], axis=1).astype(np.float32).tobytes()),
                self.ctx.buffer(m.triangles.astype(np.int32).tobytes()))
                if len(m.triangles) else None for m in self.meshes]
        self.vertex_arrays: dict = {}       # (program, mesh index or "sky"): vertex array
        self.targets: dict = {}             # (name, W, H): (all planes, colour and depth only)
        self.textures: dict = {}            # "atlas" / "planes": (key, texture)
        self.generated: dict = {}           # what `shaders` was asked for: its LitShaders

    def draw(self, materials, lights, camera: Camera, width: int, height: int,
             **settings) -> tuple[np.ndarray, Raster]:
        """Draw one frame and read it back (arguments as the module's `draw`)."""
        fbo = self.draw_planes(materials, lights, camera, width, height, **settings)
        color, raster = read_planes(self.ctx, fbo, width, height)
        return color, raster

    def draw_planes(self, materials, lights, camera: Camera, width: int, height: int, *,
                    ambient=(0.0, 0.0, 0.0), model: str = "phong", background=(0.0, 0.0, 0.0),
                    toon_bands: int = 4, visibility=None, cull_back_faces: bool = False,
                    fog=None, depth_range: float = 100.0, objects=None):
        """Draw one frame and leave it on the GPU; return its framebuffer: attachments 0 to
        3 hold normal and depth, uv, ids (as `rasterise`'s) and the colour (alpha 1 where
        a triangle is drawn, 0 on the background). ``fog`` and ``depth_range`` as
        `lit_shaders`'; ``objects`` (K,) bool, which meshes to draw (default all)."""
        shaders = self.shaders(materials, lights, ambient=ambient, model=model,
                               background=background, toon_bands=toon_bands,
                               visibility=visibility, fog=fog, depth_range=depth_range)
        return self.draw_pass(shaders, camera, width, height, objects=objects,
                              visibility=visibility, cull_back_faces=cull_back_faces)

    def shaders(self, materials, lights, **settings) -> LitShaders:
        """`lit_shaders` for these meshes, after checking there is a material for each."""
        if len(materials) != len(self.meshes):
            raise ValueError(f"expected a material for each of the {len(self.meshes)} meshes, "
                             f"got {len(materials)}")
        # A frame's passes ask again for the same shaders every frame: generating them (a
        # template filled in, the material rows) costs milliseconds, so they are kept by
        # what they are made of (of the visibility, only its kinds: the textures are bound
        # by `draw_pass`).
        planes = settings.get("visibility")
        kinds = None if planes is None else tuple(_light_reads(p) for p in planes)
        key = repr((materials, lights, kinds, sorted((k, v) for k, v in settings.items()
                                                     if k != "visibility")))
        if key not in self.generated:
            if len(self.generated) >= KEPT_SHADERS:
                self.generated.clear()
            self.generated[key] = lit_shaders(materials, lights, **settings)
        return self.generated[key]

    def draw_pass(self, shaders: LitShaders, camera: Camera, width: int, height: int, *,
                  target: str = "frame", objects=None, visibility=None, reads=None,
                  uniforms=None, vertex: str = "raster/mesh.vert", clear: bool = True,
                  sky: bool = True, cull_back_faces: bool = False, front_face: str = "cw",
                  query=None, scissor=None):
        """Draw ``objects`` with ``shaders`` into the planes of ``target`` (one set of
        framebuffers per name and size) and return its framebuffer.

        ``reads`` maps sampler names to textures the pass reads (bound from `PASS_UNIT`),
        ``uniforms`` holds the pass's other numbers; ``vertex`` is the vertex shader's file.
        With ``clear``, the colour is cleared to the background's and the depth to 1 first;
        with ``sky``, the skybox fills what no triangle covers. ``front_face`` is the winding
        of a front face in GL's window ("cw" drawn upside down; "ccw" mirrored as well).
        A ``query`` (moderngl.Query) counts the samples of the meshes' fragments that pass.
        A ``scissor`` (x, y, w, h) in pixels (GL's window: y is the image's row) limits the
        clear, the meshes and the skybox to that rectangle
        (`gpu_shader.raster_render.screen_rectangle`).
        Like every method here it makes the context current itself: call it outside a
        ``with ctx`` block (moderngl's are not reentrant: the inner one's end releases it).
        """
        ctx = self.ctx
        with ctx:
            fbo, sky_fbo = self.target(target, width, height)
            program = self.program(shaders, camera, width, height, vertex=vertex,
                                   visibility=visibility, reads=reads, uniforms=uniforms)
            try:
                if clear:
                    sky_fbo.use()
                    sky_fbo.viewport = (0, 0, width, height)
                    sky_fbo.scissor = scissor
                    sky_fbo.clear(*shaders.clear, 0.0, depth=1.0)
                fbo.use()
                fbo.viewport = (0, 0, width, height)
                fbo.scissor = scissor
                ctx.enable(ctx.DEPTH_TEST)
                if cull_back_faces:
                    ctx.enable(ctx.CULL_FACE)
                    ctx.front_face = front_face
                with query or contextlib.nullcontext():
                    for k, rows in enumerate(shaders.materials):
                        if self.buffers[k] is None or (objects is not None and not objects[k]):
                            continue
                        program["object_id"].value = k
                        if "material" in program:
                            program["material"].write(rows.tobytes())
                        self._vertex_array(program, k).render()
                if sky and shaders.sky_source:
                    program = self.program(shaders, camera, width, height, sky=True,
                                           uniforms=uniforms)
                    sky_fbo.use()
                    sky_fbo.scissor = scissor
                    ctx.depth_func = "<="       # only where the depth is still the clear's 1
                    self._vertex_array(program, "sky").render(vertices=3)
            finally:
                fbo.scissor = sky_fbo.scissor = None
                ctx.depth_func = "<"
                ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)
                ctx.front_face = "ccw"
        return fbo

    def release(self) -> None:
        """Free every GL object this renderer made (its programs stay compiled)."""
        with self.ctx:
            made = [*self.vertex_arrays.values(),
                    *(b for pair in self.buffers if pair for b in pair),
                    *(t for _, t in self.textures.values())]
            for fbo, sky_fbo in self.targets.values():
                made += [sky_fbo, fbo, *fbo.color_attachments, fbo.depth_attachment]
            for gl_object in made:
                gl_object.release()
        self.vertex_arrays, self.buffers, self.targets, self.textures = {}, [], {}, {}

    def program(self, shaders: LitShaders, camera: Camera, width: int, height: int, *,
                vertex: str = "raster/mesh.vert", sky: bool = False, visibility=None,
                reads=None, uniforms=None):
        """The meshes' program of ``shaders`` (the skybox's with ``sky``), compiled on first
        use, with this frame's camera, numbers and textures set (as `draw_pass` takes them)."""
        program = (_compile(self.ctx, glsl_file("raster/sky.vert"), shaders.sky_source) if sky
                   else _compile(self.ctx, glsl_file(vertex), shaders.source))
        self._prepare(program, shaders, camera, width, height, visibility)
        self._bind(program, reads, uniforms)
        return program

    def vertex_array(self, program, k: int, triangles: np.ndarray):
        """A vertex array of mesh k's vertices with its own ``triangles`` (T, 3) (the caller
        releases it and the index buffer it returns): part of a mesh, in an order."""
        ibo = self.ctx.buffer(np.ascontiguousarray(triangles, np.int32).tobytes())
        vao = self.ctx.vertex_array(program, [(self.buffers[k][0], *_layout(program))],
                                    index_buffer=ibo, index_element_size=4)
        return vao, ibo

    def _bind(self, program, reads, uniforms) -> None:
        """Bind the textures a pass reads, from `PASS_UNIT` on, and set its other uniforms."""
        for unit, (name, texture) in enumerate((reads or {}).items(), PASS_UNIT):
            if name in program:
                texture.use(location=unit)
                program[name].value = unit
        _set_uniforms(program, uniforms or {})

    def _prepare(self, program, shaders: LitShaders, camera, width, height, visibility):
        """Set a program's camera, numbers and textures for this frame."""
        _set_camera(program, camera, width, height)
        _set_uniforms(program, shaders.uniforms)
        if shaders.texels is not None and "texels" in program:
            self._texture("atlas", id(shaders.texels), lambda: self._atlas(shaders.texels)
                          ).use(location=ATLAS_UNIT)
            program["texels"].value = ATLAS_UNIT
        arrays = [p for p in visibility or [] if isinstance(p, np.ndarray)]
        if arrays and "visibility_planes" in program:
            if any(p.shape != (height, width) for p in arrays):
                raise ValueError(f"visibility planes must be ({height}, {width}) arrays, got "
                                 f"{', '.join(str(p.shape) for p in arrays)}")
            size = (width, height, len(arrays))
            planes = self._texture("planes", size, lambda: self.ctx.texture_array(
                size, 1, dtype="f4"))
            planes.write(np.ascontiguousarray(arrays, np.float32).tobytes())
            planes.use(location=PLANES_UNIT)
            program["visibility_planes"].value = PLANES_UNIT
        for i, plane in enumerate(visibility or []):
            if plane is not None and not isinstance(plane, np.ndarray):
                # A texture drawn on the GPU (a ShadowCount holds one).
                if f"visibility{i}" in program:   # none read by "normals" or "depth"
                    getattr(plane, "texture", plane).use(location=FIRST_PLANE_UNIT + i)
                    program[f"visibility{i}"].value = FIRST_PLANE_UNIT + i

    def _texture(self, slot: str, key, make):
        """The texture kept in ``slot`` if made for ``key``, else a new one from ``make``."""
        if slot in self.textures and self.textures[slot][0] == key:
            return self.textures[slot][1]
        if slot in self.textures:
            self.textures[slot][1].release()
        self.textures[slot] = (key, make())
        return self.textures[slot][1]

    def _atlas(self, texels: np.ndarray):
        """The atlas (R, W, 4) as an RGBA32F texture, read texel by texel with texelFetch."""
        rows, width, _ = texels.shape
        texture = self.ctx.texture((width, rows), 4, np.ascontiguousarray(texels).tobytes(),
                                   dtype="f4")
        texture.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        return texture

    def target(self, name: str, width: int, height: int):
        """The framebuffers ``name`` at this size, made on first use: the four planes with
        a depth buffer, and the colour plane alone with the same depth buffer (the clear
        and the skybox write only colour)."""
        if (name, width, height) not in self.targets:
            planes = [self.ctx.texture((width, height), 4, dtype=dtype)
                      for dtype in ("f4", "f4", "i4", "f4")]
            depth = self.ctx.depth_texture((width, height))
            self.targets[(name, width, height)] = (
                self.ctx.framebuffer(color_attachments=planes, depth_attachment=depth),
                self.ctx.framebuffer(color_attachments=planes[3:], depth_attachment=depth))
        return self.targets[(name, width, height)]

    def _vertex_array(self, program, part):
        """The vertex array of mesh ``part`` (or the skybox's triangle) for ``program``."""
        key = (program, part)
        if key not in self.vertex_arrays:
            if part == "sky":
                self.vertex_arrays[key] = self.ctx.vertex_array(program, [])
            else:
                vbo, ibo = self.buffers[part]
                self.vertex_arrays[key] = self.ctx.vertex_array(
                    program, [(vbo, *_layout(program))],
                    index_buffer=ibo, index_element_size=4)
        return self.vertex_arrays[key]


def _layout(program) -> tuple:
    """The vertex buffer's layout "3f 3f 2f" (position, normal, uv) as ``program`` reads it:
    (format, *names), an attribute it does not read (the compiler dropped it) skipped."""
    parts, names = [], []
    for name, count in (("position", 3), ("normal", 3), ("uv", 2)):
        parts.append(f"{count}f" if name in program else f"{count}x4")
        names += [name] * (name in program)
    return (" ".join(parts), *names)


def read_planes(ctx, fbo, width: int, height: int) -> tuple[np.ndarray, Raster]:
    """A frame's colour (H, W, 3) and `Raster`, read back from the planes of ``fbo``."""
    planes = [np.empty((height, width, 4), dtype) for dtype in
              (np.float32, np.float32, np.int32, np.float32)]
    with ctx:
        for k, plane in enumerate(planes):
            fbo.read_into(plane, components=4, attachment=k, dtype=plane.dtype.str[1:])
    normal_depth, uv, ids, color = planes
    return color[..., :3].copy(), _raster(normal_depth, uv, ids, color[..., 3] > 0)


def draw(meshes: list[TriangleMesh], materials, lights, camera: Camera, width: int,
         height: int, *, ambient=(0.0, 0.0, 0.0), model: str = "phong",
         background=(0.0, 0.0, 0.0), toon_bands: int = 4, visibility=None,
         cull_back_faces: bool = False) -> tuple[np.ndarray, Raster]:
    """Draw and shade ``meshes`` on the GPU: `rasterise`, then
    `reference_cpu.raster_shading.shade_raster`, in one draw.

    Parameters
    ----------
    meshes : list of TriangleMesh
    materials : list of Material
        One per mesh: its colour, checkerboard or texture, ka, kd, ks and shininess.
    lights : sequence of lights (`scene_model.scene`)
    camera : Camera
    width, height : int
    ambient, model, background, toon_bands
        As `shade_raster`'s: the ambient light (linear RGB), "phong", "blinn_phong", "toon",
        "stripes" or "normals", a colour or a `Background` (the skybox), the toon bands.
    visibility : sequence, optional
        One entry per light, how much of it reaches the surface at each pixel (0 to 1):
        None (all of it), an (H, W) array, or a moderngl texture of W x H texels whose red
        channel holds it (GL row r the image's row r from the top, as the planes here), e.g.
        a shadow mask drawn on the GPU. It scales the light's diffuse and specular terms.
    cull_back_faces : bool
        As `rasterise`'s.

    Returns
    -------
    color : (H, W, 3) float32 ndarray
        Linear RGB, unclamped, as `shade_raster`'s.
    raster : Raster
        The planes the colour was shaded from (``coverage`` None).
    """
    renderer = RasterRenderer(meshes)
    try:
        return renderer.draw(materials, lights, camera, width, height, ambient=ambient,
                             model=model, background=background, toon_bands=toon_bands,
                             visibility=visibility, cull_back_faces=cull_back_faces)
    finally:
        renderer.release()
