{# A template: gpu_shader/raster_shaders.py (lit_shaders) fills it in for one scene (Jinja). #}
{% from "raster/view.glsl" import banner, camera %}
{{ prelude }}
// The raster pipeline's lit fragment shader, generated for one scene: the planes of the
// unlit pipeline (glsl/raster/mesh.frag, its main renamed write_planes), then the pixel's
// colour by the sphere tracer's own lights and shading functions, as
// reference_cpu/raster_shading.py's shade_raster computes it in NumPy. It holds only what
// the scene uses:
//   - the {{ model }} model
{% if lights %}
//   - {{ lights | length }} light{{ "s" if lights | length > 1 }}: {{ lights | map(attribute="kind") | join(", ") }}
{% endif %}
{% if checker %}
//   - checkerboards
{% endif %}
{% for mapping in mappings %}
//   - {{ mapping }} textures
{% endfor %}
{% if planes_read %}
//   - the visibility planes of {{ planes_read }} light{{ "s" if planes_read > 1 }}
{% endif %}
{% if fog %}
//   - fog
{% endif %}
{% if variant == "mirror" %}
//   - the mirrored pass: what a flat mirror shows (gpu_shader/raster_render.py)
{% elif variant in ("peel", "sorted") %}
//   - a transparent layer ({{ "depth peeling" if variant == "peel" else "sorted blending" }}; gpu_shader/raster_render.py)
{% endif %}

{{ structs }}
{{ banner("the planes (glsl/raster/mesh.frag)") }}
{{ planes }}
{{ camera(declared=True) }}
// The render's settings, set per frame.
uniform vec3 ambient;
uniform float toon_bands;
#define AMBIENT ambient
#define TOON_BANDS toon_bands
#define MAX_DISTANCE far         // the distance a directional light is taken to be at
{% if model != "normals" %}

// The material of the object drawn, set before its draw: {{ stride }} rows, laid out as the
// sphere tracer's (glsl/pipeline/materials.glsl). The id is the drawn object's.
uniform vec4 material[{{ stride }}];
#define MATERIAL(id, row) material[row]
{% endif %}
{% if lights %}

// The lights, one array element each, set per frame, under the names that
// glsl/pipeline/shade.glsl reads.
{% for name, type in light_arrays %}
uniform {{ type }} light_{{ name | lower }}[{{ lights | length }}];
{% endfor %}
{% for light in lights %}
{% for name in light.names %}
{% if name in ("RADIANCE", "SPECULAR") and light.visibility %}
#define LIGHT{{ light.index }}_{{ name }} (LIGHT{{ light.index }}_VISIBLE * light_{{ name | lower }}[{{ light.index }}])
{% else %}
#define LIGHT{{ light.index }}_{{ name }} light_{{ name | lower }}[{{ light.index }}]
{% endif %}
{% endfor %}
{% endfor %}
{% endif %}
{% if planes_read %}

// How much of a light reaches the surface drawn at this pixel, 0 to 1: its visibility plane
// at the pixel. It scales the light's diffuse and specular radiance, not its ambient light
// (reference_cpu/raster_shading.py, shade_raster).
{% if array_planes %}
uniform sampler2DArray visibility_planes;      // the planes handed in as arrays, one layer each
{% endif %}
{% for light in lights if light.visibility %}
{% if light.visibility == "layer" %}
#define LIGHT{{ light.index }}_VISIBLE texelFetch(visibility_planes, ivec3(gl_FragCoord.xy, {{ light.layer }}), 0).x
{% elif light.visibility == "count" %}
uniform sampler2D visibility{{ light.index }};                 // light {{ light.index }}'s shadow-volume count: lit where 0
#define LIGHT{{ light.index }}_VISIBLE (texelFetch(visibility{{ light.index }}, ivec2(gl_FragCoord.xy), 0).x == 0.0 ? 1.0 : 0.0)
{% else %}
uniform sampler2D visibility{{ light.index }};                 // a texture handed in for light {{ light.index }}
#define LIGHT{{ light.index }}_VISIBLE texelFetch(visibility{{ light.index }}, ivec2(gl_FragCoord.xy), 0).x
{% endif %}
{% endfor %}
{% endif %}
{% if model == "depth" %}

uniform float depth_range;                     // render.max_distance: black from there on
{% endif %}
{% if fog %}

// Exponential fog of the first hit (reference_cpu/raster_render.py, picture).
uniform vec3 fog_color;
uniform float fog_density;
{% endif %}
{% if variant == "mirror" %}

// The mirrored pass (reference_cpu/planar_reflection.py, reflect_through): the scene was
// mirrored by M in the vertex shader (glsl/raster/mirror.vert); a fragment is shaded at its
// real point M (eye + t d) = M eye + t H d, seen along the reflected ray H d, and only on the
// pixels where the mirror itself was drawn (its object id in the opaque pass: the stencil).
uniform mat4 mirror;                           // M; mat3(mirror) is H
uniform isampler2D mask_ids;                   // the opaque pass's ids plane
uniform int mask_id;                           // the mirror's object
{% elif variant in ("peel", "sorted") %}

// A transparent layer (reference_cpu/transparency.py): only fragments in front of the opaque
// surface drawn count{% if variant == "peel" %}, and of those only the ones farther than the layer
// the previous pass peeled (Everitt 2001); the depth test keeps the nearest of them{% endif %}.
uniform sampler2D opaque_planes;               // the opaque pass's normal and depth (w: t)
uniform sampler2D opaque_color;                // ... and its colour (a: 1 where drawn)
{% if variant == "peel" %}
uniform sampler2D previous_layer;              // the previous pass's planes (w: t; -1 at first)
{% endif %}
{% endif %}
{% if prepass %}

// The scene's depth drawn before this pass (by the shadow volumes' pass,
// gpu_shader/raster_shadows.py), z / (z + 1 m) as this pass's: a fragment well behind it
// loses the depth test anyway, so it is dropped before its shading, and the heavy part of
// this shader runs about once per pixel. The margin keeps every fragment that might win.
uniform sampler2D scene_depth;
{% endif %}
{% if mappings %}
{{ texel_reader | trim }}
{% endif %}

{% if variant in ("peel", "sorted") %}
layout(location = 3) out vec4 out_color;       // rgb: linear colour, a: the opacity 1 - transparency
{% else %}
layout(location = 3) out vec4 out_color;       // rgb: linear colour, a: 1 (drawn)
{% endif %}
{% for title, text in sections %}

{{ banner(title) }}
{{ text }}
{%- endfor %}

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
{% if prepass %}
    if (v_z / (v_z + 1.0) > texelFetch(scene_depth, pixel, 0).r * (1.0 + 1e-5)) {
        discard;                               // hidden: another surface lies in front
    }
{% endif %}
{% if variant == "mirror" %}
    if (texelFetch(mask_ids, pixel, 0).x != mask_id) {
        discard;                               // not the mirror's pixel: nothing to show
    }
{% endif %}
    write_planes();
    // Shade what the planes hold: the unit normal n and the distance t along the pixel's
    // unit ray d, whose point is p = eye + t d (reference_cpu/raster_shading.py).
    vec3 n = out_normal_depth.xyz;
    real t = out_normal_depth.w;
{% if variant in ("peel", "sorted") %}
    if (texelFetch(opaque_color, pixel, 0).a > 0.0 && t >= texelFetch(opaque_planes, pixel, 0).w) {
        discard;                               // behind the opaque surface
    }
{% if variant == "peel" %}
    if (t <= texelFetch(previous_layer, pixel, 0).w) {
        discard;                               // peeled already (or nearer than that)
    }
{% endif %}
{% endif %}
{% if variant == "mirror" %}
    vec3 d = mat3(mirror) * camera_ray(gl_FragCoord.x, gl_FragCoord.y);
    precise vec3 p = (mirror * vec4(CAMERA_POSITION, 1.0)).xyz + t * d;
{% else %}
    vec3 d = camera_ray(gl_FragCoord.x, gl_FragCoord.y);
{% endif %}
{% if model == "normals" %}
    out_color = vec4(shade_normals(n), 1.0);
{% elif model == "depth" %}
    out_color = vec4(shade_depth(t, depth_range), 1.0);
{% else %}
{% if variant != "mirror" %}
    precise vec3 p = CAMERA_POSITION + t * d;
{% endif %}
    vec3 color = shade_{{ model }}(p, n, -d, object_id);
{% if fog %}
    color = apply_fog(color, t, fog_color, fog_density);
{% endif %}
{% if variant in ("peel", "sorted") %}
    out_color = vec4(color, MATERIAL(object_id, 1).w);
{% else %}
    out_color = vec4(color, 1.0);
{% endif %}
{% endif %}
}
