{# A macro the entry points share (Jinja): imported by glsl/main.frag and glsl/main.comp. #}
{# One pixel's three planes from its centre (x, y) and its rays' start, which the caller has
   declared: colour and hit, normal and depth, and steps, object id and path label. #}
{% macro pixel_planes(path_labels, samples) %}
{% if samples %}
    Pixel px = supersample(x, y, start);      // every ray of the pixel (anti-aliasing)
{% else %}
    Pixel px = trace(CAMERA_POSITION, camera_ray(x, y), start);
{% endif %}
    Hit h = px.primary;
    vec4 color_hit = vec4(clamp(px.color, 0.0, 1.0), float(h.hit));
    vec4 normal_depth = vec4(px.normal, h.hit == 1 ? h.t : INFINITY);
    ivec4 steps_id = ivec4(h.steps, px.id, {{ "int(px.path)" if path_labels else "0" }}, 0);
{% endmacro %}
