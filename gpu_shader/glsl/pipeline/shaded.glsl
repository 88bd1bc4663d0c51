{# Macros the pipeline templates share (Jinja): imported, never filled in on their own. #}
{# The colour of a hit by `shade` (with path labels a vec4 `lit` holds its features too), then fog. #}
{% macro shaded_hit(shade, fog, path_labels) %}
{% if path_labels %}
vec4 lit = {{ shade }};
vec3 shaded = lit.xyz;
{% else %}
vec3 shaded = {{ shade }};
{% endif %}
{% if fog %}
shaded = apply_fog(shaded, h.t, FOG_COLOR, FOG_DENSITY);
{% endif %}
{% endmacro %}
