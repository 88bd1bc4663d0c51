{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
// Each object's material, by object id: the rows that follow the fixed parameters in U.
// Row 0: (color, ka); row 1: (kd, ks, shininess, kr){% if checker %}; row 2: (checker color_a, scale);
// row 3: (checker color_b, 1 if checkered){% endif %}.
#define MATERIAL(id, row) U[{{ first }} + {{ stride }} * (id) + (row)]

// The albedo at p of the object hit: its colour{% if checker %}, or its checkerboard{% endif %}.
vec3 surface_albedo(vec3 p, int id)
{
{% if checker %}
    if (MATERIAL(id, 3).w > 0.0) {
        return checker(p, MATERIAL(id, 2).xyz, MATERIAL(id, 3).xyz, MATERIAL(id, 2).w);
    }
{% endif %}
    return MATERIAL(id, 0).xyz;
}
{% if checker and path_labels %}

// The checker cell's parity at p (0 where the material has no checkerboard): a feature of
// the path label.
real surface_checker_parity(vec3 p, int id)
{
    return MATERIAL(id, 3).w > 0.0 ? checker_parity(p, MATERIAL(id, 2).w) : 0.0;
}
{% endif %}
