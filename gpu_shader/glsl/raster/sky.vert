#version 330 core
// The skybox's vertex shader: one triangle over the whole viewport (as glsl/fullscreen.vert),
// at the far end of the depth range. Drawn after the meshes with the depth test "<=", it
// covers only the pixels no triangle drew, and the depth test rejects the others before
// their fragments run: every hidden pixel costs no background lookup (de Vries,
// LearnOpenGL, "Cubemaps", "An optimization").

void main()
{
    vec2 corner = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(corner, 1.0, 1.0);      // z = w: depth 1, the far plane
}
