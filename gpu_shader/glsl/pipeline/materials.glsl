{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
{% import "pipeline/albedo.glsl" as albedo %}
// Each object's material, by object id: the rows that follow the fixed parameters in U.
// Row 0: (color, ka); row 1: (kd, ks, shininess, kr){% if checker %}; row 2: (checker color_a, scale);
// row 3: (checker color_b, 1 if checkered){% endif %}{% if glass_row is not none %}; row {{ glass_row }}: (absorption, transparency);
// row {{ glass_row + 1 }}: (ior, 0, 0, 0){% endif %}{% if model_row is not none %}; row {{ model_row }}: (shading model code, 0, 0, 0){% endif %}{% if texture_row is not none %};
// row {{ texture_row }}: (texture image: first row, width, height, wrap); row {{ texture_row + 1 }}: (tint, scale);
// row {{ texture_row + 2 }}: (mapping code: {% for name, code in mappings.items() %}{{ code }} {{ name }}, {% endfor %}0 without a texture; sharpness, 0, 0){% endif %}.
#define MATERIAL(id, row) U[{{ first }} + {{ stride }} * (id) + (row)]

// The albedo at p, with unit normal n, of the object hit: its colour{% if checker %}, or its checkerboard{% endif %}{% if texture_row is not none %}, or its
// texture times the tint{% endif %}.
{{ albedo.surface_albedo(checker, texture_row, mappings, {
       "triplanar": "texture_triplanar(p, n, MATERIAL(id, %(T)d), MATERIAL(id, %(T1)d).w, MATERIAL(id, %(T2)d).y)",
       "cube": "texture_cube(p, n, MATERIAL(id, %(T)d), MATERIAL(id, %(T1)d).w)",
       "sphere": "texture_sphere(n, MATERIAL(id, %(T)d))"}) }}{% if checker and path_labels %}

// The checker cell's parity at p (0 where the material has no checkerboard): a feature of
// the path label.
real surface_checker_parity(vec3 p, int id)
{
    return MATERIAL(id, 3).w > 0.0 ? checker_parity(p, MATERIAL(id, 2).w) : 0.0;
}
{% endif %}
{% if path_labels and texture_row is not none and "cube" in mappings %}

// The face of a cube-mapped texture at normal n (0 where the object has none): a feature of
// the path label, as the texture may jump where the face changes.
real surface_texture_face(vec3 n, int id)
{
    return MATERIAL(id, {{ texture_row + 2 }}).x == {{ "%d.0" % mappings["cube"] }} ? major_face(n) : 0.0;
}
{% endif %}
