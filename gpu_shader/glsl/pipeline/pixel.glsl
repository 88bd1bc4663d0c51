{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% from "pipeline/shaded.glsl" import shaded_hit %}
{% macro pixel(color, path) -%}
{{ "vec4(%s, real(%s))" % (color, path) if path_labels else color }}
{%- endmacro %}
// The colour{{ " and path label" if path_labels }} of one pixel, given its primary ray, the march result h
// and, on a hit, the normal n and object id there (reference_cpu/render.py, Tracer.trace).
{{ "vec4" if path_labels else "vec3" }} pixel_color(vec3 origin, vec3 direction, Hit h, vec3 n, int id)
{
{% if mode == "steps" %}
    return {{ pixel("heat(real(h.steps) / real(MAX_STEPS))", "path_step(uint(h.steps), id, 0u)") }};
{% elif mode == "normals" %}
    return {{ pixel("h.hit == 1 ? shade_normals(n) : background(direction)", "path_step(0u, id, 0u)") }};
{% elif mode == "depth" %}
    return {{ pixel("h.hit == 1 ? shade_depth(h.t, MAX_DISTANCE) : background(direction)", "path_step(0u, id, 0u)") }};
{% else %}
    if (h.hit == 0) {
        return {{ pixel("background(direction)", "path_step(0u, -1, 0u)") }};
    }
    vec3 d = direction;
    precise vec3 p = origin + h.t * d;
    {{ shaded_hit(shade, fog, path_labels) | indent(4) | trim }}
    return {{ pixel("shaded", "path_step(0u, id, uint(lit.w))") }};
{% endif %}
}
