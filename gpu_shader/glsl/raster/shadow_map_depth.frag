#version 330 core
// The shadow map's depth pass, fragment stage: the depth along the light's axis (m), kept
// in a float32 texture. gpu_shader/raster_shadow_map.py blends with MIN instead of testing
// depth, so each texel keeps exactly the nearest of its fragments' float32 depths, as
// reference_cpu/shadow_map.py's depth_map keeps np.minimum of them (no depth buffer's
// 24-bit rounding in between).

in float v_depth;

out float depth;

void main()
{
    depth = v_depth;
}
