{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% if kind in ("solid", "sky") %}
// What a ray that hits nothing sees: the scene's {{ kind }} background (glsl/shading.glsl).
{% else %}
// What a ray that hits nothing sees: the scene's {{ kind }} environment, a {{ "cube map" if sampler == "cubemap" else "panorama" }}
// (glsl/environment.glsl).
{% endif %}
vec3 background(vec3 direction)
{
{% if kind == "solid" %}
    return background_solid(direction, BACKGROUND_COLOR);
{% elif kind == "sky" %}
    return background_sky(direction, BACKGROUND_BOTTOM, BACKGROUND_TOP);
{% else %}
    return background_{{ sampler }}(direction, ENVIRONMENT_TEXTURE, ENVIRONMENT_LOOK);
{% endif %}
}
