{# A template: gpu_shader/generate.py fills in the {{ }} parts (Jinja). #}
// The OpenCL kernel's entry point: one work-item per pixel, the twin of main.frag. It writes
// the same three planes of 4 values per pixel that the GLSL shader writes into its render
// targets, so both backends build their Frame the same way (gpu_shader/planes.py).
//
//   color_hit:    rgb colour in [0, 1], 1 on a hit                  (float32: Frame.color's)
//   normal_depth: unit normal, depth t (inf on a miss)               (in the precision)
//   steps_id:     SDF evaluations, object id (-1 on a miss), path label (24 bits; 0 without)
//                                                                    (int32)
// Only the middle plane needs float64 in a float64 program: the colour is kept as float32 and
// the counts are integers, so the other two are written as such, a third less to copy back.
//
// The calls below are written as in GLSL; generating the program passes the parameter buffer
// P on as their first argument (thread_parameters in gpu_shader/dialects.py).

{% if prepass %}
// The cone pre-pass, run first: one work-item per tile of PREPASS_TILE x PREPASS_TILE pixels
// (column, row of tiles, row 0 at the top), writing where its pixels' rays start.
__kernel void cone_prepass(PARAMETERS, __global real* restrict cone_starts)
{
    int column = get_global_id(0);
    int row = get_global_id(1);
    int columns = ((int)(IMAGE_WIDTH) + (int)(PREPASS_TILE) - 1) / (int)(PREPASS_TILE);
    int rows = ((int)(IMAGE_HEIGHT) + (int)(PREPASS_TILE) - 1) / (int)(PREPASS_TILE);
    if (column >= columns || row >= rows) {
        return;
    }
    cone_starts[row * columns + column] = tile_start((real)(column), (real)(row));
}

{% endif %}
__kernel void render(PARAMETERS,
                     __global float4* restrict color_hit,
                     __global vec4* restrict normal_depth,
                     __global int4* restrict steps_id{{ ",\n                     __global const real* restrict cone_starts" if prepass }})
{
    // Work-item (column, row) is the pixel whose centre is (column + 0.5, row + 0.5), row 0
    // at the top, as in the reference. The launch may be padded to whole work-groups.
    int column = get_global_id(0);
    int row = get_global_id(1);
    if (column >= (int)(IMAGE_WIDTH) || row >= (int)(IMAGE_HEIGHT)) {
        return;
    }
    real x = (real)(column) + 0.5;
    real y = (real)(row) + 0.5;
{% if not samples %}
    vec3 direction = camera_ray(x, y);
{% endif %}
{% if prepass %}
    int tile = (int)(PREPASS_TILE);
    int columns = ((int)(IMAGE_WIDTH) + tile - 1) / tile;
    real start = cone_starts[(row / tile) * columns + column / tile];
{% else %}
    real start = 0.0;
{% endif %}
{% if samples %}
    Pixel px = supersample(x, y, start);      // every ray of the pixel (anti-aliasing)
{% else %}
    Pixel px = trace(CAMERA_POSITION, direction, start);
{% endif %}

    Hit h = px.primary;
    int pixel = row * (int)(IMAGE_WIDTH) + column;
    color_hit[pixel] = (float4)(convert_float3(clamp(px.color, 0.0, 1.0)), (float)(h.hit));
    normal_depth[pixel] = vec4(px.normal, h.hit == 1 ? h.t : INFINITY);
    steps_id[pixel] = (int4)(h.steps, px.id, {{ "(int)(px.path)" if path_labels else "0" }}, 0);
}
