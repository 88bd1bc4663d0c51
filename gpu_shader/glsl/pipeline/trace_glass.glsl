{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% from "pipeline/shaded.glsl" import shaded_hit %}
{% set label = ", label" if path_labels else "" %}
// A ray of the tree: where it starts and goes, what of its light reaches the pixel (the
// product of the weights along its branch), the absorption of the glass it travels in (0 in
// air) and its depth in the tree{{ "; its label is its branch's path label so far" if path_labels }}.
Ray make_ray(vec3 origin, vec3 direction, vec3 weight, vec3 absorption, int depth{{ ", real label" if path_labels }})
{
    Ray r;
    r.origin = origin;
    r.direction = direction;
    r.weight = weight;
    r.absorption = absorption;
    r.depth = depth;
{% if path_labels %}
    r.label = label;
{% endif %}
    return r;
}

// The largest channel of a weight.
real max3(vec3 v)
{
    return max(v.x, max(v.y, v.z));
}

// The absorption of the glass at p, or 0 in air or inside an opaque solid: a camera ray
// that starts inside glass fades until it leaves.
vec3 absorption_at(vec3 p)
{
    int id = scene_object_id(p);
    return scene_sdf(p) < 0.0 && MATERIAL(id, {{ glass_row }}).w > 0.0 ? MATERIAL(id, {{ glass_row }}).xyz : vec3(0.0);
}

// One pixel, from its camera ray to everything the Frame holds (reference_cpu/render.py,
// Tracer.trace and lit_color), with Whitted's ray tree: a hit adds its shaded colour times
// the ray's weight, then sends on a reflected ray (weight kr, plus transparency x F on glass)
// and on glass a refracted one (transparency x (1 - F)). The reference traces the tree a
// generation at a time; here it is walked depth first: the ray goes on reflected and the
// refracted one waits in `pending0` .. (at most one per level, so {{ depth }} of them). A ray
// deeper than REFLECTION_DEPTH, or whose weight is at most MIN_RAY_WEIGHT, is not traced. The
// camera ray starts at `start` (0, or its tile's cone distance: glsl/cone.glsl).
{% if path_labels %}
// The pixel's path label is the sum of the labels of its rays weighing more than
// LABEL_WEIGHT, which does not depend on the order the tree is walked in.
{% endif %}
Pixel trace(vec3 origin, vec3 direction, real start)
{
    Pixel px;
    px.normal = vec3(0.0);
    px.id = -1;
    vec3 color = vec3(0.0);
{% if path_labels %}
    uint path = 0u;
{% endif %}
    Ray ray = make_ray(origin, direction, vec3(1.0), absorption_at(origin), 0{{ ", 0.0" if path_labels }});
    real t0 = start;
{% for k in range(depth) %}
    Ray pending{{ k }};
{% endfor %}
    int pending = 0;
    for (int i = 0; i < TREE_RAYS; i++) {
        vec3 d = ray.direction;
        Hit h = march(ray.origin, d, t0, MAX_DISTANCE, 0u);
        if (i == 0) {
            px.primary = h;
        }
        t0 = 0.0;
        // What the glass the ray travelled in let through (a miss went MAX_DISTANCE).
        vec3 weight = ray.weight * beer_lambert(ray.absorption, h.hit == 1 ? h.t : MAX_DISTANCE);
        bool leaf = true;
        if (h.hit == 0) {
            color = color + weight * background(d);
{% if path_labels %}
            if (max3(weight) > LABEL_WEIGHT) {
                path = (path + path_step(uint(ray.label), -1, 0u)) & 0xFFFFFFu;
            }
{% endif %}
        } else {
            precise vec3 p = ray.origin + h.t * d;
            vec3 n = estimate_normal(p);
            int id = scene_object_id(p);
            if (i == 0) {
                px.normal = n;
                px.id = id;
            }
            bool entering = dot(d, n) < 0.0;
            vec4 glass = MATERIAL(id, {{ glass_row }});
            real tau = glass.w;
{% if path_labels %}
            uint features = 0u;
{% endif %}
            // Glass seen from inside adds no Phong term (the lights are outside).
            if (entering || tau == 0.0) {
                {{ shaded_hit(shade, fog, path_labels) | indent(16) | trim }}
{% if path_labels %}
                features = uint(lit.w);
{% endif %}
                color = color + weight * shaded;
            }
{% if path_labels %}
            real label = real(path_step(uint(ray.label), id, features));
            if (max3(weight) > LABEL_WEIGHT) {
                path = (path + uint(label)) & 0xFFFFFFu;
            }
{% endif %}
            // The children: reflected (kr, and tau F on glass), refracted (tau (1 - F)).
            vec3 n_facing = entering ? n : -n;
            real cos_i = -dot(d, n_facing);
            real reflected = MATERIAL(id, 1).w;
            real transmitted = 0.0;
            vec3 bent = vec3(0.0);
            bool total = false;
            if (tau > 0.0) {
                real ior = MATERIAL(id, {{ glass_row + 1 }}).x;
                real n1 = entering ? 1.0 : ior;
                real n2 = entering ? ior : 1.0;
                real eta = n1 / n2;
                real k = refract_k(cos_i, eta);
                total = k <= 0.0;
                real cos_t = sqrt(max(k, 0.0));
                bent = refract_direction(d, n_facing, cos_i, eta, cos_t);
                real f = total ? 1.0 : fresnel_{{ fresnel }}(cos_i, cos_t, n1, n2);
                reflected = reflected + tau * f;
                transmitted = tau * (1.0 - f);
            }
            vec3 w_reflected = weight * reflected;
            vec3 w_transmitted = weight * transmitted;
            bool deeper = ray.depth < REFLECTION_DEPTH;
            bool go_r = deeper && max3(w_reflected) > MIN_RAY_WEIGHT;
            bool go_t = deeper && !total && max3(w_transmitted) > MIN_RAY_WEIGHT;
            // The reflected ray starts just off the surface on the ray's side, the refracted
            // one just beyond it, in the solid it enters (or out of the one it leaves).
            Ray refracted = make_ray(p - SURFACE_OFFSET * n_facing, bent, w_transmitted, entering ? glass.xyz : vec3(0.0), ray.depth + 1{{ label }});
            if (go_r) {
                if (go_t) {
{% for k in range(depth) %}
                    if (pending == {{ k }}) {
                        pending{{ k }} = refracted;
                    }
{% endfor %}
                    pending = pending + 1;
                }
                ray = make_ray(p + SURFACE_OFFSET * n_facing, reflect(d, n_facing), w_reflected, ray.absorption, ray.depth + 1{{ label }});
                leaf = false;
            } else if (go_t) {
                ray = refracted;
                leaf = false;
            }
        }
        if (leaf) {
            // This branch is done: take up the last ray left waiting, if any.
            if (pending == 0) {
                break;
            }
            pending = pending - 1;
{% for k in range(depth) %}
            if (pending == {{ k }}) {
                ray = pending{{ k }};
            }
{% endfor %}
        }
    }
    px.color = color;
{% if path_labels %}
    px.path = real(path);
{% endif %}
    return px;
}
