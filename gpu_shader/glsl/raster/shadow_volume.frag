#version 330 core
// A shadow volume's fragment: what a stencil operation would add, summed by additive
// blending into a float texture. Depth-fail (the depth test, set by
// gpu_shader/raster_shadows.py, lets through only the fragments behind the surface drawn):
// +1 on a back face, -1 on a front face; z-pass (only those in front of it): the opposite.
// Its depth is the view depth z mapped as z / (z + depth_scale): 0 at the eye, 1 exactly at
// infinity (v_w = 0), and fine enough in a 24-bit depth buffer (2e-6 m at 5 m for
// depth_scale = 1 m), where mesh.frag's z / far is 6e-3 m coarse.

in float v_z;
in float v_w;

uniform float depth_scale;      // m
uniform float front_count;      // what a front face adds: -1 depth-fail, +1 z-pass

out float count;

void main()
{
    // Drawn upside down, a face wound outward is front facing with front_face = "cw".
    count = gl_FrontFacing ? front_count : -front_count;
    gl_FragDepth = v_z / (v_z + v_w * depth_scale);
}
