#version 330 core
// How many transparent surfaces lie in front of the opaque one on each pixel
// (reference_cpu/transparency.py, depth_complexity): every transparent fragment in front adds 1,
// summed by additive blending. The path label counts them (gpu_shader/raster_render.py).

in vec3 v_normal;
in vec2 v_uv;
in float v_z;

uniform vec2 size;              // W, H
uniform float half_height;
uniform float aspect;
uniform sampler2D opaque_planes;   // the opaque pass's normal and depth (w: t)
uniform sampler2D opaque_color;    // ... and its colour (a: 1 where drawn)

out float count;

void main()
{
    // t as glsl/raster/mesh.frag computes it, to the bit.
    float sx = (2.0 * gl_FragCoord.x / size.x - 1.0) * half_height * aspect;
    float sy = (1.0 - 2.0 * gl_FragCoord.y / size.y) * half_height;
    float t = v_z * sqrt(1.0 + sx * sx + sy * sy);
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    if (texelFetch(opaque_color, pixel, 0).a > 0.0 && t >= texelFetch(opaque_planes, pixel, 0).w) {
        discard;
    }
    count = 1.0;
}
