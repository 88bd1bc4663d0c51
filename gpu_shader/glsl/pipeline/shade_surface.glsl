{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% macro shaded(color, features) -%}
{{ "vec4(%s, %s)" % (color, features) if path_labels else color }}
{%- endmacro %}
// The shading model of the object hit: its material's, or the render's
// (scene_model.scene.shading_modes, reference_cpu/render.py Tracer.shade), coded in x of
// its material's row {{ row }}: {% for m in models %}{{ m.code }} {{ m.name }}{{ ", " if not loop.last }}{% endfor %}.
// h is the march that hit: the depth and steps models show its t and its step count.
{{ "vec4" if path_labels else "vec3" }} shade_surface(vec3 p, vec3 n, vec3 v, int id, Hit h)
{
    real model = MATERIAL(id, {{ row }}).x;
{% for m in models %}
{% if m.name == "normals" %}
{% set call = shaded("shade_normals(n)", "0.0") %}
{% elif m.name == "depth" %}
{% set call = shaded("shade_depth(h.t, MAX_DISTANCE)", "0.0") %}
{% elif m.name == "steps" %}
{% set call = shaded("heat(real(h.steps) / real(MAX_STEPS))", "real(h.steps)") %}
{% else %}
{% set call = "shade_%s(p, n, v, id)" % m.name %}
{% endif %}
{% if loop.last %}
    return {{ call }};
{% else %}
    if (model == {{ m.code }}.0) {
        return {{ call }};
    }
{% endif %}
{% endfor %}
}
