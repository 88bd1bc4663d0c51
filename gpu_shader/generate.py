"""The shader generator: one scene in, one readable program out, holding only what it uses.

The program is assembled in the order a reader meets it:

1. the dialect's prelude, the parameter names (``#define EPSILON P[4].x``) and the structs;
2. the SDF library functions the tree uses, then ``scene_sdf`` / ``scene_object_id``
   written from the tree (`gpu_shader.sdf_code`);
3. the march and the shadow function the settings ask for, ``estimate_normal`` for the
   chosen stencil;
4. lights of the kinds present, the shading model, checker, fog and background only if used;
5. ``trace``, the per-pixel pipeline of `reference_cpu.render`, then the entry point.

Every number that a frame may change is in the parameter block (`gpu_shader.parameters`), so
the text depends only on the scene's structure, and a program cache keyed by the text never
compiles the same structure twice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from reference_cpu.culling import culled_bounds
from reference_cpu.normals import STENCILS
from reference_cpu.relaxation import SLOPE_WEIGHT
from scene_model.camera import camera_basis
from scene_model.colormaps import HEAT_COLORS, HEAT_STOPS
from scene_model.errors import MarchlabError
from scene_model.scene import DirectionalLight, PointLight, Scene, SpotLight
from scene_model.shapes import primitives

from .dialects import MAX_FLAT_ROWS, Dialect, dialect as get_dialect
from .library import glsl_file
from .parameters import ParameterBlock
from .sdf_code import PACKET_TYPES, SCALAR_TYPES, scene_sdf_code

LIT_MODES = ("phong", "blinn_phong", "toon")
SPECULAR = {"phong": "specular_phong", "blinn_phong": "specular_blinn_phong",
            "toon": "specular_phong"}
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
    """
    source: str
    parameters: np.ndarray
    features: tuple[str, ...]
    vertex_source: str = ""


def generate(scene: Scene, width: int, height: int, dialect: str = "glsl",
             precision: str = "float32", flat_rows: int = MAX_FLAT_ROWS) -> Program:
    """Generate the program that renders ``scene`` at ``width`` x ``height``.

    ``dialect`` is "glsl" (a fragment shader) or "opencl" (a kernel); ``precision`` the
    meaning of ``real`` ("float64" only in OpenCL). In GLSL, up to ``flat_rows`` parameter
    rows read with fixed indices reach the fragment shader as flat varyings (the context's
    GL_MAX_VARYING_VECTORS at most).
    """
    try:
        language = get_dialect(dialect, precision)
    except KeyError as err:
        raise MarchlabError(err.args[0]) from None
    if language.packets:
        from .generate_packets import PacketGenerator
        return PacketGenerator(scene, language).program(width, height)
    return _Generator(scene, language, flat_rows).program(width, height)


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
    """
    defines: str
    functions: str
    parameters: np.ndarray
    features: tuple[str, ...]


def scalar_program(scene: Scene, width: int, height: int,
                   precision: str = "float32") -> ScalarProgram:
    """The one-ray OpenCL program of ``scene``, unwrapped (see `ScalarProgram`)."""
    generator = _Generator(scene, get_dialect("opencl", precision))
    parts, _ = generator.sections(width, height)
    functions = "\n".join(_banner(title) + text for title, text in parts if text)
    return ScalarProgram(generator.block.defines(), functions,
                         generator.block.values(np.float64), tuple(sorted(generator.features)))


class _Generator:
    def __init__(self, scene: Scene, dialect: Dialect, flat_rows: int = 0):
        self.scene, self.s, self.d = scene, scene.render, dialect
        self.flat_rows = flat_rows
        self.block = ParameterBlock()
        self.features: set[str] = set()
        self.primitives = list(primitives(scene.objects))
        self.materials = [scene.materials[p.material] for p in self.primitives]
        self.checker = any(m.checker is not None for m in self.materials)
        self.reflections = (self.s.reflection_depth > 0 and self.s.shading in LIT_MODES
                            and any(m.kr > 0 for m in self.materials))
        self.fog = self.s.fog.density > 0 and self.s.shading in LIT_MODES
        self.types = PACKET_TYPES if dialect.packets else SCALAR_TYPES
        # Hard shadow rays toward two lights are marched together (hard_shadow_pair) in a
        # program with one ray per pixel and plain sphere tracing (relaxed shadow rays keep
        # the relaxed march of their own): lights 0 .. paired_lights - 1, two by two. The
        # last of an odd number, or every light without pairs, is marched alone.
        lights = len(scene.lights)
        pairs = (PAIR_SHADOW_RAYS and not dialect.packets and self.s.shading in LIT_MODES
                 and self.s.shadows == "hard" and self.s.relaxation == "none")
        self.paired_lights = lights - lights % 2 if pairs else 0
        self.lone_shadows = self.paired_lights < lights

    def program(self, width: int, height: int) -> Program:
        parts, fixed = self.sections(width, height)
        entry = self.d.entry
        parts.append((f"the entry point (glsl/{entry})", glsl_file(entry)))
        rows, fixed = max(1, len(self.block.rows)), max(1, fixed)
        head = [self.d.prelude, _banner("parameters: one vec4 row each, set per frame")
                + self.d.declare_parameters(rows, fixed, self.flat_rows)]
        head.append(self.block.defines())
        head.append(self.d.structs())
        body = [_banner(title) + text for title, text in parts if text]
        source = self.d.finish("\n".join(head + body))
        return Program(source, self.block.values(np.float64), tuple(sorted(self.features)),
                       self.d.vertex_shader(rows, fixed, self.flat_rows))

    def sections(self, width: int, height: int) -> tuple[list[tuple[str, str]], int]:
        """The program's functions as (section title, text) pairs in reading order, all but
        the entry point, and the number of parameter rows read with fixed indices."""
        self.settings_rows(width, height)
        bounds = None
        if self.s.bounding_spheres:
            self.features.add("bounding_spheres")
            bounds = culled_bounds(self.scene.objects, self.s.epsilon)
        sdf_source, sdf_used = scene_sdf_code(self.scene.objects, self.block, bounds,
                                              self.types)
        self.features |= sdf_used
        parts = [
            (f"the SDF building blocks used by this scene ({self.file('sdf')})",
             self.d.library("sdf").select(sdf_used)),
            (f"bounding spheres ({self.file('culling')})",
             self.d.library("culling").select(["ray_meets_sphere"]) if bounds is not None else ""),
            ("the scene's SDF tree", sdf_source),
            (f"the camera ({self.file('camera')})", self.d.library("camera").select(["camera_ray"])),
        ]
        parts += self.march_parts()
        parts += [
            ("surface normals", self.normal_code()),
        ]
        parts += self.shading_parts()
        # Materials are read by object id; their rows come last, outside the private copy.
        fixed = len(self.block.rows)
        if self.s.shading in LIT_MODES:
            parts.insert(-1, ("materials, indexed by object id", self.material_code()))
        parts.append(("the per-pixel pipeline (reference_cpu/render.py)", self.pixel_code()))
        return parts, fixed

    def file(self, name: str) -> str:
        """Where the building blocks ``name`` come from, for the program's section titles."""
        return self.d.library(name).file

    # --- parameters that every program has --------------------------------------------------

    def settings_rows(self, width: int, height: int):
        s, camera, b = self.s, self.scene.camera, self.block
        forward, right, up = camera_basis(camera)
        half_height = math.tan(math.radians(camera.fov) / 2)
        b.named({"CAMERA_POSITION": ("xyz", camera.position)})
        b.named({"CAMERA_FORWARD": ("xyz", forward)})
        b.named({"CAMERA_RIGHT": ("xyz", right)})
        b.named({"CAMERA_UP": ("xyz", up)})
        b.named({"HALF_WIDTH": ("x", half_height * width / height), "HALF_HEIGHT": ("y", half_height),
                 "IMAGE_WIDTH": ("z", width), "IMAGE_HEIGHT": ("w", height)})
        b.named({"EPSILON": ("x", s.epsilon), "MAX_DISTANCE": ("y", s.max_distance),
                 "NORMAL_STEP": ("z", s.normal_step), "SURFACE_OFFSET": ("w", s.surface_offset)})
        b.named({"MAX_STEPS": ("x", s.max_steps), "REFLECTION_DEPTH": ("y", s.reflection_depth),
                 "PENUMBRA_K": ("z", s.penumbra_k), "TOON_BANDS": ("w", s.toon_bands)})
        # Loop bounds are integers; the block holds floats, exact for any sensible count.
        b.names = [(n, self.d.to_int(e) if n in ("MAX_STEPS", "REFLECTION_DEPTH") else e)
                   for n, e in b.names]
        b.named({"AMBIENT": ("xyz", s.ambient)})
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
            return [(f"sphere tracing ({self.file('march')})", self.d.library("march").select(needs))]
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
        """``estimate_normal`` written out for the chosen stencil (`reference_cpu.normals`)."""
        method = self.s.normal_method
        self.features.add(f"normals:{method}")
        lines = [f"// Normal by finite differences, the {method!r} stencil of reference_cpu/normals.py:",
                 "// n = normalize(sum_k k scene_sdf(p + h k)); zero where the gradient vanishes.",
                 "vec3 estimate_normal(vec3 p)", "{", "    real h = NORMAL_STEP;",
                 "    vec3 g = vec3(0.0);"]
        for k in STENCILS[method]:
            k = ", ".join(self.d.literal(c) for c in k)
            lines.append(f"    g = g + scene_sdf(p + h * vec3({k})) * vec3({k});")
        lines += ["    real size = sqrt(dot(g, g));",
                  "    return size > 0.0 ? g / size : vec3(0.0);", "}", ""]
        return "\n".join(lines)

    # --- lights, materials and shading --------------------------------------------------------

    def shading_parts(self) -> list[tuple[str, str]]:
        mode = self.s.shading
        self.features.add(f"shading:{mode}")
        shading_lib = self.d.library("shading")
        background = self.background_code()
        if mode == "normals":
            return [(f"shading ({self.file('shading')})", shading_lib.select(["shade_normals", "path_step"] + background[1])),
                    ("the background", background[0])]
        if mode == "depth":
            return [(f"shading ({self.file('shading')})", shading_lib.select(["shade_depth", "path_step"] + background[1])),
                    ("the background", background[0])]
        if mode == "steps":
            return [(f"the path label ({self.file('shading')})", shading_lib.select(["path_step"])),
                    ("the heat colour map (scene_model/colormaps.py)", self.heat_code())]
        light_source, light_needs = self.light_code()
        wanted = ["diffuse", SPECULAR[mode]] + background[1]
        wanted += ["toon_band"] * (mode == "toon") + ["checker"] * self.checker + ["path_step"]
        wanted += ["apply_fog"] * self.fog
        pairs = ([(f"shadow rays toward two lights at once ({self.file('shadow_pair')})",
                   self.d.library("shadow_pair").select(["hard_shadow_pair"]))]
                 if self.paired_lights else [])
        return [
            (f"lights ({self.file('lights')})", self.d.library("lights").select(light_needs)),
            (f"shading ({self.file('shading')})", shading_lib.select(wanted)),
            ("the background", background[0]),
        ] + pairs + [(f"the {mode} model over the scene's lights", light_source)]

    def material_rows(self) -> tuple[int, int, str]:
        """Append each object's material rows; return the first row, the rows per object
        and a comment saying what the rows hold."""
        stride = 4 if self.checker else 2
        first = len(self.block.rows)
        for m in self.materials:
            self.block.row([*m.color, m.ka])
            self.block.row([m.kd, m.ks, m.shininess, m.kr])
            if self.checker:
                c = m.checker
                self.block.row([*c.color_a, c.scale] if c else [0, 0, 0, 1])
                self.block.row([*c.color_b, 1.0] if c else [0, 0, 0, 0])
        if self.checker:
            self.features.add("checker")
        return first, stride, ("// Row 0: (color, ka); row 1: (kd, ks, shininess, kr)"
                               + ("; row 2: (checker color_a, scale);\n// row 3: (checker color_b, "
                                  "1 if checkered)." if self.checker else "."))

    def material_code(self) -> str:
        """Material rows per object id, and ``surface_albedo``."""
        first, stride, rows = self.material_rows()
        lines = [rows, f"#define MATERIAL(id, row) U[{first} + {stride} * (id) + (row)]", ""]
        lines += ["vec3 surface_albedo(vec3 p, int id)", "{"]
        if self.checker:
            lines += ["    if (MATERIAL(id, 3).w > 0.0) {",
                      "        return checker(p, MATERIAL(id, 2).xyz, MATERIAL(id, 3).xyz, MATERIAL(id, 2).w);",
                      "    }"]
        lines += ["    return MATERIAL(id, 0).xyz;", "}", ""]
        if self.checker:
            lines += ["real surface_checker_parity(vec3 p, int id)", "{",
                      "    return MATERIAL(id, 3).w > 0.0 ? checker_parity(p, MATERIAL(id, 2).w) : 0.0;",
                      "}", ""]
        return "\n".join(lines)

    def light_code(self) -> tuple[str, list[str]]:
        """The shading function, one block per light, and the light functions it calls."""
        mode, needs = self.s.shading, set()
        term, spec = self.light_terms()
        lines = [f"// The {mode} model (reference_cpu/shading.py) summed over the lights, plus ambient.",
                 "// Returns (colour, features): features codes the checker cell and, one bit per",
                 "// light, whether a hard shadow blocked it (for the path label).",
                 f"vec4 shade_{mode}(vec3 p, vec3 n, vec3 v, int id)", "{",
                 "    vec3 albedo = surface_albedo(p, id);",
                 "    real ka = MATERIAL(id, 0).w;",
                 "    real kd = MATERIAL(id, 1).x;",
                 "    real ks = MATERIAL(id, 1).y;",
                 "    real shininess = MATERIAL(id, 1).z;",
                 "    vec3 color = ka * albedo * AMBIENT;",
                 f"    real features = {'surface_checker_parity(p, id)' if self.checker else '0.0'};",
                 "    real visible;",
                 "    LightSample s;"]
        calls = [self.light_call(i, light) for i, light in enumerate(self.scene.lights)]
        paired = self.paired_lights
        if paired:
            lines.append("    // The lights' samples first: their hard shadow rays are marched two by two.")
            lines += [f"    LightSample s{i} = {call};" for i, (_, call) in enumerate(calls)]
            lines += [f"    vec2 visible{i}{i + 1} = lights_visible(p, n, s{i}, s{i + 1});"
                      for i in range(0, paired, 2)]
        for i, (kind, call) in enumerate(calls):
            needs.add(f"light_{kind}")
            lines.append(f"    // light {i}: {kind}")
            lines.append(f"    s = {f's{i}' if paired else call};")
            if self.s.shadows != "none":
                if i < paired:
                    first = i - i % 2
                    lines.append(f"    visible = visible{first}{first + 1}.{'xy'[i % 2]};")
                else:
                    lines.append("    visible = light_visible(p, n, s);")
                lines.append("    s.radiance = visible * s.radiance;")
                blocked = "(visible == 0.0 ? 1.0 : 0.0)" if self.s.shadows == "hard" else "0.0"
                lines.append(f"    features = 2.0 * features + {blocked};")
            else:
                lines.append("    features = 2.0 * features;")
            lines.append(f"    color = color + s.radiance * (kd * {term} * albedo + ks * {spec});")
        lines += ["    return vec4(color, features);", "}", ""]
        source = "\n".join(lines)
        if self.s.shadows != "none" and self.scene.lights:
            source = self.shadow_code() + "\n" + source
        return source, sorted(needs)

    def light_terms(self) -> tuple[str, str]:
        """The diffuse and specular terms of one light sample ``s`` in the shading mode."""
        mode = self.s.shading
        term = {"phong": "diffuse(n, s.to_light)", "blinn_phong": "diffuse(n, s.to_light)",
                "toon": "toon_band(diffuse(n, s.to_light), TOON_BANDS)"}[mode]
        spec = f"{SPECULAR[mode]}(n, s.to_light, v, shininess)"
        if mode == "toon":
            spec = f"toon_band({spec}, TOON_BANDS)"
        return term, spec

    def light_call(self, i: int, light) -> tuple[str, str]:
        """Put light ``i``'s numbers in the parameter block; return its kind and the call
        that samples it at p."""
        kind = LIGHT_KINDS.get(type(light))
        if kind is None:
            raise MarchlabError(f"the shader generator does not support lights of type "
                                f"{type(light).__name__} yet; render with --backend numpy")
        self.features.add(f"light:{kind}")
        b = self.block
        radiance = np.multiply(light.color, light.intensity)
        L = f"LIGHT{i}_"
        if kind == "directional":
            direction = np.asarray(light.direction, dtype=np.float64)
            b.named({L + "TO_LIGHT": ("xyz", -direction / np.linalg.norm(direction))})
            b.named({L + "RADIANCE": ("xyz", radiance)})
            return kind, f"light_directional({L}TO_LIGHT, {L}RADIANCE)"
        b.named({L + "POSITION": ("xyz", light.position)})
        b.named({L + "RADIANCE": ("xyz", radiance)})
        b.named({L + "ATTENUATION": ("xyz", (light.constant, light.linear, light.quadratic))})
        if kind == "point":
            return kind, f"light_point(p, {L}POSITION, {L}RADIANCE, {L}ATTENUATION)"
        axis = np.asarray(light.direction, dtype=np.float64)
        cos_inner = math.cos(math.radians(light.inner_angle))
        cos_outer = math.cos(math.radians(light.outer_angle))
        b.named({L + "AXIS": ("xyz", axis / np.linalg.norm(axis))})
        b.named({L + "CONE": ("xy", (cos_outer, cos_inner - cos_outer))})
        return kind, f"light_spot(p, {L}POSITION, {L}RADIANCE, {L}ATTENUATION, {L}AXIS, {L}CONE)"

    def shadow_code(self) -> str:
        lines = [
            "// Whether light s needs a shadow ray at p: points facing away from the light, or",
            "// where it sends nothing, need none, as their diffuse and specular terms are zero",
            "// whatever the visibility (taken as 1).",
            "bool needs_shadow_ray(vec3 n, LightSample s)",
            "{",
            "    return dot(n, s.to_light) > 0.0 && max(s.radiance.x, max(s.radiance.y, s.radiance.z)) > 0.0;",
            "}",
            ""]
        origin = ["// Shadow rays start SURFACE_OFFSET off the surface (else they find the surface",
                  "// itself: shadow acne)."]
        if self.lone_shadows:
            lines += ["// How much of light s reaches p."] + origin + [
                "real light_visible(vec3 p, vec3 n, LightSample s)",
                "{",
                "    if (!needs_shadow_ray(n, s)) {",
                "        return 1.0;",
                "    }",
                "    vec3 origin = p + SURFACE_OFFSET * n;",
                f"    return {self.s.shadows}_shadow(origin, s.to_light, s.distance);",
                "}", ""]
        if self.paired_lights:
            lines += ["// How much of lights a and b reaches p, their shadow rays marched together."] + origin + [
                "vec2 lights_visible(vec3 p, vec3 n, LightSample a, LightSample b)",
                "{",
                "    vec3 origin = p + SURFACE_OFFSET * n;",
                "    return hard_shadow_pair(origin, a.to_light, a.distance, needs_shadow_ray(n, a),",
                "                            b.to_light, b.distance, needs_shadow_ray(n, b));",
                "}", ""]
        return "\n".join(lines)

    def background_code(self) -> tuple[str, list[str]]:
        bg = self.s.background
        self.features.add(f"background:{bg.kind}")
        if bg.kind == "solid":
            self.block.named({"BACKGROUND_COLOR": ("xyz", bg.color)})
            call, needs = "background_solid(direction, BACKGROUND_COLOR)", ["background_solid"]
        else:
            self.block.named({"BACKGROUND_BOTTOM": ("xyz", bg.bottom)})
            self.block.named({"BACKGROUND_TOP": ("xyz", bg.top)})
            call, needs = ("background_sky(direction, BACKGROUND_BOTTOM, BACKGROUND_TOP)",
                           ["background_sky"])
        vec3 = self.types["vec3"]
        return f"{vec3} background({vec3} direction)\n{{\n    return {call};\n}}\n", needs

    def heat_code(self) -> str:
        """``heat`` by linear interpolation between the stops of `scene_model.colormaps`."""
        lit = self.d.literal
        lines = ["// The heat ramp of scene_model/colormaps.py: linear between its stops.",
                 "vec3 heat(real x)", "{", "    x = clamp(x, 0.0, 1.0);"]
        for i in range(len(HEAT_STOPS) - 1):
            x0, x1 = HEAT_STOPS[i], HEAT_STOPS[i + 1]
            c0 = ", ".join(lit(c) for c in HEAT_COLORS[i])
            c1 = ", ".join(lit(c) for c in HEAT_COLORS[i + 1])
            test = f"if (x <= {lit(x1)}) " if i < len(HEAT_STOPS) - 2 else ""
            lines.append(f"    {test}return vec3({c0}) + (vec3({c1}) - vec3({c0})) * "
                         f"((x - {lit(x0)}) / {lit(x1 - x0)});")
        lines += ["}", ""]
        return "\n".join(lines)

    # --- the per-pixel pipeline -----------------------------------------------------------------

    def pixel_code(self) -> str:
        """``trace``, the whole pixel: glsl/trace.glsl's around a generated ``pixel_color``,
        or, with mirrors, a generated one whose reflection loop marches the camera ray too."""
        if self.s.shading in LIT_MODES and self.reflections:
            return self.reflection_trace_code()
        return self.pixel_color_code() + "\n" + self.d.library("trace").select(["trace"])

    def pixel_color_code(self) -> str:
        mode = self.s.shading
        head = ["// The colour of one pixel and its path label, given its primary ray, the march",
                "// result h and, on a hit, the normal n and object id there",
                "// (reference_cpu/render.py, Tracer.trace).",
                "vec4 pixel_color(vec3 origin, vec3 direction, Hit h, vec3 n, int id)", "{"]
        path = f"{self.d.to_real('path_step(0u, id, 0u)')}"
        if mode == "steps":                  # the colour jumps with every step: label them
            path = f"{self.d.to_real('path_step(uint(h.steps), id, 0u)')}"
            color = f"heat({self.d.to_real('h.steps')} / {self.d.to_real('MAX_STEPS')})"
        elif mode == "normals":
            color = "h.hit == 1 ? shade_normals(n) : background(direction)"
        elif mode == "depth":
            color = "h.hit == 1 ? shade_depth(h.t, MAX_DISTANCE) : background(direction)"
        else:
            return self.lit_pixel_code(head)
        return "\n".join(head + [f"    return vec4({color}, {path});", "}", ""])

    def lit_pixel_code(self, head: list[str]) -> str:
        """Shading and fog of the primary hit (no mirrors: one bounce)."""
        shade = f"shade_{self.s.shading}(p, n, -d, id)"
        fog = ["    shaded = apply_fog(shaded, h.t, FOG_COLOR, FOG_DENSITY);"] if self.fog else []
        to_real = self.d.to_real
        return "\n".join(head + [
            "    if (h.hit == 0) {",
            f"        return vec4(background(direction), {to_real('path_step(0u, -1, 0u)')});",
            "    }",
            "    vec3 d = direction;",
            "    precise vec3 p = origin + h.t * d;",
            f"    vec4 lit = {shade};",
            "    vec3 shaded = lit.xyz;"] + fog + [
            f"    return vec4(shaded, {to_real('path_step(0u, id, uint(lit.w))')});", "}", ""])

    def reflection_trace_code(self) -> str:
        """``trace`` with source 000's reflection loop, the camera ray its first bounce."""
        self.features.add("reflections")
        shade = f"shade_{self.s.shading}(p, n, -d, id)"
        fog = ["        shaded = apply_fog(shaded, h.t, FOG_COLOR, FOG_DENSITY);"] if self.fog else []
        return "\n".join([
            "// One pixel, from its camera ray to everything the Frame holds (reference_cpu/render.py,",
            "// Tracer.trace and lit_color). Each bounce marches its ray, shades the hit and adds",
            "// the colour weighted by the product of the kr seen so far; a ray that hits nothing",
            "// adds the background. Bounce 0 is the camera ray: its march, normal and object id",
            "// are the pixel's primary buffers. (The reference marches the camera ray first, then",
            "// loops; here the loop does it, so that llvmpipe, which runs every statement of a",
            "// loop body for a whole block of pixels, never runs a march or a normal twice.)",
            "Pixel trace(vec3 origin, vec3 direction)", "{",
            "    Pixel px;",
            "    px.normal = vec3(0.0);",
            "    px.id = -1;",
            "    vec3 color = vec3(0.0);",
            "    uint path = 0u;",
            "    real weight = 1.0;",
            "    vec3 o = origin;",
            "    vec3 d = direction;",
            "    for (int bounce = 0; bounce <= REFLECTION_DEPTH; bounce++) {",
            "        Hit h = march(o, d, MAX_DISTANCE);",
            "        if (bounce == 0) {",
            "            px.primary = h;",
            "        }",
            "        if (h.hit == 0) {",
            "            color = color + weight * background(d);",
            "            path = path_step(path, -1, 0u);",
            "            break;",
            "        }",
            "        precise vec3 p = o + h.t * d;",
            "        vec3 n = estimate_normal(p);",
            "        int id = scene_object_id(p);",
            "        if (bounce == 0) {",
            "            px.normal = n;",
            "            px.id = id;",
            "        }",
            f"        vec4 lit = {shade};",
            "        vec3 shaded = lit.xyz;"] + fog + [
            "        color = color + weight * shaded;",
            "        path = path_step(path, id, uint(lit.w));",
            "        weight = weight * MATERIAL(id, 1).w;",
            "        if (bounce == REFLECTION_DEPTH || !(weight > 0.0)) {",
            "            break;",
            "        }",
            "        // Continue just off the mirror, in the mirrored direction.",
            "        o = p + SURFACE_OFFSET * n;",
            "        d = reflect(d, n);",
            "    }",
            f"    px.color_path = vec4(color, {self.d.to_real('path')});",
            "    return px;", "}", ""])


def _banner(title: str) -> str:
    return f"// ---- {title} " + "-" * max(4, 86 - len(title)) + "\n\n"
