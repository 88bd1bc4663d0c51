{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% from "pipeline/shaded.glsl" import shaded_hit %}
{% if not reflections %}
// One pixel, from its camera ray to everything the Frame holds (reference_cpu/render.py,
// Tracer.trace): the primary ray's march and, on a hit, the normal and object id there;
// then its colour{{ " and path label" if path_labels }} from pixel_color. The camera ray starts at `start`
// (0, or its tile's cone distance: glsl/cone.glsl).
Pixel trace(vec3 origin, vec3 direction, real start)
{
    Pixel px;
    px.primary = march(origin, direction, start, MAX_DISTANCE, 0u);
    px.normal = vec3(0.0);
    px.id = -1;
    if (px.primary.hit == 1) {
        precise vec3 p = origin + px.primary.t * direction;
        px.normal = estimate_normal(p);
        px.id = scene_object_id(p);
    }
{% if path_labels %}
    vec4 color_path = pixel_color(origin, direction, px.primary, px.normal, px.id);
    px.color = color_path.xyz;
    px.path = color_path.w;
{% else %}
    px.color = pixel_color(origin, direction, px.primary, px.normal, px.id);
{% endif %}
    return px;
}
{% else %}
// One pixel, from its camera ray to everything the Frame holds (reference_cpu/render.py,
// Tracer.trace and lit_color), with Whitted's mirror reflections. Each bounce marches its
// ray, shades the hit and adds the colour weighted by the product of the kr seen so far; a
// ray that hits nothing adds the background; a weight of at most MIN_RAY_WEIGHT ends the
// chain (reference_cpu/refraction.py). Bounce 0 is the camera ray: its march, normal
// and object id are the pixel's primary buffers. (The reference marches the camera ray
// first, then loops; here the loop does it, so that llvmpipe, which runs every statement of
// a loop body for a whole block of pixels, never runs a march or a normal twice.) The camera
// ray starts at `start` (0, or its tile's cone distance: glsl/cone.glsl), a mirror ray at 0.
Pixel trace(vec3 origin, vec3 direction, real start)
{
    Pixel px;
    px.normal = vec3(0.0);
    px.id = -1;
    vec3 color = vec3(0.0);
{% if path_labels %}
    uint path = 0u;
    uint label = 0u;
{% endif %}
    real weight = 1.0;
    vec3 o = origin;
    vec3 d = direction;
    real t0 = start;
    for (int bounce = 0; bounce <= REFLECTION_DEPTH; bounce++) {
        Hit h = march(o, d, t0, MAX_DISTANCE, 0u);
        if (bounce == 0) {
            px.primary = h;
        }
        if (h.hit == 0) {
            color = color + weight * background(d);
{% if path_labels %}
            label = path_step(label, -1, 0u);
            if (weight > LABEL_WEIGHT) {
                path = (path + label) & 0xFFFFFFu;
            }
{% endif %}
            break;
        }
        precise vec3 p = o + h.t * d;
        vec3 n = estimate_normal(p);
        int id = scene_object_id(p);
        if (bounce == 0) {
            px.normal = n;
            px.id = id;
        }
        {{ shaded_hit(shade, fog, path_labels) | indent(8) | trim }}
        color = color + weight * shaded;
{% if path_labels %}
        label = path_step(label, id, uint(lit.w));
        if (weight > LABEL_WEIGHT) {
            path = (path + label) & 0xFFFFFFu;
        }
{% endif %}
        weight = weight * MATERIAL(id, 1).w;
        if (bounce == REFLECTION_DEPTH || !(weight > MIN_RAY_WEIGHT)) {
            break;
        }
        // Continue just off the mirror on the ray's side, in the mirrored direction.
        vec3 n_facing = dot(d, n) < 0.0 ? n : -n;
        o = p + SURFACE_OFFSET * n_facing;
        d = reflect(d, n_facing);
        t0 = 0.0;
    }
    px.color = color;
{% if path_labels %}
    px.path = real(path);
{% endif %}
    return px;
}
{% endif %}
