{# A Jinja macro the sphere tracer's materials (pipeline/materials.glsl) and the raster #}
{# pipeline's (raster/albedo.glsl) share: imported, never filled in alone. `calls` maps each #}
{# texture mapping to its lookup, with %(T)d, %(T1)d and %(T2)d for the texture's rows. #}
{% macro surface_albedo(checker, texture_row, mappings, calls) %}
vec3 surface_albedo(vec3 p, vec3 n, int id)
{
{% if checker %}
    if (MATERIAL(id, 3).w > 0.0) {
        return checker(p, MATERIAL(id, 2).xyz, MATERIAL(id, 3).xyz, MATERIAL(id, 2).w);
    }
{% endif %}
{% if texture_row is not none %}
{% set rows = {"T": texture_row, "T1": texture_row + 1, "T2": texture_row + 2} %}
    real mapping = MATERIAL(id, {{ texture_row + 2 }}).x;
{% for name, code in mappings.items() %}
    if (mapping == {{ "%d.0" % code }}) {
        return MATERIAL(id, {{ texture_row + 1 }}).xyz * {{ calls[name] % rows }};
    }
{% endfor %}
{% endif %}
    return MATERIAL(id, 0).xyz;
}
{% endmacro %}
