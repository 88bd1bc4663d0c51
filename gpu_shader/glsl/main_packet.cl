{# A template: gpu_shader/packets.py fills in the {{ }} parts (Jinja). #}
// The packet kernel's entry point: one work-item per LANES neighbouring pixels of a row, the
// twin of main.cl, calling the packet forms of its functions (gpu_shader/vectorise.py). It
// writes the same three planes of 4 values per pixel (see main.cl), so the Frame is built
// the same way (gpu_shader/planes.py).
//
// The calls below are written as in GLSL; generating the program passes the parameter buffer
// P on as their first argument (thread_parameters in gpu_shader/dialects.py).

{% if prepass %}
// The cone pre-pass, run first: one work-item per LANES neighbouring tiles of a row of
// tiles, lane k the tile (first + k, row), writing where their pixels' rays start (see
// main.cl). Lanes past the last column of tiles are left out of tile_start's mask `live`.
__kernel void cone_prepass(PARAMETERS, __global real* restrict cone_starts)
{
    int first = get_global_id(0) * LANES;
    int row = get_global_id(1);
    int columns = ((int)(IMAGE_WIDTH) + (int)(PREPASS_TILE) - 1) / (int)(PREPASS_TILE);
    int rows = ((int)(IMAGE_HEIGHT) + (int)(PREPASS_TILE) - 1) / (int)(PREPASS_TILE);
    if (first >= columns || row >= rows) {
        return;
    }
    ipacket tiles = first + LANE_INDEX;
    packet start = tile_start(convert_packet(tiles), (packet)((real)(row)), tiles < columns);
    int lanes = min(LANES, columns - first);
    for (int k = 0; k < lanes; k++) {
        cone_starts[row * columns + first + k] = start[k];
    }
}

{% endif %}
__kernel void render(PARAMETERS,
                     __global float4* restrict color_hit,
                     __global vec4* restrict normal_depth,
                     __global int4* restrict steps_id{{ ",\n                     __global const real* restrict cone_starts" if prepass }})
{
    // Work-item (i, row) holds the pixels first .. first + LANES - 1 of its row, lane k the
    // pixel whose centre is (first + k + 0.5, row + 0.5). Lanes past the image's right edge
    // (when LANES does not divide the width) are left out of trace's mask `live`: traced
    // nowhere and written nowhere.
    int first = get_global_id(0) * LANES;
    int row = get_global_id(1);
    if (first >= (int)(IMAGE_WIDTH) || row >= (int)(IMAGE_HEIGHT)) {
        return;
    }
    ipacket column = first + LANE_INDEX;
    ipacket inside = column < (int)(IMAGE_WIDTH);
    packet x = convert_packet(column) + 0.5;
    packet y = (real)(row) + 0.5;
{% if not samples %}
    vec3p direction = camera_ray(x, y);
{% endif %}
{% if prepass %}
    int tile = (int)(PREPASS_TILE);
    int columns = ((int)(IMAGE_WIDTH) + tile - 1) / tile;
    packet start;
    for (int k = 0; k < LANES; k++) {
        start[k] = cone_starts[(row / tile) * columns + min(first + k, (int)(IMAGE_WIDTH) - 1) / tile];
    }
{% else %}
    packet start = 0.0;
{% endif %}
{% if samples %}
    Pixel px = supersample(x, y, start, inside);      // every ray of the pixel (anti-aliasing)
{% else %}
    Pixel px = trace(splat3(CAMERA_POSITION), direction, start, inside);
{% endif %}

    Hit h = px.primary;
    vec3p color = clamp(px.color, 0.0, 1.0);
    packet depth = h.hit == 1 ? h.t : (packet)(INFINITY);
    ipacket path = {{ "convert_ipacket(px.path)" if path_labels else "0" }};
    int lanes = min(LANES, (int)(IMAGE_WIDTH) - first);
    for (int k = 0; k < lanes; k++) {       // the planes' types: main.cl
        int pixel = row * (int)(IMAGE_WIDTH) + first + k;
        color_hit[pixel] = (float4)((float)(color.x[k]), (float)(color.y[k]), (float)(color.z[k]),
                                    (float)(h.hit[k]));
        normal_depth[pixel] = vec4(px.normal.x[k], px.normal.y[k], px.normal.z[k], depth[k]);
        steps_id[pixel] = (int4)((int)(h.steps[k]), (int)(px.id[k]), (int)(path[k]), 0);
    }
}
