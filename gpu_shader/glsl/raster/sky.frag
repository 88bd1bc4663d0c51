{# A template: gpu_shader/raster_shaders.py (lit_shaders) fills it in for one background (Jinja). #}
{% from "raster/view.glsl" import banner, camera %}
{{ prelude }}
// The raster pipeline's skybox: what a pixel that no triangle covers shows, the scene's
// {{ kind }} background looked up along the pixel's ray with the sphere tracer's own functions
// (glsl/pipeline/background.glsl), as reference_cpu/raster_shading.py's shade_raster does
// in NumPy. Alpha 0 marks the pixel as a miss (gpu_shader/raster_lit.py reads it back).

{{ camera() }}
{% if kind == "sky" %}
uniform vec3 background_bottom;
uniform vec3 background_top;
#define BACKGROUND_BOTTOM background_bottom
#define BACKGROUND_TOP background_top
{% else %}
// The environment's first image in the atlas (first row, width, height, wrap) and its look
// (intensity, cos and sin of its rotation).
uniform vec4 environment_texture;
uniform vec3 environment_look;
#define ENVIRONMENT_TEXTURE environment_texture
#define ENVIRONMENT_LOOK environment_look
{{ texel_reader | trim }}
{% endif %}

{% if mirrored %}
// The mirrored pass's background: what the reflected ray H d sees (reference_cpu/
// planar_reflection.py, reflect_through).
uniform mat4 mirror;
{% endif %}

layout(location = 0) out vec4 out_color;
{% for title, text in sections %}

{{ banner(title) }}
{{ text }}
{%- endfor %}

void main()
{
{% if mirrored %}
    out_color = vec4(background(mat3(mirror) * camera_ray(gl_FragCoord.x, gl_FragCoord.y)), 0.0);
{% else %}
    out_color = vec4(background(camera_ray(gl_FragCoord.x, gl_FragCoord.y)), 0.0);
{% endif %}
}
