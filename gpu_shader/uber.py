"""One "uber" fragment shader for every scene it supports, to time against the specialised one.

`gpu_shader.generate` writes a program per scene holding only what the scene uses. The uber
program is the other design (one shader with an ``if`` per technique): ONE
text, the same for every scene, holding every primitive, light kind, shading mode, shadow
mode, fog, background, checker and normal stencil, each chosen at run time by values in the
parameter block. The scene becomes tables of rows (the layout is written into the program as
``#define`` lines, see `LAYOUT`)::

    header    (private copy P)  camera, settings, mode codes, the normal stencil
    heat      3 rows a segment  the `steps` colour ramp of scene_model/colormaps.py
    lights    5 rows a light    (position or direction, kind), radiance, attenuation, axis, cone
    objects   16 rows an object (shape, transforms, bit, own), bounding sphere,
                                two shape rows, then up to 4 transforms of 3 rows each
    materials 4 rows an object  as the specialised program's MATERIAL(id, row)

``glsl/uber.glsl`` walks these tables; the numbers it computes are those of the specialised
program, expression for expression, so both render the same `Frame`. `compare_specialised_uber`
times the two on one context.
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from reference_cpu.culling import MAX_CULLED, object_bits, own_objects
from reference_cpu.normals import STENCILS
from reference_cpu.refraction import LABEL_WEIGHT, MIN_RAY_WEIGHT
from scene_model.camera import camera_basis
from scene_model.colormaps import HEAT_COLORS, HEAT_STOPS
from scene_model.errors import MarchlabError
from scene_model.scene import DirectionalLight, PointLight, Scene, SpotLight, rendered_scene
from scene_model.shapes import (Box, CappedCylinder, Capsule, Cone, Disk, HexPrism, Plane, Pyramid,
                                Rotate, RoundBox, Scale, Sphere, Torus, Translate)

from .context import renderer_name
from .dialects import GLSL, MAX_FLAT_ROWS
from .generate import Program, generate
from .library import fill_template, glsl_file, load_library
from .parameters import ParameterBlock
from .render import ShaderCompileError, _renderer, compile_message
from .sdf_code import primitive_parameters, transform_parameters

# Codes of the run-time switches; written into the program as #define NAME code.
SHAPES = {Sphere: "SHAPE_SPHERE", Box: "SHAPE_BOX", RoundBox: "SHAPE_ROUND_BOX",
          Plane: "SHAPE_PLANE", Torus: "SHAPE_TORUS", CappedCylinder: "SHAPE_CAPPED_CYLINDER",
          Capsule: "SHAPE_CAPSULE", Cone: "SHAPE_CONE", Pyramid: "SHAPE_PYRAMID",
          Disk: "SHAPE_DISK", HexPrism: "SHAPE_HEX_PRISM"}
TRANSFORMS = {Translate: "TRANSFORM_TRANSLATE", Rotate: "TRANSFORM_ROTATE",
              Scale: "TRANSFORM_SCALE"}
LIGHTS = {DirectionalLight: "LIGHT_DIRECTIONAL", PointLight: "LIGHT_POINT",
          SpotLight: "LIGHT_SPOT"}
SHADING = ("phong", "blinn_phong", "toon", "normals", "depth", "steps")
SHADOWS = ("none", "hard", "soft")
BACKGROUNDS = ("solid", "sky")
CODES = {name: code for names in (SHAPES.values(), TRANSFORMS.values(), LIGHTS.values())
         for code, name in enumerate(names)}
CODES |= {f"SHADING_{m.upper()}": c for c, m in enumerate(SHADING)}
CODES |= {f"SHADOWS_{m.upper()}": c for c, m in enumerate(SHADOWS)}
CODES |= {f"BACKGROUND_{m.upper()}": c for c, m in enumerate(BACKGROUNDS)}

# Capacities: the program declares a fixed block, so these are the most a scene may have.
MAX_OBJECTS = MAX_CULLED           # one culling bit each
MAX_LIGHTS = 8
MAX_TRANSFORMS = 4                 # transforms above one primitive
MAX_STENCIL = max(len(k) for k in STENCILS.values())
HEAT_SEGMENTS = len(HEAT_STOPS) - 1

# Rows of one record in each table, and where the object record's parts start.
LIGHT_STRIDE, MATERIAL_STRIDE, HEAT_STRIDE = 5, 4, 3
BOUND_ROW, SHAPE_ROW, TRANSFORM_ROW = 1, 2, 4
OBJECT_STRIDE = TRANSFORM_ROW + 3 * MAX_TRANSFORMS

# Header rows: those named in `_header` (fixed by the code, checked there) and the stencil.
HEADER_NAMED_ROWS = 12
HEADER_ROWS = HEADER_NAMED_ROWS + MAX_STENCIL
HEAT_START = HEADER_ROWS
LIGHTS_START = HEAT_START + HEAT_STRIDE * HEAT_SEGMENTS
OBJECTS_START = LIGHTS_START + LIGHT_STRIDE * MAX_LIGHTS
MATERIALS_START = OBJECTS_START + OBJECT_STRIDE * MAX_OBJECTS
ROWS = MATERIALS_START + MATERIAL_STRIDE * MAX_OBJECTS   # 710: under the 1024 GL promises

LAYOUT = {"HEAT_SEGMENTS": HEAT_SEGMENTS, "BOUND_ROW": BOUND_ROW, "SHAPE_ROW": SHAPE_ROW,
          "TRANSFORM_ROW": TRANSFORM_ROW}
ACCESSORS = f"""\
// Record `row` of object i, light i, material i (by object id), heat segment i; stencil k.
#define OBJECT(i, row) U[{OBJECTS_START} + {OBJECT_STRIDE} * (i) + (row)]
#define LIGHT(i, row) U[{LIGHTS_START} + {LIGHT_STRIDE} * (i) + (row)]
#define MATERIAL(id, row) U[{MATERIALS_START} + {MATERIAL_STRIDE} * (id) + (row)]
#define HEAT(i, row) U[{HEAT_START} + {HEAT_STRIDE} * (i) + (row)]
#define STENCIL(k) P[{HEADER_NAMED_ROWS} + (k)].xyz
"""
# Named header values read as integers (the block holds floats, exact for these).
INTEGERS = {"MAX_STEPS", "REFLECTION_DEPTH", "SHADING_MODE", "SHADOW_MODE", "BACKGROUND_KIND",
            "OBJECT_COUNT", "LIGHT_COUNT", "STENCIL_SIZE"}
# The interpreter functions the march needs before it (glsl/uber.glsl's first section).
SCENE_FUNCTIONS = ["scene_sdf", "scene_object_id", "ray_objects", "march_sdf"]

FEATURES = tuple(sorted(
    ["uber", "bounding_spheres", "checker", "fog", "reflections"]
    + [f"sdf_{n[6:].lower()}" for n in SHAPES.values()]
    + [f"light:{n[6:].lower()}" for n in LIGHTS.values()]
    + [f"shading:{m}" for m in SHADING] + [f"shadows:{m}" for m in SHADOWS[1:]]
    + [f"background:{b}" for b in BACKGROUNDS] + [f"normals:{m}" for m in STENCILS]))


def uber_program(scene: Scene, width: int, height: int) -> Program:
    """The uber program and its parameter block for ``scene`` at ``width`` x ``height``.

    ``Program.source`` is the same text for every scene; ``Program.parameters`` is a
    (`ROWS`, 4) float64 array that fills the whole declared block. Raises MarchlabError, in
    one line, for what the uber shader cannot hold: an operator, a repetition, relaxed
    marching, the cone pre-pass, or more objects, lights or transforms than its tables have
    rows for.
    """
    block = _header(scene, width, height)
    for k in STENCILS[scene.render.normal_method]:
        block.row(k)
    rows = np.zeros((ROWS, 4))
    rows[:len(block.rows)] = block.values(np.float64)
    for i, (x0, x1) in enumerate(zip(HEAT_STOPS[:-1], HEAT_STOPS[1:])):
        at = HEAT_START + HEAT_STRIDE * i
        rows[at:at + HEAT_STRIDE, :] = [[*HEAT_COLORS[i], x0], [*HEAT_COLORS[i + 1], x1],
                                        [x1 - x0, 0, 0, 0]]
    for i, light in enumerate(scene.lights):
        at = LIGHTS_START + LIGHT_STRIDE * i
        rows[at:at + LIGHT_STRIDE] = _light_rows(light)
    s = scene.render
    skip_own = s.shadow_skip_own and s.shadows == "hard"
    object_bit = object_bits(scene.objects, s.epsilon, s.bounding_spheres, skip_own)
    # An object with a bit but no bounding sphere has radius -1: every ray meets it.
    bits = {index: (bit, [0.0, 0.0, 0.0, -1.0] if centre is None else [*centre, radius])
            for bit, (index, centre, radius) in enumerate(object_bit)}
    own = set(own_objects(scene.objects, object_bit).tolist()) if skip_own else set()
    for i, node in enumerate(scene.objects):
        at = OBJECTS_START + OBJECT_STRIDE * i
        primitive, record = _object_rows(node)
        bit, sphere = bits.get(i, (-1, [0.0] * 4))
        record[0][2:] = [bit, float(i in own)]
        record[BOUND_ROW] = sphere
        rows[at:at + OBJECT_STRIDE] = record
        at = MATERIALS_START + MATERIAL_STRIDE * i
        rows[at:at + MATERIAL_STRIDE] = _material_rows(scene.materials[primitive.material])
    return Program(_source(block), rows, FEATURES,
                   GLSL.vertex_shader(ROWS, HEADER_ROWS, MAX_FLAT_ROWS), path_labels=True)


def _header(scene: Scene, width: int, height: int) -> ParameterBlock:
    """The named rows: those of `generate`'s settings, then the mode codes and counts."""
    s, camera, b = scene.render, scene.camera, ParameterBlock()
    if s.relaxation != "none":
        raise MarchlabError(f"the uber shader marches with plain sphere tracing only "
                            f"(relaxation = {s.relaxation!r}); render with backend gpu")
    if s.prepass != "none":
        raise MarchlabError(f"the uber shader marches every ray from the eye (prepass = "
                            f"{s.prepass!r}); render with backend gpu")
    if s.background.kind not in BACKGROUNDS:
        raise MarchlabError(f"the uber shader draws a solid or sky background only (background "
                            f"type = {s.background.kind!r}); render with backend gpu")
    if s.shading not in SHADING or any(m.shading for m in scene.materials.values()):
        raise MarchlabError(f"the uber shader shades every object by one of "
                            f"{', '.join(SHADING)} (the scene asks for {s.shading!r}, or a "
                            "material for its own); render with backend gpu")
    if any(light.separate_colors() for light in scene.lights):
        raise MarchlabError("the uber shader takes lights of one colour (a light gives its own "
                            "ambient, diffuse or specular colour); render with backend gpu")
    if any(m.transparency > 0 for m in scene.materials.values()):
        raise MarchlabError("the uber shader draws opaque materials only (a material has "
                            "transparency > 0); render with backend gpu")
    if any(m.texture is not None for m in scene.materials.values()):
        raise MarchlabError("the uber shader draws plain and checkered materials only (a "
                            "material has a texture); render with backend gpu")
    if s.samples != 1:
        raise MarchlabError(f"the uber shader traces one ray a pixel (samples = {s.samples}); "
                            "render with backend gpu")
    for what, count, most in (("objects", len(scene.objects), MAX_OBJECTS),
                              ("lights", len(scene.lights), MAX_LIGHTS)):
        if count > most:
            raise MarchlabError(f"the uber shader holds at most {most} {what} (the scene "
                                f"has {count})")
    forward, right, up = camera_basis(camera)
    half_height = math.tan(math.radians(camera.fov) / 2)
    background = s.background
    bottom = background.color if background.kind == "solid" else background.bottom
    top = background.color if background.kind == "solid" else background.top
    for fields in (
            {"CAMERA_POSITION": ("xyz", camera.position)},
            {"CAMERA_FORWARD": ("xyz", forward)},
            {"CAMERA_RIGHT": ("xyz", right)},
            {"CAMERA_UP": ("xyz", up)},
            {"HALF_WIDTH": ("x", half_height * width / height), "HALF_HEIGHT": ("y", half_height),
             "IMAGE_WIDTH": ("z", width), "IMAGE_HEIGHT": ("w", height)},
            {"EPSILON": ("x", s.epsilon), "MAX_DISTANCE": ("y", s.max_distance),
             "NORMAL_STEP": ("z", s.normal_step), "SURFACE_OFFSET": ("w", s.surface_offset)},
            {"MAX_STEPS": ("x", s.max_steps), "REFLECTION_DEPTH": ("y", s.reflection_depth),
             "PENUMBRA_K": ("z", s.penumbra_k), "TOON_BANDS": ("w", s.toon_bands)},
            {"AMBIENT": ("xyz", s.ambient), "SHADING_MODE": ("w", SHADING.index(s.shading))},
            {"FOG_COLOR": ("xyz", s.fog.color), "FOG_DENSITY": ("w", s.fog.density)},
            {"BACKGROUND_BOTTOM": ("xyz", bottom),
             "BACKGROUND_KIND": ("w", BACKGROUNDS.index(background.kind))},
            {"BACKGROUND_TOP": ("xyz", top)},
            {"SHADOW_MODE": ("x", SHADOWS.index(s.shadows)),
             "OBJECT_COUNT": ("y", len(scene.objects)), "LIGHT_COUNT": ("z", len(scene.lights)),
             "STENCIL_SIZE": ("w", len(STENCILS[s.normal_method]))}):
        b.named(fields)
    assert len(b.rows) == HEADER_NAMED_ROWS
    b.names = [(n, f"int({e})" if n in INTEGERS else e) for n, e in b.names]
    return b


def _object_rows(node) -> tuple[object, list[list[float]]]:
    """(the primitive, the `OBJECT_STRIDE` rows of its record) for one top-level object:
    transforms above one primitive, outermost first."""
    record = [[0.0] * 4 for _ in range(OBJECT_STRIDE)]
    transforms = 0
    while type(node) in TRANSFORMS:
        if transforms == MAX_TRANSFORMS:
            raise MarchlabError(f"the uber shader holds at most {MAX_TRANSFORMS} transforms "
                                "above a primitive")
        _, values, _ = transform_parameters(node)     # the rows the specialised code reads
        values = [list(v) for v in values]
        values[0] = values[0] + [0.0] * (3 - len(values[0])) + [CODES[TRANSFORMS[type(node)]]]
        at = TRANSFORM_ROW + 3 * transforms
        for r, v in enumerate(values):
            record[at + r][:len(v)] = v
        transforms += 1
        node = node.child
    if type(node) not in SHAPES:
        kind = getattr(node, "kind", "") or type(node).__name__
        raise MarchlabError(f"the uber shader supports transformed primitives joined by union "
                            f"only; this scene has a {kind!r} ({type(node).__name__}) node")
    values, _ = primitive_parameters(node)
    for r, v in enumerate(values):
        record[SHAPE_ROW + r][:len(v)] = list(v)
    record[0][:2] = [CODES[SHAPES[type(node)]], transforms]
    return node, record


def _light_rows(light) -> list[list[float]]:
    """The `LIGHT_STRIDE` rows of one light, with the values `generate` puts in its rows."""
    rows = [[0.0] * 4 for _ in range(LIGHT_STRIDE)]
    if type(light) not in LIGHTS:
        raise MarchlabError(f"the uber shader does not support lights of type "
                            f"{type(light).__name__}")
    code = CODES[LIGHTS[type(light)]]
    rows[1][:3] = np.multiply(light.color, light.intensity)
    if isinstance(light, DirectionalLight):
        direction = np.asarray(light.direction, dtype=np.float64)
        rows[0] = [*(-direction / np.linalg.norm(direction)), code]
        return rows
    rows[0] = [*light.position, code]
    rows[2][:3] = [light.constant, light.linear, light.quadratic]
    if isinstance(light, SpotLight):
        axis = np.asarray(light.direction, dtype=np.float64)
        cos_inner = math.cos(math.radians(light.inner_angle))
        cos_outer = math.cos(math.radians(light.outer_angle))
        rows[3][:3] = axis / np.linalg.norm(axis)
        rows[4][:2] = [cos_outer, cos_inner - cos_outer]
    return rows


def _material_rows(m) -> list[list[float]]:
    c = m.checker
    return [[*m.color, m.ka], [m.kd, m.ks, m.shininess, m.kr],
            [*c.color_a, c.scale] if c else [0, 0, 0, 1],
            [*c.color_b, 1.0] if c else [0, 0, 0, 0]]


def _source(block: ParameterBlock) -> str:
    """The program text: the same for every scene, as only the header's names reach it."""
    glsl = GLSL
    sdf_needs = [f"sdf_{n[6:].lower()}" for n in SHAPES.values()]
    sdf_needs += ["op_union", "op_translate", "op_rotate", "op_scale"]
    shading = ["diffuse", "specular_phong", "specular_blinn_phong", "toon_band", "checker",
               "checker_parity", "path_step", "shade_normals", "shade_depth", "apply_fog",
               "background_solid", "background_sky"]
    uber = load_library("uber")
    weights = {"MIN_RAY_WEIGHT": glsl.literal(MIN_RAY_WEIGHT),
               "LABEL_WEIGHT": glsl.literal(LABEL_WEIGHT)}
    layout = "".join(f"#define {name} {value}\n" for name, value in
                     {**CODES, **LAYOUT, **weights}.items()) + "\n" + ACCESSORS
    parts = [
        ("the SDF building blocks (glsl/sdf.glsl)", load_library("sdf").select(sdf_needs)),
        ("bounding spheres (glsl/culling.glsl)",
         load_library("culling").select(["ray_meets_sphere"])),
        ("the scene's SDF, read from the object table (glsl/uber.glsl)",
         uber.header + "\n\n" + uber.select(SCENE_FUNCTIONS)),
        ("the camera (glsl/camera.glsl)", load_library("camera").select(["camera_ray"])),
        ("sphere tracing and shadow rays (glsl/march.glsl)",
         load_library("march").select(["march", "hard_shadow", "soft_shadow"])),
        ("lights (glsl/lights.glsl)",
         load_library("lights").select(["light_directional", "light_point", "light_spot"])),
        ("shading (glsl/shading.glsl)", load_library("shading").select(shading)),
        ("normals, lights, materials and shading by run-time switches (glsl/uber.glsl)",
         uber.select(["estimate_normal", "pixel_color"], provided=set(SCENE_FUNCTIONS))),
        ("the pixel, from its camera ray (glsl/pipeline/trace.glsl)",
         fill_template("pipeline/trace.glsl", reflections=False, path_labels=True, mode="")),
        ("the entry point (glsl/main.frag)", fill_template(glsl.entry, path_labels=True,
                                                                    prepass=False,
                                                                    samples=False)),
    ]
    head = [glsl.prelude,
            _banner(f"parameters: {ROWS} rows whatever the scene; the first {HEADER_ROWS} (camera, "
                    "settings, normal stencil) are P, the tables are read from U")
            + glsl.declare_parameters(ROWS, HEADER_ROWS, MAX_FLAT_ROWS),
            block.defines(),
            _banner("codes of the run-time switches and the table layout") + layout,
            glsl.structs(path_labels=True)]
    body = [_banner(title) + text for title, text in parts]
    return glsl.finish("\n".join(head + body))


def _banner(title: str) -> str:
    return f"// ---- {title} " + "-" * max(4, 86 - len(title)) + "\n\n"


# --- timing: the specialised program against the uber program ----------------------------

def compare_specialised_uber(scene: Scene, width: int, height: int, repeat: int = 5) -> dict:
    """Time the specialised and the uber program on ``scene``, side by side on one context.

    Each program is compiled afresh (not taken from the gpu backend's cache), drawn once
    untimed but for its compile cost, then both are drawn ``repeat`` times, alternating
    (specialised first in even rounds, uber first in odd ones) so that a slow spell of a
    shared machine falls on both. A draw is timed from the draw call to ``ctx.finish()``:
    the fragment shader's work, without reading the buffers back.

    Returns
    -------
    dict
        ``specialised_ms``, ``uber_ms``: median draw time in ms; ``ratio``: uber_ms /
        specialised_ms (above 1: the specialised program is faster); ``*_compile_ms``: link
        time plus what the first draw took beyond a steady draw (a driver may compile the
        machine code at the first draw, as Mesa's llvmpipe does); ``*_link_ms``,
        ``*_first_draw_ms``, ``*_draws_ms`` (every timed draw), the image size, ``repeat``
        and ``device`` (the GL renderer).
    """
    if repeat < 1:
        raise MarchlabError(f"repeat must be at least 1 (got {repeat})")
    scene = rendered_scene(scene)               # bodies drawn as spheres, as marchlab.render does
    programs = {"specialised": generate(scene, width, height),
                "uber": uber_program(scene, width, height)}
    renderer = _renderer()
    with renderer.ctx:
        fbo = renderer.target(width, height)
        timers = {name: _DrawTimer(renderer.ctx, fbo, program, width, height)
                  for name, program in programs.items()}
        try:
            first = {name: timer.draw() for name, timer in timers.items()}
            draws = {name: [] for name in timers}
            for round_ in range(repeat):
                order = list(timers) if round_ % 2 == 0 else list(timers)[::-1]
                for name in order:
                    draws[name].append(timers[name].draw())
        finally:
            for timer in timers.values():
                timer.release()
    result = {"width": width, "height": height, "repeat": repeat,
              "device": renderer_name(renderer.ctx)}
    for name, timer in timers.items():
        median = statistics.median(draws[name])
        result[f"{name}_ms"] = median
        result[f"{name}_link_ms"] = timer.link_ms
        result[f"{name}_first_draw_ms"] = first[name]
        result[f"{name}_compile_ms"] = timer.link_ms + max(first[name] - median, 0.0)
        result[f"{name}_draws_ms"] = draws[name]
    result["ratio"] = result["uber_ms"] / result["specialised_ms"]
    return result


class _DrawTimer:
    """One program compiled afresh with its parameters uploaded, drawn into ``fbo`` on demand."""

    def __init__(self, ctx, fbo, program: Program, width: int, height: int):
        self.ctx, self.fbo, self.size = ctx, fbo, (width, height)
        vertex = program.vertex_source or glsl_file("fullscreen.vert")
        start = time.perf_counter()
        try:
            self.program = ctx.program(vertex_shader=vertex, fragment_shader=program.source)
        except Exception as err:
            raise ShaderCompileError(compile_message(str(err), program.source)) from None
        self.link_ms = 1e3 * (time.perf_counter() - start)
        self.vao = ctx.vertex_array(self.program, [])
        self.buffer = ctx.buffer(program.parameters.astype(np.float32).tobytes())

    def draw(self) -> float:
        """Draw the full-screen triangle once; the wall time in ms until the GPU is done."""
        self.buffer.bind_to_uniform_block(0)
        self.program["Parameters"].binding = 0
        self.fbo.use()
        self.fbo.viewport = (0, 0, *self.size)
        self.ctx.finish()
        start = time.perf_counter()
        self.vao.render(vertices=3)
        self.ctx.finish()
        return 1e3 * (time.perf_counter() - start)

    def release(self):
        for thing in (self.vao, self.buffer, self.program):
            thing.release()
