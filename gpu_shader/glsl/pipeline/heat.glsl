{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
// The heat ramp of scene_model/colormaps.py, x in [0, 1]: linear between its stops.
vec3 heat(real x)
{
    x = clamp(x, 0.0, 1.0);
{% for s in segments %}
    {% if not loop.last %}if (x <= {{ s.x1 }}) {% endif %}return vec3({{ s.c0 }}) + (vec3({{ s.c1 }}) - vec3({{ s.c0 }})) * ((x - {{ s.x0 }}) / {{ s.width }});
{% endfor %}
}
