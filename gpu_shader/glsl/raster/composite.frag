#version 330 core
// The raster backend's full-screen compositing steps (gpu_shader/raster_render.py), one
// program: each reads one texture at the pixel and writes (rgb, a) for the blending that the
// Python side sets for the step.
//   0 "reflection": kr times the mirrored pass's colour, on the mirror's pixels only;
//      added (ONE, ONE) to the picture: colour += kr * reflected (reference_cpu/raster_render.py).
//   1 "layer": one peeled layer (a c, a) under the layers before it: C += T a c, T *= 1 - a,
//      the front-to-back form of Porter and Duff's "over" (Bavoil and Myers 2008), with T
//      kept in the accumulator's alpha.
//   2 "under": the accumulated layers over the picture: colour = C + T colour.

uniform int stage;
uniform sampler2D source;       // the mirrored pass's colour, a peeled layer, or the layers
uniform isampler2D ids;         // the opaque pass's ids (step 0)
uniform int mask_id;            // the mirror's object (step 0)
uniform float kr;               // the mirror's reflectivity (step 0)

out vec4 out_color;

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec4 value = texelFetch(source, pixel, 0);
    if (stage == 0) {
        if (texelFetch(ids, pixel, 0).x != mask_id) {
            discard;
        }
        out_color = vec4(kr * value.rgb, 0.0);
    } else if (stage == 1) {
        out_color = vec4(value.a * value.rgb, value.a);
    } else {
        out_color = value;
    }
}
