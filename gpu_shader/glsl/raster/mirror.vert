#version 330 core
// The mirrored pass's vertex shader: glsl/raster/mesh.vert for the scene reflected about a
// flat mirror's plane (Kilgard, "Improving Shadows and Reflections via the Stencil Buffer",
// NVIDIA 1999; reference_cpu/planar_reflection.py is the same in NumPy).
//
// Each vertex p is drawn at M p, M the reflection about the plane (Householder's, mirror_matrix
// in reference_cpu/planar_reflection.py). What lies behind the mirror, seen from the eye, must
// not show in it: gl_ClipDistance[0] is p's signed distance from the plane, positive on the
// eye's side, and GL cuts every triangle where it is 0 and keeps the positive part, as
// clip_to_plane does in NumPy. The normal stays the real one: the fragment is shaded at the
// real point (glsl/raster/lit.frag, variant "mirror"). M has determinant -1, so it turns the
// winding over: a face wound outward turns anticlockwise in GL's window.

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
uniform mat4 mirror;            // M
uniform vec4 plane;             // the mirror's plane: (n, -n . q), n towards the eye

out vec3 v_normal;
out vec2 v_uv;
out float v_z;                  // view depth of the mirrored point

void main()
{
    vec3 mirrored = (mirror * vec4(position, 1.0)).xyz;
    vec3 offset = mirrored - eye;
    vec3 view = vec3(dot(offset, right), dot(offset, up), dot(offset, forward));
    float z_clip = (view.z * (far + near) - 2.0 * far * near) / (far - near);
    gl_Position = vec4(view.x / (half_height * aspect), -view.y / half_height, z_clip, view.z);
    gl_ClipDistance[0] = dot(plane.xyz, position) + plane.w;
    v_normal = normal;
    v_uv = uv;
    v_z = view.z;
}
