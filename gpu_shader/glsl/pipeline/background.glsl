{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
// What a ray that hits nothing sees: the scene's {{ kind }} background (glsl/shading.glsl).
vec3 background(vec3 direction)
{
{% if kind == "solid" %}
    return background_solid(direction, BACKGROUND_COLOR);
{% else %}
    return background_sky(direction, BACKGROUND_BOTTOM, BACKGROUND_TOP);
{% endif %}
}
