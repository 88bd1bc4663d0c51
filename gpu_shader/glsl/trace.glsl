// One pixel, from its camera ray to everything the Frame holds (reference_cpu/render.py,
// Tracer.trace). A scene with mirrors gets a generated trace instead, whose reflection loop
// marches the camera ray as its first bounce (gpu_shader/generate.py).

// The pixel's primary ray: its march and, on a hit, the normal and object id there; then
// its colour and path label from pixel_color.
Pixel trace(vec3 origin, vec3 direction)
{
    Pixel px;
    px.primary = march(origin, direction, MAX_DISTANCE);
    px.normal = vec3(0.0);
    px.id = -1;
    if (px.primary.hit == 1) {
        precise vec3 p = origin + px.primary.t * direction;
        px.normal = estimate_normal(p);
        px.id = scene_object_id(p);
    }
    px.color_path = pixel_color(origin, direction, px.primary, px.normal, px.id);
    return px;
}
