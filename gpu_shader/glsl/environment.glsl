// Environment maps: the GLSL and OpenCL twin of reference_cpu/environment.py.
//
// What a ray that hits nothing sees, read from a cube map or a panorama in the texture atlas
// (glsl/texture.glsl, which also holds the cube face rule and equirect_uv that these call).
// `look` is the background's (intensity, cos, sin of its rotation).

// The direction of the environment that a ray along d sees: d turned by -rotation about +y
// (a rotation of 90 degrees shows, looking along -z, what was along +x).
vec3 environment_direction(vec3 d, real cos_turn, real sin_turn)
{
    precise real x = cos_turn * d.x - sin_turn * d.z;
    precise real z = sin_turn * d.x + cos_turn * d.z;
    return vec3(x, d.y, z);
}

// The cube face that d points at and where on it: (face, s, t), face 0 to 5 for +x, -x, +y,
// -y, +z, -z (major_face: the largest |component| ma, ties to x, then y), and s, t in [0, 1]
// from the face's top left corner: with the face coordinates sc, tc of d
// (cube_face_coordinates), s = (sc / |ma| + 1) / 2 and t = (tc / |ma| + 1) / 2 (OpenGL 4.6
// core spec, section 8.13, "Cube Map Texture Selection", table 8.19).
vec3 cube_map_face(vec3 d)
{
    real face = major_face(d);
    vec2 q = cube_face_coordinates(d, face);
    vec3 a = abs(d);
    real ma = face < 2.0 ? a.x : (face < 4.0 ? a.y : a.z);
    return vec3(face, 0.5 * (q.x / ma + 1.0), 0.5 * (q.y / ma + 1.0));
}

// A cube map background: the face's texture (face f starts f times the width below the
// first), sampled at (s, t) and scaled by the intensity.
vec3 background_cubemap(vec3 direction, vec4 image, vec3 look)
{
    vec3 d = environment_direction(direction, look.y, look.z);
    vec3 face = cube_map_face(d);
    precise real first = image.x + face.x * image.y;
    vec4 side = vec4(first, image.y, image.z, image.w);
    return look.x * texture_bilinear(side, face.y, face.z);
}

// An equirectangular background: the panorama sampled at (u, v), scaled by the intensity.
vec3 background_equirect(vec3 direction, vec4 image, vec3 look)
{
    vec3 d = environment_direction(direction, look.y, look.z);
    vec2 uv = equirect_uv(d);
    return look.x * texture_bilinear(image, uv.x, uv.y);
}
