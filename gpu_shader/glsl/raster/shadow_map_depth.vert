#version 330 core
// The shadow map's depth pass, vertex stage: a mesh's vertex into clip space as the light
// sees it (reference_cpu/shadow_map.py, map_coordinates, is the same arithmetic in NumPy).
//
// view = (right, up, forward) . (p - eye) in the light's frame. A point or spot light looks
// through a square perspective frustum (eye: the light, half: tan(fov / 2), center: 0); a
// directional light through an orthographic box fitted to the scene (eye: the origin, half:
// half the map's side in metres, center: the map's middle in (right, up)). Both land the
// map's column x = ((view.x - center.x) / (half w) + 1) S / 2 and row from the top
// y = (1 - (view.y - center.y) / (half w)) S / 2, w = view.z (perspective) or 1: the map is
// drawn upside down, as the raster pipeline's planes are (glsl/raster/mesh.vert), so GL
// row r holds the map's row r from the top and GL's fill rule is the top-left rule.

in vec3 position;

uniform vec3 light_eye;
uniform vec3 light_right;
uniform vec3 light_up;
uniform vec3 light_forward;
uniform vec2 light_center;      // m: the map's middle in (right, up) (0 for perspective)
uniform float light_half;       // tan(fov / 2) (perspective) or half the map's side (m)
uniform bool perspective;
uniform float near;             // the perspective map's near and far planes (m)
uniform float far;

out float v_depth;              // depth along the light's axis (m), what the map stores

void main()
{
    vec3 offset = position - light_eye;
    vec3 view = vec3(dot(offset, light_right), dot(offset, light_up),
                     dot(offset, light_forward));
    float w = perspective ? view.z : 1.0;
    // Perspective: clip where view.z < near, as the NumPy rasteriser's clip_near. The
    // orthographic box keeps every depth (z_clip = 0): it is fitted across, not along.
    float z_clip = perspective ? (view.z * (far + near) - 2.0 * far * near) / (far - near)
                               : 0.0;
    gl_Position = vec4((view.x - light_center.x) / light_half,
                       -(view.y - light_center.y) / light_half, z_clip, w);
    // GL interpolates it perspective-correctly (w = view.z), or linearly (w = 1): the
    // weights reference_cpu/shadow_map.py's depth_map interpolates with.
    v_depth = view.z;
}
