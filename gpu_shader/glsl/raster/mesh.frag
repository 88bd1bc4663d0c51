#version 330 core
// The raster pipeline's fragment shader: what the NumPy rasteriser's depth buffer keeps for a
// pixel, written into three planes (gpu_shader/raster.py reads them back as a Raster).

in vec3 v_normal;
in vec2 v_uv;
in float v_z;

uniform int object_id;
uniform vec2 size;              // W, H
uniform float half_height;
uniform float aspect;
uniform float far;

layout(location = 0) out vec4 out_normal_depth;   // xyz: unit normal, w: ray distance t
layout(location = 1) out vec4 out_uv;             // xy: texture coordinates
layout(location = 2) out ivec4 out_ids;           // x: object, y: triangle

void main()
{
    // The pixel's ray direction before normalising, d = forward + sx right + sy up, is
    // |d| = sqrt(1 + sx^2 + sy^2) long: a point at view depth z along it is z |d| away.
    float sx = (2.0 * gl_FragCoord.x / size.x - 1.0) * half_height * aspect;
    float sy = (1.0 - 2.0 * gl_FragCoord.y / size.y) * half_height;
    out_normal_depth = vec4(normalize(v_normal), v_z * sqrt(1.0 + sx * sx + sy * sy));
    out_uv = vec4(v_uv, 0.0, 0.0);
    out_ids = ivec4(object_id, gl_PrimitiveID, 0, 0);
    // The depth test on view depth z mapped as z / (z + 1 m), as the shadow volumes'
    // (glsl/raster/shadow_volume.frag): 2e-6 m fine at 5 m in the 24-bit depth buffer, where
    // z / far was 6e-3 m coarse and let two surfaces 2 mm apart swap (GL's own z / w crowds
    // its precision at the near plane instead).
    gl_FragDepth = v_z / (v_z + 1.0);
}
