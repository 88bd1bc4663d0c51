{# A template: gpu_shader/generate.py fills in the {{ }} parts (Jinja). #}
{% from "pipeline/planes.glsl" import pixel_planes %}
// The compute shader's entry point: one invocation per pixel, GROUP_SIZE x GROUP_SIZE pixels
// a work group, the same pixel as glsl/main.frag. It stores the Frame's buffers into the
// same three textures (bound as images) that the fragment shader renders into.

layout(local_size_x = GROUP_SIZE, local_size_y = GROUP_SIZE) in;

layout(rgba32f, binding = 0) uniform writeonly image2D out_color;    // rgb colour, a hit
layout(rgba32f, binding = 1) uniform writeonly image2D out_normal;   // xyz normal, w depth
layout(rgba32i, binding = 2) uniform writeonly iimage2D out_steps;   // steps, id, path label
// The image's size, and the first row of this dispatch (a frame may be drawn in bands).
uniform ivec2 frame_size;
uniform int first_row;
{% if prepass %}
// The start of each tile's rays, stored by the pre-pass (glsl/prepass.comp): texel (i, j)
// holds tile column i, tile row j counted from the top, as the image's rows are.
uniform sampler2D cone_starts;
{% endif %}

void main()
{
    load_parameters();
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, first_row);
    if (pixel.x >= frame_size.x || pixel.y >= frame_size.y) {
        return;               // the last groups reach past the image's edges
    }
    // The pixel's centre, as gl_FragCoord gives it to the fragment shader (exact in float).
    real x = real(pixel.x) + 0.5;
    real y = real(pixel.y) + 0.5;
{% if prepass %}
    real start = texelFetch(cone_starts, pixel / int(PREPASS_TILE), 0).x;
{% else %}
    real start = 0.0;
{% endif %}
{{ pixel_planes(path_labels, samples) }}
    imageStore(out_color, pixel, color_hit);
    imageStore(out_normal, pixel, normal_depth);
    imageStore(out_steps, pixel, steps_id);
}
