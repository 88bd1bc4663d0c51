{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% macro sample(light) -%}
{% set L = "LIGHT%d_" % light.index -%}
{# A light with its own colours is sampled in white: what it gives is its fall-off. #}
{% set R = "vec3(1.0)" if light.own else L + "RADIANCE" -%}
{% if light.kind == "directional" -%}
light_directional({{ L }}TO_LIGHT, {{ R }})
{%- elif light.kind == "point" -%}
light_point(p, {{ L }}POSITION, {{ R }}, {{ L }}ATTENUATION)
{%- else -%}
light_spot(p, {{ L }}POSITION, {{ R }}, {{ L }}ATTENUATION, {{ L }}AXIS, {{ L }}CONE)
{%- endif %}
{%- endmacro %}
{% set specular = "specular_blinn_phong" if model == "blinn_phong" else "specular_phong" %}
{% set band = {"toon": "toon_band", "stripes": "stripes_band"}.get(model) %}
{# A hard shadow ray leaves out the convex object it starts on (own_object; render.shadow_skip_own). #}
{% set own = ", own_object(id)" if skip_own | default(false) else (", 0u" if shadows == "hard" else "") %}
{% set D = "%s(diffuse(n, s.to_light), TOON_BANDS)" % band if band else "diffuse(n, s.to_light)" %}
{% set S = "%s(%s(n, s.to_light, v, shininess), TOON_BANDS)" % (band, specular) if band else "%s(n, s.to_light, v, shininess)" % specular %}
{% if helpers and shadows != "none" and lights %}
// Whether light s needs a shadow ray at p: points facing away from the light, or where it
// sends nothing, need none, as their diffuse and specular terms are zero whatever the
// visibility (taken as 1).
bool needs_shadow_ray(vec3 n, LightSample s)
{
    return dot(n, s.to_light) > 0.0 && max(s.radiance.x, max(s.radiance.y, s.radiance.z)) > 0.0;
}
{% if paired < lights | length %}

// How much of light s reaches p on object id. Shadow rays start SURFACE_OFFSET off the
// surface (else they find the surface itself: shadow acne).
real light_visible(vec3 p, vec3 n, LightSample s, int id)
{
    if (!needs_shadow_ray(n, s)) {
        return 1.0;
    }
    vec3 origin = p + SURFACE_OFFSET * n;
    return {{ shadows }}_shadow(origin, s.to_light, s.distance{{ own }});
}
{% endif %}
{% if paired %}

// How much of lights a and b reaches p, their shadow rays marched together (from
// SURFACE_OFFSET off the surface, as light_visible's).
vec2 lights_visible(vec3 p, vec3 n, LightSample a, LightSample b, int id)
{
    vec3 origin = p + SURFACE_OFFSET * n;
    return hard_shadow_pair(origin, a.to_light, a.distance, needs_shadow_ray(n, a),
                            b.to_light, b.distance, needs_shadow_ray(n, b){{ own }});
}
{% endif %}

{% endif %}
// The {{ model }} model (reference_cpu/shading.py) summed over the lights, plus ambient.
{% if path_labels %}
// Returns (colour, features): features codes the checker cell or the texture's face and, one
// bit per light, whether a hard shadow blocked it (for the path label).
vec4 shade_{{ model }}(vec3 p, vec3 n, vec3 v, int id)
{% else %}
vec3 shade_{{ model }}(vec3 p, vec3 n, vec3 v, int id)
{% endif %}
{
    vec3 albedo = surface_albedo(p, n, id);
    real ka = MATERIAL(id, 0).w;
    real kd = MATERIAL(id, 1).x;
    real ks = MATERIAL(id, 1).y;
    real shininess = MATERIAL(id, 1).z;
    vec3 color = ka * albedo * AMBIENT;
{% if path_labels %}
    real features = {{ features }};
{% endif %}
{% if shadows != "none" %}
    real visible;
{% endif %}
    LightSample s;
{% if paired %}
    // The lights' samples first: their hard shadow rays are marched two by two.
{% for light in lights %}
    LightSample s{{ light.index }} = {{ sample(light) }};
{% endfor %}
{% for i in range(0, paired, 2) %}
    vec2 visible{{ i }}{{ i + 1 }} = lights_visible(p, n, s{{ i }}, s{{ i + 1 }}, id);
{% endfor %}
{% endif %}
{% for light in lights %}
{% set L = "LIGHT%d_" % light.index %}
    // light {{ light.index }}: {{ light.kind }}{{ ", with its own ambient, diffuse and specular colours" if light.own }}
    s = {{ "s%d" % light.index if paired else sample(light) }};
{% if shadows != "none" %}
{% if light.index < paired %}
    visible = visible{{ light.index - light.index % 2 }}{{ light.index - light.index % 2 + 1 }}.{{ "xy"[light.index % 2] }};
{% else %}
    visible = light_visible(p, n, s, id);
{% endif %}
{% endif %}
{% if light.own %}
    vec3 falloff{{ light.index }} = s.radiance;
    s.radiance = falloff{{ light.index }} * {{ L }}RADIANCE;
{% endif %}
{% if shadows != "none" %}
    s.radiance = visible * s.radiance;
{% endif %}
{% if path_labels %}
    features = 2.0 * features{{ " + (visible == 0.0 ? 1.0 : 0.0)" if shadows == "hard" }};
{% endif %}
{% if light.own %}
    color = color + s.radiance * (kd * {{ D }} * albedo) + {{ "visible * " if shadows != "none" }}(falloff{{ light.index }} * {{ L }}SPECULAR) * (ks * {{ S }});
    color = color + ka * albedo * {{ "%sAMBIENT" % L if light.kind == "directional" else "attenuation(s.distance, %sATTENUATION) * %sAMBIENT" % (L, L) }};
{% else %}
    color = color + s.radiance * (kd * {{ D }} * albedo + ks * {{ S }});
{% endif %}
{% endfor %}
    return {{ "vec4(color, features)" if path_labels else "color" }};
}
