#version 330 core
// One triangle that covers the whole viewport: vertices (-1,-1), (3,-1), (-1,3). No vertex
// buffer is needed; every pixel's fragment runs the sphere tracer.
//
// A generated program defines ROWS and FLAT_ROWS below the #version line when its fragment
// shader reads the first FLAT_ROWS rows of the parameter block as flat varyings
// (gpu_shader/dialects.py): the copy from the uniform buffer then runs three times per draw,
// once per vertex, instead of once per pixel.
#ifdef FLAT_ROWS
layout(std140) uniform Parameters
{
    vec4 U[ROWS];
};

flat out vec4 P[FLAT_ROWS];
#endif

void main()
{
    vec2 corner = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(corner, 0.0, 1.0);
#ifdef FLAT_ROWS
    for (int i = 0; i < FLAT_ROWS; i++) {
        P[i] = U[i];
    }
#endif
}
