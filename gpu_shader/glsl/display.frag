{# A template: gpu_shader/display.py fills in the {{ }} parts (Jinja) from Python constants. #}
#version 330 core
// The display pass: turns the three planes a generated program drew (gpu_shader/planes.py)
// into the 8-bit picture a person sees, the GLSL twin of scene_model.frame.Frame.image plus
// the object-id overlay and the selection outline of gpu_shader/display.py.
//
// The planes may be smaller than the viewport (the viewer renders at reduced resolution while
// the camera moves): each pixel shows the texel under its centre, fetched whole with
// texelFetch (an integer texture cannot be filtered, and an object id must not be blended).
//
// This one shows the "{{ overlay }}" overlay{{ " with the selection's outline" if outline else "" }}: a program is made per overlay and outline, with only
// that code in it. A software rasteriser such as llvmpipe runs every branch of a shader for
// every pixel (under a mask), so one program with all overlays behind a uniform switch costs
// the sum of them all: 10 to 15 ms a frame at 640x480, against about 1 ms for this.

const int HEAT_STOP_COUNT = {{ heat_stop_count }};
const int MAX_SELECTED = {{ max_selected }};

uniform sampler2D color_hit;       // plane 0: rgb colour, a: 1 on a hit
uniform sampler2D normal_depth;    // plane 1: xyz normal, w: depth t (inf on a miss)
uniform isampler2D steps_id;       // plane 2: x steps, y object id (-1 on a miss)

uniform ivec4 viewport;            // x, y, width, height of the drawing, in framebuffer pixels
uniform float gamma;
uniform float max_steps;
uniform vec2 depth_range;          // nearest and farthest hit depth (display.depth_range)
uniform float heat_stops[HEAT_STOP_COUNT];    // scene_model.colormaps.HEAT_STOPS
uniform vec3 heat_colors[HEAT_STOP_COUNT];    // scene_model.colormaps.HEAT_COLORS
uniform int selected[MAX_SELECTED];           // the selected object ids, then unused slots
uniform int selected_count;
uniform vec3 outline_color;

out vec4 picture;

// floor(n / d) for n >= 0, d > 0, exactly: a float quotient, then corrected by one where its
// rounding crossed an integer. (Integer division has no SIMD instruction, so a software
// rasteriser divides lane by lane; this stays in vector floats and integer products.)
ivec2 floor_divide(ivec2 n, ivec2 d)
{
    ivec2 q = ivec2(vec2(n) / vec2(d));
    q -= ivec2(greaterThan(q * d, n));
    q += ivec2(lessThanEqual((q + 1) * d, n));
    return q;
}

// The texel this pixel shows: the one whose area holds the pixel's centre,
// floor((column + 0.5) * W / w) across, in integers. Texel row r is image row r from the top
// while framebuffer rows count from the bottom, so the rows are turned over: the top of the
// image is drawn at the top of the viewport.
ivec2 source_texel()
{
    ivec2 size = textureSize(steps_id, 0);
    ivec2 local = ivec2(gl_FragCoord.xy) - viewport.xy;
    ivec2 pixel = ivec2(local.x, viewport.w - 1 - local.y);
    return floor_divide((2 * pixel + 1) * size, 2 * viewport.zw);
}

// scene_model.colormaps.heat: linear interpolation between the stops (numpy.interp).
vec3 heat(float x)
{
    x = clamp(x, 0.0, 1.0);
    for (int i = 0; i < HEAT_STOP_COUNT - 1; i++) {
        if (x <= heat_stops[i + 1]) {
            float f = (x - heat_stops[i]) / (heat_stops[i + 1] - heat_stops[i]);
            return mix(heat_colors[i], heat_colors[i + 1], f);
        }
    }
    return heat_colors[HEAT_STOP_COUNT - 1];
}

// display.id_colors: the "lowbias32" integer hash (Chris Wellons, "Prospecting for Hash
// Functions", 2018) spreads neighbouring ids far apart; its low three bytes, each mapped
// into 64..255 so that no object looks as black as a miss.
vec3 id_colors(int id)
{
    if (id < 0) {
        return vec3(0.0);
    }
    uint x = uint(id);
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    uvec3 bytes = uvec3(x, x >> 8, x >> 16) & 0xffu;
    return vec3(64u + ((bytes * 3u) >> 2)) / 255.0;
}

bool is_selected(int id)
{
    for (int i = 0; i < selected_count; i++) {
        if (selected[i] == id) {
            return true;
        }
    }
    return false;
}

int object_id(ivec2 texel)
{
    return texelFetch(steps_id, texel, 0).y;
}

// display.outline_mask: a texel that is not selected but has a selected 4-neighbour inside
// the image, so the outline lies just outside the selected objects' silhouettes.
bool outline_mask(ivec2 texel)
{
    if (selected_count == 0 || is_selected(object_id(texel))) {
        return false;
    }
    ivec2 size = textureSize(steps_id, 0);
    ivec2 neighbours[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    for (int i = 0; i < 4; i++) {
        ivec2 n = texel + neighbours[i];
        if (all(greaterThanEqual(n, ivec2(0))) && all(lessThan(n, size))
                && is_selected(object_id(n))) {
            return true;
        }
    }
    return false;
}

// scene_model.frame.to_uint8: round to the nearest of the 256 levels, as k / 255, which the
// 8-bit target stores exactly.
vec3 to_uint8(vec3 x)
{
    return floor(clamp(x, 0.0, 1.0) * 255.0 + 0.5) / 255.0;
}

// One pixel of scene_model.frame.Frame.image(overlay), or of the object-id overlay.
vec3 overlay_color(ivec2 texel)
{
{% if overlay == "color" %}
    return pow(texelFetch(color_hit, texel, 0).rgb, vec3(1.0 / gamma));
{% elif overlay == "depth" %}
    bool hit = texelFetch(color_hit, texel, 0).a > 0.5;
    float t = texelFetch(normal_depth, texel, 0).w;
    float near = depth_range.x, far = depth_range.y;
    return hit ? vec3(1.0 - (t - near) / max(far - near, 1e-12)) : vec3(0.0);
{% elif overlay == "normal" %}
    bool hit = texelFetch(color_hit, texel, 0).a > 0.5;
    return hit ? 0.5 + 0.5 * texelFetch(normal_depth, texel, 0).xyz : vec3(0.0);
{% elif overlay == "steps" %}
    return heat(float(texelFetch(steps_id, texel, 0).x) / max_steps);
{% else %}
    return id_colors(object_id(texel));
{% endif %}
}

void main()
{
    ivec2 texel = source_texel();
{% if outline %}
    vec3 rgb = outline_mask(texel) ? outline_color : overlay_color(texel);
{% else %}
    vec3 rgb = overlay_color(texel);
{% endif %}
    // Opaque, so the picture is the same whether or not the caller left blending on.
    picture = vec4(to_uint8(rgb), 1.0);
}
