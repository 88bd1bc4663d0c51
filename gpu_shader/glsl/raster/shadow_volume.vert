#version 330 core
// A shadow volume's vertex into clip space through marchlab's camera, with points at
// infinity allowed: w = 1 for an ordinary vertex, w = 0 for one extruded infinitely far
// away from the light (the direction p - L, or a directional light's direction).
// gpu_shader/raster_shadows.py draws the scene's depth with this shader too, so that a
// front cap triangle (a light-facing triangle of the object) lands on exactly the depth
// the same triangle wrote.
//
// The camera is mesh.vert's; the projection is Everitt and Kilgard's infinite one
// ("Practical and Robust Stenciled Shadow Volumes", 2002, section 5): the far plane moved
// to infinity, so z_clip = z - 2 near w and a point at infinity (w = 0) lands on it instead
// of being clipped away. The factor 1 - 1e-6 keeps it just inside, against rounding.

in vec4 position;

uniform vec3 eye;
uniform vec3 right;
uniform vec3 up;
uniform vec3 forward;
uniform float half_height;      // tan(fov / 2)
uniform float aspect;           // W / H
uniform float near;             // the near clipping plane (m)

out float v_z;                  // view depth of the homogeneous point (x, y, z, w) ...
out float v_w;                  // ... and its w: the point's view depth is v_z / v_w

void main()
{
    vec3 offset = position.xyz - eye * position.w;
    vec3 view = vec3(dot(offset, right), dot(offset, up), dot(offset, forward));
    float z_clip = view.z * (1.0 - 1e-6) - 2.0 * near * position.w;
    gl_Position = vec4(view.x / (half_height * aspect), -view.y / half_height, z_clip, view.z);
    v_z = view.z;
    v_w = position.w;
}
