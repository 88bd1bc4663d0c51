{# A template: gpu_shader/raster_shaders.py (lit_shaders) fills it in (Jinja). The raster twin of #}
{# glsl/pipeline/materials.glsl: the same material rows, and a mesh's own texture coordinates. #}
{% import "pipeline/albedo.glsl" as albedo %}
{% if "uv" in mappings %}
// A texture at a mesh's texture coordinates uv, repeated every `scale` in u and v: a mesh's
// (0, 0) is its texture's bottom left (scene_model/meshes.py), an image's its top left, so
// v is turned over (reference_cpu/raster_shading.py, texture_uv).
vec3 texture_uv(vec4 image, vec2 uv, real scale)
{
    return texture_repeat(image, uv.x / scale, (1.0 - uv.y) / scale);
}

{% endif %}
// The albedo at p, with unit normal n, of the object drawn: its colour{% if checker %}, or its checkerboard{% endif %}{% if texture_row is not none %}, or
// its texture times the tint{% endif %} (reference_cpu/raster_shading.py, surface_albedo). Its material rows:
//   0: (color, ka)
{% if checker %}
//   2, 3: (checker color_a, scale), (checker color_b, 1 if checkered)
{% endif %}
{% if texture_row is not none %}
//   {{ texture_row }} to {{ texture_row + 2 }}: (its image in the atlas: first row, width, height, wrap), (tint, scale),
//   (mapping code: {% for name, code in mappings.items() %}{{ code }} {{ name }}, {% endfor %}0 without a texture; sharpness)
{% endif %}
{% if "uv" in mappings %}
// A uv texture reads v_uv, the fragment's interpolated texture coordinates (mesh.frag).
{% endif %}
{{ albedo.surface_albedo(checker, texture_row, mappings, {
       "triplanar": "texture_triplanar(p, n, MATERIAL(id, %(T)d), MATERIAL(id, %(T1)d).w, MATERIAL(id, %(T2)d).y)",
       "uv": "texture_uv(MATERIAL(id, %(T)d), v_uv, MATERIAL(id, %(T1)d).w)"}) }}