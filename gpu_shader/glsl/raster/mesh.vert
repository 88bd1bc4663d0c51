#version 330 core
// The raster pipeline's vertex shader: a mesh's vertex into clip space through marchlab's
// camera (reference_cpu/rasterise.py, project_corners, is the same arithmetic in NumPy).
//
// view = (right, up, forward) . (p - eye); the image point is x = (view.x / (view.z h a) + 1)
// W / 2 and y = (1 - view.y / (view.z h)) H / 2, y counted down from the top, where h is
// tan(fov / 2) and a = W / H. Window y here equals the image's y (the picture is drawn upside
// down in GL's y-up window), so GL row r holds image row r from the top, as the sphere
// tracer's planes do (gpu_shader/render.py), and GL's fill rule in window coordinates is the
// top-left rule in the image's.

in vec3 position;
in vec3 normal;
in vec2 uv;

uniform vec3 eye;
uniform vec3 right;
uniform vec3 up;
uniform vec3 forward;
uniform float half_height;      // tan(fov / 2)
uniform float aspect;           // W / H
uniform float near;             // the near clipping plane (m)
uniform float far;

out vec3 v_normal;
out vec2 v_uv;
out float v_z;                  // view depth, interpolated perspective-correctly by GL

void main()
{
    vec3 offset = position - eye;
    vec3 view = vec3(dot(offset, right), dot(offset, up), dot(offset, forward));
    // Clip space with w = view depth: GL divides by it, and clips where z_clip < -w, that is
    // where view.z < near (the NumPy rasteriser's clip_near).
    float z_clip = (view.z * (far + near) - 2.0 * far * near) / (far - near);
    gl_Position = vec4(view.x / (half_height * aspect), -view.y / half_height, z_clip, view.z);
    v_normal = normal;
    v_uv = uv;
    v_z = view.z;
}
