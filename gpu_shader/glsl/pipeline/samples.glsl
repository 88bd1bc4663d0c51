{# A template: gpu_shader/generate.py fills in the {{ }} and {% %} parts for one scene (Jinja). #}
// Anti-aliasing by supersampling, {{ n }} x {{ n }} rays a pixel on the {{ pattern }} grid
// (scene_model/sampling.py, which derives the offsets below: every backend shoots these rays).

// The offset of ray k from its pixel's centre, in pixels (x right, y down): the samples
// 0 .. {{ n * n - 1 }}{{ ", then the centre itself, for the buffers other than colour" if centre == n * n }}
// (scene_model/sampling.py, ray_offsets).
vec2 ray_offset(int k)
{
{% for dx, dy in offsets[:-1] %}
    if (k == {{ loop.index0 }}) {
        return vec2({{ dx }}, {{ dy }});
    }
{% endfor %}
    return vec2({{ offsets[-1][0] }}, {{ offsets[-1][1] }});
}

// The pixel whose centre is the image point (x, y), from all of its rays, each traced from
// `start` (the tile's cone holds every point of its pixels: glsl/cone.glsl). As
// reference_cpu/render.py folds them (add_ray): the mean of the samples' colours, each
// clamped to [0, 1] first; the march, normal and object id of ray {{ centre }}, through the centre;
// the steps of all the rays{{ "; the samples' path labels folded in order" if path_labels }}.
Pixel supersample(real x, real y, real start)
{
    Pixel centre;
    vec3 color = vec3(0.0);
    int steps = 0;
{% if path_labels %}
    uint path = 0u;
{% endif %}
    for (int k = 0; k < {{ rays }}; k++) {
        vec2 offset = ray_offset(k);
        vec3 direction = camera_ray(x + offset.x, y + offset.y);
        Pixel px = trace(CAMERA_POSITION, direction, start);
        steps = steps + px.primary.steps;
        if (k < {{ n * n }}) {
            color = color + clamp(px.color, 0.0, 1.0);
{% if path_labels %}
            path = path_step(path, int(px.path), 0u);
{% endif %}
        }
        if (k == {{ centre }}) {
            centre = px;
        }
    }
    centre.color = color / {{ count }};
    centre.primary.steps = steps;
{% if path_labels %}
    centre.path = real(path);
{% endif %}
    return centre;
}
