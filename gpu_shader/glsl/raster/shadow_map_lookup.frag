{# A template: gpu_shader/raster_shadow_map.py fills it in (Jinja). #}
{% from "raster/view.glsl" import banner, camera %}
{{ prelude }}
// The shadow map's screen pass: the scene drawn again from the camera (glsl/raster/mesh.vert),
// and each pixel's surface point looked up in the light's map with a bias, a slope bias and
// percentage-closer filtering. reference_cpu/shadow_map.py's shadow_map_visibility does the
// same in NumPy, under the same names (map_coordinates, texel_width).

in vec3 v_normal;
in float v_z;

uniform float far;
uniform float half_height;
uniform vec2 size;              // W, H
{{ camera(declared=True) }}
// The light's view of the scene (glsl/raster/shadow_map_depth.vert's uniforms).
uniform vec3 light_eye;
uniform vec3 light_right;
uniform vec3 light_up;
uniform vec3 light_forward;
uniform vec2 light_center;
uniform float light_half;
uniform bool perspective;

uniform sampler2D shadow_map;   // S x S, red: the nearest depth (m), +inf where nothing is
// A cube map (a point or spot light among the objects): six 90-degree faces, face 0 in
// shadow_map, each looking along face_forward[k] (reference_cpu/shadow_map.py, cube_views).
uniform bool cube;
uniform sampler2D shadow_face1;
uniform sampler2D shadow_face2;
uniform sampler2D shadow_face3;
uniform sampler2D shadow_face4;
uniform sampler2D shadow_face5;
uniform vec3 face_right[6];
uniform vec3 face_up[6];
uniform vec3 face_forward[6];
uniform float map_size;         // S
uniform float bias;             // m
uniform float slope_bias;       // texels of depth slope
uniform float max_tilt;         // the slope bias's tan(theta) is clamped here
uniform int reach;              // pcf / 2: the filter covers (2 reach + 1)^2 texels

out float visibility;           // 1 lit, 0 shadowed, between with PCF

{{ banner("the camera (glsl/camera.glsl)") }}
{{ camera_ray }}
{{ banner("the light's map") }}
// Where a point falls in the map looking along forward: x, y in texels from its top-left
// corner, and its depth along that axis (m). As glsl/raster/shadow_map_depth.vert projects
// a vertex.
vec3 map_coordinates(vec3 p, vec3 right, vec3 up, vec3 forward)
{
    vec3 offset = p - light_eye;
    vec3 view = vec3(dot(offset, right), dot(offset, up), dot(offset, forward));
    float w = perspective ? view.z : 1.0;
    float x = ((view.x - light_center.x) / (light_half * w) + 1.0) * map_size / 2.0;
    float y = (1.0 - (view.y - light_center.y) / (light_half * w)) * map_size / 2.0;
    return vec3(x, y, view.z);
}

// The cube map face a point falls in: its largest coordinate axis k of p - light_eye, face
// 2 k where that coordinate is positive, 2 k + 1 where negative; on a tie the first axis
// wins, as numpy's argmax in reference_cpu/shadow_map.py's cube_face.
int cube_face(vec3 p)
{
    vec3 offset = p - light_eye;
    vec3 a = abs(offset);
    int axis = (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
    return 2 * axis + (offset[axis] < 0.0 ? 1 : 0);
}

// The depth a map holds at a texel: the one map's, or a cube face's (GLSL 3.30 indexes an
// array of samplers only by a constant, so each face is named).
float stored_depth(int face, ivec2 at)
{
    if (face == 1) return texelFetch(shadow_face1, at, 0).r;
    if (face == 2) return texelFetch(shadow_face2, at, 0).r;
    if (face == 3) return texelFetch(shadow_face3, at, 0).r;
    if (face == 4) return texelFetch(shadow_face4, at, 0).r;
    if (face == 5) return texelFetch(shadow_face5, at, 0).r;
    return texelFetch(shadow_map, at, 0).r;
}

// The side (m) of one texel at a depth along the light's axis: the frustum's width there
// over S, or the orthographic map's side over S.
float texel_width(float depth)
{
    return 2.0 * light_half * (perspective ? depth : 1.0) / map_size;
}

void main()
{
    // The surface point as the lit pipeline finds it: the distance t along the pixel's
    // unit ray that glsl/raster/mesh.frag writes, then p = eye + t d.
    float sx = (2.0 * gl_FragCoord.x / size.x - 1.0) * half_width;
    float sy = (1.0 - 2.0 * gl_FragCoord.y / size.y) * half_height;
    float t = v_z * sqrt(1.0 + sx * sx + sy * sy);
    precise vec3 p = CAMERA_POSITION + t * camera_ray(gl_FragCoord.x, gl_FragCoord.y);
    vec3 n = normalize(v_normal);

    // The slope bias: a surface at angle theta to the light gains texel x tan(theta) of
    // depth across one texel (glPolygonOffset's factor; Williams 1978 needs a bias at all).
    vec3 to_light = perspective ? normalize(light_eye - p) : -light_forward;
    float cosine = clamp(abs(dot(n, to_light)), 1e-12, 1.0);
    float tilt = min(sqrt(1.0 - cosine * cosine) / cosine, max_tilt);
    int face = cube ? cube_face(p) : 0;
    vec3 where = cube ? map_coordinates(p, face_right[face], face_up[face], face_forward[face])
                      : map_coordinates(p, light_right, light_up, light_forward);
    float allowed = bias + slope_bias * texel_width(where.z) * tilt;

    // Percentage-closer filtering (Reeves, Salesin and Cook 1987): the share of the
    // (2 reach + 1)^2 texels round the point's own that it is no deeper than (in a cube,
    // clamped at the edge of the point's face).
    ivec2 texel = ivec2(floor(where.xy));
    int last = int(map_size) - 1;
    float lit = 0.0;
    for (int dy = -reach; dy <= reach; dy++) {
        for (int dx = -reach; dx <= reach; dx++) {
            ivec2 at = clamp(texel + ivec2(dx, dy), ivec2(0), ivec2(last));
            float stored = stored_depth(face, at);
            lit += where.z <= stored + allowed ? 1.0 : 0.0;
        }
    }
    visibility = lit / float((2 * reach + 1) * (2 * reach + 1));
    gl_FragDepth = v_z / far;               // the depth test on view depth, as mesh.frag's
}
