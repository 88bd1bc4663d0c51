// Image textures: the GLSL and OpenCL twin of reference_cpu/texture.py.
//
// A program's textures lie in one array of texels, the atlas (scene_model/environment.py
// says how an environment's images fill it). TEXEL(column, row) reads texel `column` of atlas
// row `row` exactly, as the dialect spells it (gpu_shader/dialects.py: texelFetch from an
// RGBA32F texture in GLSL, rows of the parameter buffer in OpenCL): no sampler of the driver
// filters here, so every backend computes the same sums in the same order.
//
// One texture, `image`, is four numbers (a vec4): its first row in the atlas, its width and
// height in texels, and wrap (0: clamped at its edges; 1: it repeats left to right, as a
// panorama does; 2: it repeats both ways, as a surface texture does).
//
// Then the surface mappings, in world space (docs/phong.md, "Textures"): cube (the face of
// the world axis nearest the normal), triplanar (three faces blended by the normal, Geiss
// 2007) and sphere (the normal's longitude and latitude).

// The colour of a texture at (u, v), (0, 0) its top left corner and (1, 1) its bottom right,
// by bilinear filtering (OpenGL 4.6 core spec, section 8.14.2): the four texels around
// x = u width - 1/2, y = v height - 1/2, weighted by the fractions a, b of x and y. Texels
// beyond an edge are the edge's or, where it wraps (left and right with wrap 1, every edge
// with wrap 2), the other side's (for u and v in [0, 1]).
vec3 texture_bilinear(vec4 image, real u, real v)
{
    precise real x = u * image.y - 0.5;
    precise real y = v * image.z - 0.5;
    real fx = floor(x);
    real fy = floor(y);
    real a = x - fx;
    real b = y - fy;
    int first = int(image.x);
    int width = int(image.y);
    int height = int(image.z);
    int i0 = int(fx);
    int i1 = i0 + 1;
    if (image.w > 0.0) {
        i0 = i0 < 0 ? i0 + width : i0;
        i1 = i1 >= width ? i1 - width : i1;
    }
    i0 = clamp(i0, 0, width - 1);
    i1 = clamp(i1, 0, width - 1);
    int j0 = int(fy);
    int j1 = j0 + 1;
    if (image.w > 1.0) {
        j0 = j0 < 0 ? j0 + height : j0;
        j1 = j1 >= height ? j1 - height : j1;
    }
    int r0 = first + clamp(j0, 0, height - 1);
    int r1 = first + clamp(j1, 0, height - 1);
    vec3 t00 = TEXEL(i0, r0).xyz;
    vec3 t10 = TEXEL(i1, r0).xyz;
    vec3 t01 = TEXEL(i0, r1).xyz;
    vec3 t11 = TEXEL(i1, r1).xyz;
    precise vec3 upper = t00 + (t10 - t00) * a;
    precise vec3 lower = t01 + (t11 - t01) * a;
    precise vec3 color = upper + (lower - upper) * b;
    return color;
}

// A texture repeated across the plane (wrap 2): texture_bilinear at (u - floor(u),
// v - floor(v)), for any u and v.
vec3 texture_repeat(vec4 image, real u, real v)
{
    precise real fu = u - floor(u);
    precise real fv = v - floor(v);
    return texture_bilinear(image, fu, fv);
}

// The cube face 0 to 5 (+x, -x, +y, -y, +z, -z) of the largest |component| of d and its sign,
// the face a cube map shows along d (OpenGL 4.6 core spec, section 8.13). Where two
// components tie (the spec leaves it open), x wins over y and y over z.
real major_face(vec3 d)
{
    vec3 a = abs(d);
    real face = 0.0;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x >= 0.0 ? 0.0 : 1.0;
    } else if (a.y >= a.z) {
        face = d.y >= 0.0 ? 2.0 : 3.0;
    } else {
        face = d.z >= 0.0 ? 4.0 : 5.0;
    }
    return face;
}

// The coordinates (sc, tc) of q on cube face `face`: table 8.19 of the OpenGL 4.6 core spec
// (section 8.13), what a cube map's face shows, upright and unmirrored seen from outside:
// +x (-z, -y), -x (z, -y), +y (x, z), -y (x, -z), +z (x, -y), -z (-x, -y).
vec2 cube_face_coordinates(vec3 q, real face)
{
    real sc = face == 0.0 ? -q.z : (face == 1.0 ? q.z : (face == 5.0 ? -q.x : q.x));
    real tc = face == 2.0 ? q.z : (face == 3.0 ? -q.z : -q.y);
    return vec2(sc, tc);
}

// Where on a panorama d points: u = atan2(x, -z) / 2 pi + 1/2 around (0.5 straight ahead
// along -z, 0.75 along +x) and v = 1/2 - atan2(y, sqrt(x^2 + z^2)) / pi, which is
// acos(y / |d|) / pi (0 straight up) but needs no unit d.
vec2 equirect_uv(vec3 d)
{
    precise real across = d.x * d.x + d.z * d.z;
    real u = atan2(d.x, -d.z) / 6.283185307179586 + 0.5;
    real v = 0.5 - atan2(d.y, sqrt(across)) / 3.141592653589793;
    return vec2(u, v);
}

// The weights of the x, y and z projections at the unit normal n: w_i = |n_i|^k / (|n_x|^k +
// |n_y|^k + |n_z|^k), k the sharpness (after Geiss 2007, GPU Gems 3, ch. 1). They sum to 1.
vec3 triplanar_weights(vec3 n, real sharpness)
{
    vec3 a = abs(n);
    real wx = pow(a.x, sharpness);
    real wy = pow(a.y, sharpness);
    real wz = pow(a.z, sharpness);
    precise real total = wx + wy + wz;
    return vec3(wx / total, wy / total, wz / total);
}

// The texture on the face of the world axis nearest the normal n: the coordinates of p on it
// divided by scale, repeated. Exact for planes and boxes aligned with the axes; its face is
// a path-label feature, as the colour may jump where it changes.
vec3 texture_cube(vec3 p, vec3 n, vec4 image, real scale)
{
    vec2 q = cube_face_coordinates(p, major_face(n));
    return texture_repeat(image, q.x / scale, q.y / scale);
}

// The three projections along the axes, on the faces facing the normal's way (so no side
// shows mirrored), blended by triplanar_weights: a projection changes sides only where its
// weight is 0, so the blend is continuous.
vec3 texture_triplanar(vec3 p, vec3 n, vec4 image, real scale, real sharpness)
{
    vec3 w = triplanar_weights(n, sharpness);
    vec2 qx = cube_face_coordinates(p, n.x >= 0.0 ? 0.0 : 1.0);
    vec2 qy = cube_face_coordinates(p, n.y >= 0.0 ? 2.0 : 3.0);
    vec2 qz = cube_face_coordinates(p, n.z >= 0.0 ? 4.0 : 5.0);
    vec3 cx = texture_repeat(image, qx.x / scale, qx.y / scale);
    vec3 cy = texture_repeat(image, qy.x / scale, qy.y / scale);
    vec3 cz = texture_repeat(image, qz.x / scale, qz.y / scale);
    precise vec3 color = w.x * cx + w.y * cy + w.z * cz;
    return color;
}

// Where on a sphere's texture the unit normal n points: u = atan2(n.x, n.z) / 2 pi + 1/2,
// v = acos(n.y) / pi (the middle of the image faces +z, u grows eastward, v from the north
// pole down: upright and unmirrored from outside), which is equirect_uv of (n.x, n.y, -n.z).
vec2 sphere_uv(vec3 n)
{
    return equirect_uv(vec3(n.x, n.y, -n.z));
}

// A sphere's texture: the image wrapped round it once at sphere_uv (image wraps left and
// right, its rows clamped at the poles); its sides meet at the back (-z) without a seam.
vec3 texture_sphere(vec3 n, vec4 image)
{
    vec2 uv = sphere_uv(n);
    return texture_bilinear(image, uv.x, uv.y);
}
