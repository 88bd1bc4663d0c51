#version 330 core
// A shadow volume's fragment: what a stencil operation would add, +1 on a back face and -1
// on a front face, summed by additive blending into a float texture (the depth test, set
// by gpu_shader/raster_shadows.py, lets through only the fragments behind the surface
// drawn: depth-fail). Its depth is the view depth z mapped as z / (z + depth_scale): 0 at
// the eye, 1 exactly at infinity (v_w = 0), and fine enough in a 24-bit depth buffer
// (2e-6 m at 5 m for depth_scale = 1 m), where mesh.frag's z / far is 6e-3 m coarse.

in float v_z;
in float v_w;

uniform float depth_scale;      // m

out float count;

void main()
{
    // Drawn upside down, a face wound outward is front facing with front_face = "cw".
    count = gl_FrontFacing ? -1.0 : 1.0;
    gl_FragDepth = v_z / (v_z + v_w * depth_scale);
}
