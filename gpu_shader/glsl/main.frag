{# A template: gpu_shader/generate.py fills in the {{ }} parts (Jinja). #}
{% from "pipeline/planes.glsl" import pixel_planes %}
// The fragment shader's entry point: one invocation per pixel. It writes every buffer of a
// marchlab Frame into three render targets in one draw: two RGBA32F, and one RGBA32I for the
// integers, which the Frame then uses as they are read back (no conversion per pixel).
// glsl/main.comp is the same pixel as a compute shader.

layout(location = 0) out vec4 out_color;     // rgb: colour in [0, 1], a: 1 on a hit
layout(location = 1) out vec4 out_normal;    // xyz: unit normal, w: depth t (inf on a miss)
layout(location = 2) out ivec4 out_steps;    // x: SDF evaluations, y: object id (-1),
                                             // z: path label (24 bits), 0 without labels
{% if prepass %}
// The start of each tile's rays, drawn by the pre-pass (glsl/prepass.frag): texel (i, j)
// holds tile column i, tile row j counted from the top, as the image's rows are.
uniform sampler2D cone_starts;
{% endif %}

void main()
{
    load_parameters();
    // gl_FragCoord is the pixel centre (column + 0.5, GL row + 0.5), exact in float. GL row r
    // holds marchlab's row r (counted from the top): the image is stored top row first, so
    // reading it back needs no flip.
    real x = gl_FragCoord.x;
    real y = gl_FragCoord.y;
{% if prepass %}
    real start = texelFetch(cone_starts, ivec2(gl_FragCoord.xy) / int(PREPASS_TILE), 0).x;
{% else %}
    real start = 0.0;
{% endif %}
{{ pixel_planes(path_labels, samples) }}
    out_color = color_hit;
    out_normal = normal_depth;
    out_steps = steps_id;
}
