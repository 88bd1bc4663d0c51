{# A template: gpu_shader/raster.py (lit_shaders) fills it in for one scene (Jinja). #}
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
{% else %}
uniform sampler2D visibility{{ light.index }};                 // a texture handed in for light {{ light.index }}
#define LIGHT{{ light.index }}_VISIBLE texelFetch(visibility{{ light.index }}, ivec2(gl_FragCoord.xy), 0).x
{% endif %}
{% endfor %}
{% endif %}
{% if mappings %}
{{ texel_reader | trim }}
{% endif %}

layout(location = 3) out vec4 out_color;       // rgb: linear colour, a: 1 (drawn)
{% for title, text in sections %}

{{ banner(title) }}
{{ text }}
{%- endfor %}

void main()
{
    write_planes();
    // Shade what the planes hold: the unit normal n and the distance t along the pixel's
    // unit ray d, whose point is p = eye + t d (reference_cpu/raster_shading.py).
    vec3 n = out_normal_depth.xyz;
    real t = out_normal_depth.w;
    vec3 d = camera_ray(gl_FragCoord.x, gl_FragCoord.y);
{% if model == "normals" %}
    out_color = vec4(shade_normals(n), 1.0);
{% else %}
    precise vec3 p = CAMERA_POSITION + t * d;
    out_color = vec4(shade_{{ model }}(p, n, -d, object_id), 1.0);
{% endif %}
}
