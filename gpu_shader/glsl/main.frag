// The fragment shader's entry point: one invocation per pixel. It writes every buffer of a
// marchlab Frame into three render targets in one draw: two RGBA32F, and one RGBA32I for the
// integers, which the Frame then uses as they are read back (no conversion per pixel).

layout(location = 0) out vec4 out_color;     // rgb: colour in [0, 1], a: 1 on a hit
layout(location = 1) out vec4 out_normal;    // xyz: unit normal, w: depth t (inf on a miss)
layout(location = 2) out ivec4 out_steps;    // x: SDF evaluations, y: object id (-1),
                                             // z: path label (24 bits, exact in a float)

void main()
{
    load_parameters();
    // gl_FragCoord is the pixel centre (column + 0.5, GL row + 0.5), exact in float. GL row r
    // holds marchlab's row r (counted from the top): the image is stored top row first, so
    // reading it back needs no flip.
    real x = gl_FragCoord.x;
    real y = gl_FragCoord.y;
    vec3 direction = camera_ray(x, y);
    Hit h = march(CAMERA_POSITION, direction, MAX_DISTANCE);

    vec3 n = vec3(0.0);
    int id = -1;
    if (h.hit == 1) {
        precise vec3 p = CAMERA_POSITION + h.t * direction;
        n = estimate_normal(p);
        id = scene_object_id(p);
    }
    vec4 color_path = pixel_color(CAMERA_POSITION, direction, h, n, id);

    out_color = vec4(clamp(color_path.xyz, 0.0, 1.0), float(h.hit));
    out_normal = vec4(n, h.hit == 1 ? h.t : INFINITY);
    out_steps = ivec4(h.steps, id, int(color_path.w), 0);
}
