{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{# The physics step (gpu_shader/physics_shapes.py) fills it in once per static shape, with its #}
{# own name, distance function and step; the renderer leaves them at their defaults.          #}
// Surface normals by finite differences, the {{ method }} stencil of reference_cpu/normals.py:
// g = sum_k k {{ sdf | default("scene_sdf") }}(p + h k) over the stencil's offsets k (Quilez, "Normals for an SDF"),
// n = g / |g|; zero where the gradient vanishes.
vec3 {{ function | default("estimate_normal") }}(vec3 p)
{
    real h = {{ step | default("NORMAL_STEP") }};
    vec3 g = vec3(0.0);
{% for k in stencil %}
    g = g + {{ sdf | default("scene_sdf") }}(p + h * vec3({{ k }})) * vec3({{ k }});
{% endfor %}
    real size = sqrt(dot(g, g));
    return size > 0.0 ? g / size : vec3(0.0);
}
