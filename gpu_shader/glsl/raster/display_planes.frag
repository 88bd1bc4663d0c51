#version 330 core
// The raster backend's planes turned into the three planes the display pass reads
// (gpu_shader/raster_display.py): the GLSL twin of gpu_shader.raster.read_planes and
// reference_cpu.raster_render.mesh_frame, so that the live view shows a mesh scene with the
// same display pass, overlays and selection outline as a sphere-traced one.
//
// In:  0 normal xyz, depth t    1 uv (unused here)    2 ids: x object, y triangle
//      3 colour: linear rgb, unclamped; a = 1 where a triangle is drawn
// Out: 0 colour rgb in [0, 1], 1 on a hit     1 normal xyz, depth t (inf on a miss)
//      2 steps (0: nothing was marched), object id (-1 on a miss), path label (0), 0
//
// Each pixel copies texel for texel (gl_FragCoord is the texel, and both sets of planes keep
// the image's top row in GL row 0), so the rows stay as the display pass expects them.

uniform sampler2D normal_depth;
uniform isampler2D ids;
uniform sampler2D colour;

layout(location = 0) out vec4 color_hit;
layout(location = 1) out vec4 normal_depth_out;
layout(location = 2) out ivec4 steps_id;

void main()
{
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec4 c = texelFetch(colour, texel, 0);
    // read_planes: a pixel is a hit where the colour's alpha is above 0.
    bool hit = c.a > 0.0;
    vec4 nd = texelFetch(normal_depth, texel, 0);
    float miss_depth = uintBitsToFloat(0x7f800000u);       // +inf, as Raster.depth has it
    // mesh_frame clips the colour to [0, 1] (the display pass raises it to 1 / gamma, which
    // a negative number would make undefined).
    color_hit = vec4(clamp(c.rgb, 0.0, 1.0), hit ? 1.0 : 0.0);
    normal_depth_out = hit ? nd : vec4(0.0, 0.0, 0.0, miss_depth);
    steps_id = ivec4(0, hit ? texelFetch(ids, texel, 0).x : -1, 0, 0);
}
