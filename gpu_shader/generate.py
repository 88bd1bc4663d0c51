"""The shader generator: one scene in, one readable program out, holding only what it uses.

The program is assembled in the order a reader meets it:

1. the dialect's prelude, the parameter names (``#define EPSILON P[4].x``) and the structs;
2. the SDF library functions the tree uses, then ``scene_sdf`` / ``scene_object_id``
   written from the tree (`gpu_shader.sdf_code`);
3. the march and the shadow function the settings ask for, ``estimate_normal`` for the
   chosen stencil;
4. lights of the kinds present, the shading model, checker, textures, fog and background only
   if used;
5. ``trace``, the per-pixel pipeline of `reference_cpu.render`; with anti-aliasing
   (``render.samples`` > 1), ``supersample``, which traces each of a pixel's rays; then the
   entry point.

Building blocks come from the libraries in ``glsl/*.glsl``, function by function
(`gpu_shader.library`); the pipeline functions (normal, materials, shading over the lights,
background, heat ramp, ``trace``) from the templates in ``glsl/pipeline/``, filled in for
the scene. This module decides what goes in and fills in the numbers; it spells no GLSL.

Every number that a frame may change is in the parameter block (`gpu_shader.parameters`), so
the text depends only on the scene's structure, and a program cache keyed by the text never
compiles the same structure twice. ``path_labels`` adds the bookkeeping the equivalence
suite needs (`scene_model.frame.Frame.path`); a program for a student has none of it.
"""

from __future__ import annotations

import math
import re
import typing
from dataclasses import dataclass

import numpy as np

from reference_cpu.cone_prepass import CONE_SLACK, MIN_PROGRESS, tile_grid
from reference_cpu.culling import object_bits
from reference_cpu.normals import STENCILS
from reference_cpu.refraction import LABEL_WEIGHT, MIN_RAY_WEIGHT
from reference_cpu.relaxation import SLOPE_WEIGHT
from scene_model.camera import camera_basis
from scene_model.colormaps import HEAT_COLORS, HEAT_STOPS
from scene_model.environment import CUBE_KINDS, ENVIRONMENT_KINDS, environment_map, turn
from scene_model.errors import MarchlabError
from scene_model.sampling import centre_sample, ray_offsets
from scene_model.scene import (LIT_SHADING, DirectionalLight, PointLight, Scene, Shading,
                               SpotLight, shading_modes)
from scene_model.textures import (MAPPING_CODES, texture_atlas, texture_image, texture_wrap,
                                  surface_mapping)
from scene_model.shapes import primitives

from .dialects import MAX_FLAT_ROWS, Dialect, dialect as get_dialect
from .library import fill_template
from .parameters import ParameterBlock
from .packets import packet_source
from .sdf_code import scene_sdf_code

LIT_MODES = LIT_SHADING
SPECULAR = {"phong": "specular_phong", "blinn_phong": "specular_blinn_phong",
            "toon": "specular_phong", "stripes": "specular_phong"}
# How each lit model shapes its diffuse and specular terms (glsl/shading.glsl).
BANDS = {"toon": "toon_band", "stripes": "stripes_band"}
# The models a lit render's object may choose, coded in its material row (`shading_modes`).
MODEL_CODES = {m: i for i, m in enumerate(typing.get_args(Shading))}
LIGHT_KINDS = {DirectionalLight: "directional", PointLight: "point", SpotLight: "spot"}
# March hard shadow rays toward two lights in one loop (glsl/shadow_pair.glsl) where a scene
# allows it; tests turn it off to check that it changes no pixel.
PAIR_SHADOW_RAYS = True


@dataclass(frozen=True)
class Program:
    """A generated program and the values of its parameter block.

    Attributes
    ----------
    source : str
        The complete program text (for GLSL, the fragment shader).
    parameters : (N, 4) float64 ndarray
        What the program's ``P`` must hold for this scene and image size.
    features : tuple of str
        What was emitted ("sdf_sphere", "shadows:hard", "fog", ...), sorted.
    vertex_source : str
        The vertex shader that goes with a GLSL ``source`` when it needs its own (it hands on
        parameter rows as flat varyings); "" for the plain full-screen triangle.
    path_labels : bool
        Whether the program writes path labels (`scene_model.frame.Frame.path`).
    prepass_tile : int
        With ``render.prepass = "cone"``, the pre-pass's tile size T: the program reads each
        pixel's start from a (ceil(H / T), ceil(W / T)) array of tile starts (GLSL: the
        texture ``cone_starts``; OpenCL: the buffer its ``cone_prepass`` kernel fills); 0
        without a pre-pass.
    prepass_source : str
        GLSL: the fragment shader that draws the tile starts into ``cone_starts``, one
        fragment per tile (it shares ``vertex_source``); "" otherwise.
    texels : (R, W, 4) float32 ndarray or None
        The texture atlas the program reads with TEXEL (glsl/texture.glsl): an environment
        map's texels and the textured materials' images (`scene_model.textures.texture_atlas`),
        RGB and a 0; None where the program reads none. GLSL: the RGBA32F
        texture ``texels``; OpenCL: R W rows appended to the parameter buffer.
    compute : bool
        GLSL: ``source`` and ``prepass_source`` are compute shaders (the "glsl-compute"
        dialect, glsl/main.comp), dispatched one invocation per pixel (per tile), rather than
        fragment shaders drawn over the frame.
    """
    source: str
    parameters: np.ndarray
    features: tuple[str, ...]
    vertex_source: str = ""
    path_labels: bool = False
    prepass_tile: int = 0
    prepass_source: str = ""
    texels: np.ndarray | None = None
    compute: bool = False

    def tiles(self, width: int, height: int) -> tuple[int, int]:
        """(columns, rows) of pre-pass tiles of a width x height image."""
        return tile_grid(width, height, self.prepass_tile)


def generate(scene: Scene, width: int, height: int, dialect: str = "glsl",
             precision: str = "float32", flat_rows: int = MAX_FLAT_ROWS,
             path_labels: bool = False) -> Program:
    """Generate the program that renders ``scene`` at ``width`` x ``height``.

    ``dialect`` is "glsl" (a fragment shader), "glsl-compute" (the same as a compute shader),
    "opencl" (a kernel, one ray per work-item) or "opencl-packets" (a kernel, one packet of
    rays per work-item); ``precision`` the
    meaning of ``real`` ("float64" only in OpenCL). In GLSL, up to ``flat_rows`` parameter
    rows read with fixed indices reach the fragment shader as flat varyings (the context's
    GL_MAX_VARYING_VECTORS at most). ``path_labels`` makes the program compute each pixel's
    path label too, for the equivalence suite.
    """
    try:
        language = get_dialect(dialect, precision)
    except KeyError as err:
        raise MarchlabError(err.args[0]) from None
    if language.packets:
        # The packet program is the one-ray program, vectorised (gpu_shader/packets.py).
        scalar = scalar_program(scene, width, height, precision, path_labels,
                                pair_shadow_rays=False)
        return Program(packet_source(scalar, language), scalar.parameters, scalar.features,
                       path_labels=path_labels, prepass_tile=scalar.prepass_tile,
                       texels=scalar.texels)
    return _Generator(scene, language, flat_rows, path_labels).program(width, height)


@dataclass(frozen=True)
class ScalarProgram:
    """The one-ray OpenCL program of a scene before it is wrapped in its dialect: what the
    packet form is derived from.

    Attributes
    ----------
    defines : str
        The parameter names, ``#define EPSILON P[4].x`` and so on, one per line.
    functions : str
        Every function of the program but the entry point, in reading order (section
        banners included), spelled as the one-ray OpenCL dialect spells them, with ``P``
        and ``U`` read directly (not yet passed on as arguments).
    parameters : (N, 4) float64 ndarray
    features : tuple of str
    path_labels : bool
    prepass_tile : int
        As `Program.prepass_tile`.
    supersampled : bool
        Whether the functions end with ``supersample`` (``render.samples`` > 1), which the
        entry point then calls instead of ``trace``.
    """
    defines: str
    functions: str
    parameters: np.ndarray
    features: tuple[str, ...]
    path_labels: bool = False
    prepass_tile: int = 0
    supersampled: bool = False
    texels: np.ndarray | None = None


def scalar_program(scene: Scene, width: int, height: int, precision: str = "float32",
                   path_labels: bool = False, pair_shadow_rays: bool = True) -> ScalarProgram:
    """The one-ray OpenCL program of ``scene``, unwrapped (see `ScalarProgram`).

    ``pair_shadow_rays`` False marches every shadow ray alone, as the packet form wants: its
    loop already steps a packet of rays at once, and a second ray per lane only adds work.
    """
    generator = _Generator(scene, get_dialect("opencl", precision), path_labels=path_labels,
                           pair_shadow_rays=pair_shadow_rays)
    parts, _ = generator.sections(width, height)
    functions = "\n".join(_banner(title) + text for title, text in parts if text)
    return ScalarProgram(generator.block.defines() + generator.texel_reader(), functions,
                         generator.block.values(np.float64), tuple(sorted(generator.features)),
                         path_labels, generator.prepass_tile, generator.supersampled,
                         generator.texels)


class _Generator:
    def __init__(self, scene: Scene, dialect: Dialect, flat_rows: int = 0,
                 path_labels: bool = False, pair_shadow_rays: bool = True):
        self.scene, self.s, self.d = scene, scene.render, dialect
        self.flat_rows, self.path_labels = flat_rows, path_labels
        self.block = ParameterBlock()
        self.features: set[str] = set()
        self.texels: np.ndarray | None = None      # the texture atlas, where one is read
        self.primitives = list(primitives(scene.objects))
        self.materials = [scene.materials[p.material] for p in self.primitives]
        self.checker = any(m.checker is not None for m in self.materials)
        # Textured objects (glsl/texture.glsl): each primitive's mapping, or None; their
        # images join the texture atlas (`texture_parts`), their rows the materials'.
        self.mappings = [surface_mapping(m.texture, p.kind)
                         if m.texture is not None and self.s.shading in LIT_MODES else None
                         for p, m in zip(self.primitives, self.materials)]
        self.textured = any(self.mappings)
        self.texture_images: list = []        # each primitive's image in the atlas, or None
        self.reflections = (self.s.reflection_depth > 0 and self.s.shading in LIT_MODES
                            and any(m.kr > 0 for m in self.materials))
        # Glass: the ray tree with refracted rays (glsl/pipeline/trace_glass.glsl).
        self.glass = (self.s.shading in LIT_MODES
                      and any(m.transparency > 0 for m in self.materials))
        self.fog = self.s.fog.density > 0 and self.s.shading in LIT_MODES
        # The objects' shading models: one for all (`model`), or several chosen per object
        # by a material row (`shade_surface`, glsl/pipeline/shade_surface.glsl).
        self.object_models = shading_modes(scene)           # one per primitive
        models = self.object_models or [self.s.shading]
        self.models = sorted(set(models), key=models.index)
        self.model = self.models[0]
        self.mixed = self.s.shading in LIT_MODES and (len(self.models) > 1
                                                      or self.model not in LIT_MODES)
        self.prepass_tile = self.s.prepass_tile if self.s.prepass == "cone" else 0
        self.supersampled = self.s.samples > 1
        self.cone_section: tuple[str, str] | None = None      # set by `sections`
        # Hard shadow rays toward two lights are marched together (hard_shadow_pair) with
        # plain sphere tracing (relaxed shadow rays keep the relaxed march of their own):
        # lights 0 .. paired_lights - 1, two by two. The last of an odd number, or every
        # light without pairs, is marched alone.
        lights = len(scene.lights)
        pairs = (PAIR_SHADOW_RAYS and pair_shadow_rays and self.s.shading in LIT_MODES
                 and self.s.shadows == "hard" and self.s.relaxation == "none")
        self.paired_lights = lights - lights % 2 if pairs else 0
        # Hard shadow rays leave out the convex object they start on (glsl/march.glsl).
        self.skip_own = (self.s.shadow_skip_own and self.s.shadows == "hard"
                         and self.s.shading in LIT_MODES and lights > 0)
        self.lone_shadows = self.paired_lights < lights

    def program(self, width: int, height: int) -> Program:
        parts, fixed = self.sections(width, height)
        prepass_parts = []
        if self.prepass_tile and self.d.prepass_entry:
            # The cone march is a program of its own here (a first draw into a small
            # texture): the geometry and camera, then the pre-pass, then its entry point.
            cone = parts.index(self.cone_section)
            prepass_parts = parts[:cone + 1] + [self.entry(self.d.prepass_entry)]
            del parts[cone]
        parts.append(self.entry(self.d.entry))
        rows, fixed = max(1, len(self.block.rows)), max(1, fixed)
        head = [self.d.prelude, _banner("parameters: one vec4 row each, set per frame")
                + self.d.declare_parameters(rows, fixed, self.flat_rows)]
        head.append(self.block.defines() + self.texel_reader())
        head.append(self.d.structs(self.path_labels, self.glass))

        def assemble(sections):
            body = [_banner(title) + text for title, text in sections if text]
            return self.d.finish("\n".join(head + body))

        return Program(assemble(parts), self.block.values(np.float64),
                       tuple(sorted(self.features)),
                       self.d.vertex_shader(rows, fixed, self.flat_rows), self.path_labels,
                       self.prepass_tile, assemble(prepass_parts) if prepass_parts else "",
                       self.texels, self.d.compute)

    def entry(self, name: str) -> tuple[str, str]:
        """The section of the entry point ``glsl/<name>``."""
        return (f"the entry point (glsl/{name})",
                fill_template(name, path_labels=self.path_labels,
                              prepass=bool(self.prepass_tile), samples=self.supersampled))

    def sections(self, width: int, height: int) -> tuple[list[tuple[str, str]], int]:
        """The program's functions as (section title, text) pairs in reading order, all but
        the entry point, and the number of parameter rows read with fixed indices."""
        self.settings_rows(width, height)
        if self.s.bounding_spheres:
            self.features.add("bounding_spheres")
        if self.skip_own:
            self.features.add("shadows:skip_own")
        bits = object_bits(self.scene.objects, self.s.epsilon, self.s.bounding_spheres,
                           self.skip_own)
        sdf_source, sdf_used = scene_sdf_code(self.scene.objects, self.block, bits,
                                              own=self.skip_own)
        self.features |= sdf_used
        culling = (self.d.library("culling").select(["ray_meets_sphere"])
                   if any(centre is not None for _, centre, _ in bits) else "")
        parts = [
            (f"the SDF building blocks used by this scene ({self.file('sdf')})",
             self.d.library("sdf").select(sdf_used)),
            (f"bounding spheres ({self.file('culling')})", culling),
            ("the scene's SDF tree", sdf_source),
            (f"the camera ({self.file('camera')})",
             self.d.library("camera").select(["camera_ray"])),
        ]
        if self.prepass_tile:
            self.features.add("prepass:cone")
            defines = (f"#define MIN_PROGRESS {self.d.literal(MIN_PROGRESS)}\n"
                       f"#define CONE_SLACK {self.d.literal(CONE_SLACK)}\n\n")
            self.cone_section = (f"the cone pre-pass ({self.file('cone')})",
                                 defines + self.d.library("cone").select(["tile_start"]))
            parts.append(self.cone_section)
        parts += self.march_parts()
        parts.append(("surface normals (glsl/pipeline/normals.glsl)", self.normal_code()))
        if self.glass:
            parts.append((f"glass ({self.file('glass')})", self.d.library("glass").select(
                ["refract_k", "refract_direction", f"fresnel_{self.s.fresnel}", "beer_lambert"])))
        parts += self.texture_parts()
        parts += self.shading_parts()
        # Materials are read by object id; their rows come last, outside the private copy.
        fixed = len(self.block.rows)
        if self.s.shading in LIT_MODES:
            parts.insert(-1, ("materials, indexed by object id (glsl/pipeline/materials.glsl)",
                              self.material_code()))
        trace = "trace_glass" if self.glass else "trace"
        parts.append((f"the per-pixel pipeline (glsl/pipeline/{trace}.glsl)", self.pixel_code()))
        if self.supersampled:
            parts.append(("anti-aliasing: every ray of a pixel (glsl/pipeline/samples.glsl)",
                          self.samples_code()))
        return parts, fixed

    def file(self, name: str) -> str:
        """Where the building blocks ``name`` come from, for the program's section titles."""
        return self.d.library(name).file

    def template(self, name: str, **context) -> str:
        """``glsl/pipeline/<name>.glsl`` filled in for this program."""
        return fill_template(f"pipeline/{name}.glsl", path_labels=self.path_labels,
                             mode=self.s.shading, shade=self.shade_call(), **context)

    # --- parameters that every program has --------------------------------------------------

    def settings_rows(self, width: int, height: int):
        s, camera, b = self.s, self.scene.camera, self.block
        forward, right, up = camera_basis(camera)
        half_height = math.tan(math.radians(camera.fov) / 2)
        b.named({"CAMERA_POSITION": ("xyz", camera.position)})
        b.named({"CAMERA_FORWARD": ("xyz", forward)})
        b.named({"CAMERA_RIGHT": ("xyz", right)})
        b.named({"CAMERA_UP": ("xyz", up)})
        b.named({"HALF_WIDTH": ("x", half_height * width / height),
                 "HALF_HEIGHT": ("y", half_height),
                 "IMAGE_WIDTH": ("z", width), "IMAGE_HEIGHT": ("w", height)})
        b.named({"EPSILON": ("x", s.epsilon), "MAX_DISTANCE": ("y", s.max_distance),
                 "NORMAL_STEP": ("z", s.normal_step), "SURFACE_OFFSET": ("w", s.surface_offset)})
        b.named({"MAX_STEPS": ("x", s.max_steps), "REFLECTION_DEPTH": ("y", s.reflection_depth),
                 "PENUMBRA_K": ("z", s.penumbra_k), "TOON_BANDS": ("w", s.toon_bands)})
        # Loop bounds are integers; the block holds floats, exact for any sensible count.
        b.names = [(n, self.d.to_int(e) if n in ("MAX_STEPS", "REFLECTION_DEPTH") else e)
                   for n, e in b.names]
        # The pre-pass's tile size shares the ambient row: a row more can push a scene's
        # fixed rows past the flat varyings (gpu_shader/dialects.py), which made csg's
        # frame on llvmpipe twice as slow.
        b.named({"AMBIENT": ("xyz", s.ambient)}
                | ({"PREPASS_TILE": ("w", self.prepass_tile)} if self.prepass_tile else {}))
        if self.fog:
            self.features.add("fog")
            b.named({"FOG_COLOR": ("xyz", s.fog.color), "FOG_DENSITY": ("w", s.fog.density)})

    # --- marching and normals -----------------------------------------------------------------

    def march_parts(self) -> list[tuple[str, str]]:
        """The march (plain or relaxed) and the shadow function the settings ask for."""
        needs = ["march"]
        if self.s.shading in LIT_MODES and self.s.shadows != "none" and self.scene.lights:
            needs += [f"{self.s.shadows}_shadow"] * self.lone_shadows
            self.features.add(f"shadows:{self.s.shadows}")
        mode = self.s.relaxation
        if mode == "none":
            return [(f"sphere tracing ({self.file('march')})",
                     self.d.library("march").select(needs))]
        self.features.add(f"relaxation:{mode}")
        if mode == "fixed":
            self.block.named({"OMEGA": ("x", self.s.omega)})
        defines = (f"#define RELAXATION_AUTO {int(mode == 'auto')}\n"
                   + (f"#define SLOPE_WEIGHT {self.d.literal(SLOPE_WEIGHT)}\n"
                      if mode == "auto" else "") + "\n")
        return [(f"over-relaxed sphere tracing, {mode} ({self.file('relaxed')})",
                 defines + self.d.library("relaxed").select(["march"])),
                (f"shadow rays ({self.file('march')})",
                 self.d.library("march").select(needs[1:], provided={"march"}))]

    def normal_code(self) -> str:
        """``estimate_normal`` for the chosen stencil (`reference_cpu.normals`)."""
        method = self.s.normal_method
        self.features.add(f"normals:{method}")
        stencil = [", ".join(self.d.literal(c) for c in k) for k in STENCILS[method]]
        return self.template("normals", method=repr(method), stencil=stencil)

    # --- lights, materials and shading --------------------------------------------------------

    def shading_parts(self) -> list[tuple[str, str]]:
        mode = self.s.shading
        self.features |= {f"shading:{m}" for m in self.models}
        shading_lib = self.d.library("shading")
        background, background_needs = self.background_code()
        path = ["path_step"] * self.path_labels
        if mode in ("normals", "depth"):
            return [(f"shading ({self.file('shading')})",
                     shading_lib.select([f"shade_{mode}"] + path + background_needs)),
                    ("the background (glsl/pipeline/background.glsl)", background)]
        if mode == "steps":
            return [(f"the path label ({self.file('shading')})", shading_lib.select(path)),
                    ("the heat colour map (glsl/pipeline/heat.glsl)", self.heat_code())]
        light_source, light_needs = self.light_code()
        lit = [m for m in self.models if m in LIT_MODES]
        # Without lights a lit surface shows its ambient term only: no diffuse or specular.
        wanted = background_needs + path
        if self.scene.lights and lit:
            wanted += ["diffuse"] + [SPECULAR[m] for m in lit] + [BANDS[m] for m in lit
                                                                 if m in BANDS]
        wanted += [f"shade_{m}" for m in self.models if m in ("normals", "depth")]
        wanted += ["checker"] * self.checker
        wanted += ["apply_fog"] * self.fog
        pairs = ([(f"shadow rays toward two lights at once ({self.file('shadow_pair')})",
                   self.d.library("shadow_pair").select(["hard_shadow_pair"]))]
                 if self.paired_lights else [])
        heat = ([("the heat colour map (glsl/pipeline/heat.glsl)", self.heat_code())]
                if "steps" in self.models else [])
        return [
            (f"lights ({self.file('lights')})", self.d.library("lights").select(light_needs)),
            (f"shading ({self.file('shading')})", shading_lib.select(wanted)),
            ("the background (glsl/pipeline/background.glsl)", background),
        ] + heat + pairs + [(f"the {', '.join(lit)} model{'s' * (len(lit) > 1)} over the "
                             "scene's lights (glsl/pipeline/shade.glsl)", light_source)]

    def material_code(self) -> str:
        """Append each object's material rows (after every fixed row); return
        ``MATERIAL(id, row)``, which reads them by object id, and ``surface_albedo``."""
        stride = 2 + 2 * self.checker + 2 * self.glass + self.mixed + 3 * self.textured
        first = len(self.block.rows)
        for k, (m, model) in enumerate(zip(self.materials, self.object_models)):
            self.block.row([*m.color, m.ka])
            self.block.row([m.kd, m.ks, m.shininess, m.kr])
            if self.checker:
                c = m.checker
                self.block.row([*c.color_a, c.scale] if c else [0, 0, 0, 1])
                self.block.row([*c.color_b, 1.0] if c else [0, 0, 0, 0])
            if self.glass:
                self.block.row([*m.absorption, m.transparency])
                self.block.row([m.ior, 0, 0, 0])
            if self.mixed:
                self.block.row([MODEL_CODES[model], 0, 0, 0])
            if self.textured:
                mapping, t = self.mappings[k], m.texture
                self.block.row(self.texture_images[k] or [0, 1, 1, 0])
                self.block.row([*t.tint, t.scale] if mapping else [0, 0, 0, 1])
                self.block.row([MAPPING_CODES[mapping], t.sharpness, 0, 0] if mapping
                               else [0, 1, 0, 0])
        if self.checker:
            self.features.add("checker")
        used = {name: MAPPING_CODES[name] for name in MAPPING_CODES if name in self.mappings}
        return self.template("materials", first=first, stride=stride, checker=self.checker,
                             glass_row=self.glass_row if self.glass else None,
                             model_row=self.model_row if self.mixed else None,
                             texture_row=self.texture_row if self.textured else None,
                             mappings=used)

    @property
    def glass_row(self) -> int:
        """The first of a material's two glass rows: (absorption, transparency), (ior)."""
        return 4 if self.checker else 2

    @property
    def model_row(self) -> int:
        """The material row whose x codes the object's shading model (`MODEL_CODES`)."""
        return self.glass_row + 2 * self.glass

    @property
    def texture_row(self) -> int:
        """The first of a material's three texture rows: the image in the atlas (first row,
        width, height, wrap), (tint, scale), (mapping code, sharpness, 0, 0)."""
        return self.model_row + self.mixed

    def pattern_features(self) -> str:
        """What the shading adds to the path label's features for the surface's pattern:
        the checker cell's parity, and the face of a cube-mapped texture (the colour may
        jump where either changes), or 0."""
        terms = (["surface_checker_parity(p, id)"] * self.checker
                 + ["surface_texture_face(n, id)"] * ("cube" in self.mappings))
        return " + ".join(terms) or "0.0"

    def light_code(self) -> tuple[str, list[str]]:
        """The shading function over the scene's lights (and the shadow functions it calls),
        and the light functions it needs."""
        lights = [{"index": i, "kind": self.light_rows(i, light),
                   "own": light.separate_colors()} for i, light in enumerate(self.scene.lights)]
        lit = [m for m in self.models if m in LIT_MODES]
        # One shade_<model> per lit model, the shadow helpers with the first.
        source = "\n".join(
            self.template("shade", lights=lights, shadows=self.s.shadows, helpers=i == 0,
                          skip_own=self.skip_own,
                          paired=self.paired_lights, features=self.pattern_features(),
                          model=m)
            for i, m in enumerate(lit))
        if self.mixed:
            codes = [{"name": m, "code": MODEL_CODES[m]} for m in self.models]
            source += "\n" + self.template("shade_surface", models=codes, row=self.model_row)
        return source, sorted({f"light_{light['kind']}" for light in lights})

    def shade_call(self) -> str:
        """How the pipeline shades a hit p, normal n, seen along d, of object id with march
        result h: the one model's shade function, or shade_surface's choice."""
        if self.mixed:
            return "shade_surface(p, n, -d, id, h)"
        return f"shade_{self.model}(p, n, -d, id)"

    def light_rows(self, i: int, light) -> str:
        """Put light ``i``'s numbers in the parameter block (``LIGHTi_POSITION``, ...), as the
        light functions of glsl/lights.glsl take them; return its kind."""
        kind = LIGHT_KINDS.get(type(light))
        if kind is None:
            raise MarchlabError(f"the shader generator does not support lights of type "
                                f"{type(light).__name__} yet; render with --backend numpy")
        self.features.add(f"light:{kind}")
        b = self.block
        radiance = np.multiply(light.color, light.intensity)
        L = f"LIGHT{i}_"
        if light.separate_colors():
            # RADIANCE is the diffuse colour; the specular and ambient ones have rows too.
            ambient, radiance, specular = light.term_colors()
            b.named({L + "SPECULAR": ("xyz", specular)})
            b.named({L + "AMBIENT": ("xyz", ambient)})
        if kind == "directional":
            direction = np.asarray(light.direction, dtype=np.float64)
            b.named({L + "TO_LIGHT": ("xyz", -direction / np.linalg.norm(direction))})
            b.named({L + "RADIANCE": ("xyz", radiance)})
            return kind
        b.named({L + "POSITION": ("xyz", light.position)})
        b.named({L + "RADIANCE": ("xyz", radiance)})
        b.named({L + "ATTENUATION": ("xyz", (light.constant, light.linear, light.quadratic))})
        if kind == "spot":
            axis = np.asarray(light.direction, dtype=np.float64)
            cos_inner = math.cos(math.radians(light.inner_angle))
            cos_outer = math.cos(math.radians(light.outer_angle))
            b.named({L + "AXIS": ("xyz", axis / np.linalg.norm(axis))})
            b.named({L + "CONE": ("xy", (cos_outer, cos_inner - cos_outer))})
        return kind

    def background_code(self) -> tuple[str, list[str]]:
        """``background(direction)`` and the shading library function it calls (an
        environment's functions are `texture_parts`)."""
        kind = self.s.background.kind
        self.features.add(f"background:{kind}")
        if kind in ENVIRONMENT_KINDS:
            sampler = "cubemap" if kind in CUBE_KINDS else "equirect"
            return self.template("background", kind=kind, sampler=sampler), []
        if kind == "solid":
            self.block.named({"BACKGROUND_COLOR": ("xyz", self.s.background.color)})
        else:
            self.block.named({"BACKGROUND_BOTTOM": ("xyz", self.s.background.bottom)})
            self.block.named({"BACKGROUND_TOP": ("xyz", self.s.background.top)})
        return self.template("background", kind=kind), [f"background_{kind}"]

    def texture_parts(self) -> list[tuple[str, str]]:
        """The program's textures: an environment background's (where the shading mode shows
        the background) and the textured objects' images in one atlas, their numbers in the
        block, and the texture and environment functions that ``background`` and
        ``surface_albedo`` call."""
        bg = self.s.background
        environment = (environment_map(bg) if bg.kind in ENVIRONMENT_KINDS
                       and self.s.shading != "steps" else None)
        if environment is None and not self.textured:
            return []
        self.features.add("texture_bilinear")
        parts, needs = [], ["texture_bilinear"]
        if environment is not None:
            self.block.named({"ENVIRONMENT_TEXTURE": ("xyzw", environment.texture)})
            self.block.named({"ENVIRONMENT_LOOK": ("xyz", (bg.intensity, *turn(bg.rotation)))})
            sampler = "background_cubemap" if environment.cube else "background_equirect"
            source = self.d.library("environment").select([sampler])
            texture = self.d.library("texture")
            # The texture functions the environment's call (the cube face rule, equirect_uv).
            needs += [f for f in texture.names() if re.search(rf"\b{f}\s*\(", source)]
            parts.append((f"environment maps ({self.file('environment')})", source))
        self.texels = environment.rgba if environment is not None else None
        if self.textured:
            images = [texture_image(m.texture) if mapping else None
                      for m, mapping in zip(self.materials, self.mappings)]
            distinct = list(dict.fromkeys(i for i in images if i is not None))
            first = (environment,) if environment is not None else ()
            atlas = texture_atlas(first + tuple(distinct))
            self.texels = atlas.rgba
            start = len(first)
            self.texture_images = [
                None if image is None else atlas.image(start + distinct.index(image),
                                                       texture_wrap(mapping))
                for image, mapping in zip(images, self.mappings)]
            used = [m for m in MAPPING_CODES if m in self.mappings]
            self.features |= {f"texture:{m}" for m in used}
            needs += [f"texture_{m}" for m in used]    # (surface_texture_face: major_face)
        title = "bilinear texture filtering" + " and surface mappings" * self.textured
        return [(f"{title} ({self.file('texture')})",
                 self.d.library("texture").select(needs))] + parts

    def texel_reader(self) -> str:
        """How the program reads its texture atlas (``TEXEL``), after every parameter row:
        "" where it reads none."""
        if self.texels is None:
            return ""
        return "\n" + self.d.texels(len(self.block.rows), self.texels.shape[1])

    def heat_code(self) -> str:
        """``heat``, linear between the stops of `scene_model.colormaps`."""
        lit = self.d.literal
        segments = [{"x0": lit(HEAT_STOPS[i]), "x1": lit(HEAT_STOPS[i + 1]),
                     "width": lit(HEAT_STOPS[i + 1] - HEAT_STOPS[i]),
                     "c0": ", ".join(lit(c) for c in HEAT_COLORS[i]),
                     "c1": ", ".join(lit(c) for c in HEAT_COLORS[i + 1])}
                    for i in range(len(HEAT_STOPS) - 1)]
        return self.template("heat", segments=segments)

    # --- the per-pixel pipeline -----------------------------------------------------------------

    def pixel_code(self) -> str:
        """``trace``, the whole pixel: with mirrors, a reflection loop that marches the camera
        ray as its first bounce; without, one march and ``pixel_color``."""
        weight = f"#define MIN_RAY_WEIGHT {self.d.literal(MIN_RAY_WEIGHT)}\n"
        if self.path_labels:
            weight += f"#define LABEL_WEIGHT {self.d.literal(LABEL_WEIGHT)}\n"
        if self.glass:
            # The tree holds at most 2^(depth + 1) - 1 rays.
            self.features.add("glass")
            self.features.add(f"fresnel:{self.s.fresnel}")
            depth = self.s.reflection_depth
            return (weight + f"#define TREE_RAYS {2 ** (depth + 1) - 1}\n\n"
                    + self.template("trace_glass", fog=self.fog, depth=depth,
                                    glass_row=self.glass_row, fresnel=self.s.fresnel))
        if self.s.shading in LIT_MODES and self.reflections:
            self.features.add("reflections")
            return weight + "\n" + self.template("trace", reflections=True, fog=self.fog)
        return (self.template("pixel", fog=self.fog) + "\n"
                + self.template("trace", reflections=False))

    def samples_code(self) -> str:
        """``supersample``: a pixel's n x n samples (and for even n its centre) traced and
        folded, at the offsets of `scene_model.sampling.ray_offsets`, written as literals."""
        n, pattern = self.s.samples, self.s.sample_pattern
        self.features.add(f"samples:{pattern}")
        offsets = [(self.d.literal(dx), self.d.literal(dy)) for dx, dy in ray_offsets(n, pattern)]
        return self.template("samples", n=n, pattern=pattern, offsets=offsets,
                             rays=len(offsets), centre=centre_sample(n),
                             count=self.d.literal(n * n))


def _banner(title: str) -> str:
    return f"// ---- {title} " + "-" * max(4, 86 - len(title)) + "\n\n"
