// Shading for packets of rays: the packet twin of glsl/shading.glsl (and so of
// reference_cpu/shading.py), which gives the formulas and their sources. glsl/packet.cl
// says what a packet is. Each function does, lane by lane, the scalar one's operations in
// the same order; vec3 arithmetic is spelled with add, sub, mul and div, and `c ? a : b`
// with a vector c (or `choose` for a vec3p) picks lane by lane.

// Lambert's cosine term max(N.L, 0).
packet diffuse(vec3p n, vec3p l)
{
    return max(dot(n, l), 0.0);
}

// max(R.V, 0)^alpha with R = reflect(-L, N); 0 where N.L <= 0. (`power` is pow, a quarter
// packet at a time: glsl/packet.cl says why.)
packet specular_phong(vec3p n, vec3p l, vec3p v, packet shininess)
{
    vec3p r = reflect(neg(l), n);
    return dot(n, l) > 0.0 ? power(max(dot(r, v), 0.0), shininess) : 0.0;
}

// max(N.H, 0)^alpha with the half vector H = normalize(L + V) (Blinn 1977).
packet specular_blinn_phong(vec3p n, vec3p l, vec3p v, packet shininess)
{
    vec3p h = normalize(add(l, v));
    return dot(n, l) > 0.0 ? power(max(dot(n, h), 0.0), shininess) : 0.0;
}

// Quantise x in [0, 1] to `bands` levels, each step a narrow smoothstep (glsl/shading.glsl).
packet toon_band(packet x, real bands)
{
    packet q = x * bands;
    packet level = floor(q);
    packet step = smoothstep(0.9, 1.0, q - level);
    return min((level + step) / (bands - 1.0), 1.0);
}

// 0 where floor(x/s) + floor(z/s) is even, 1 where it is odd.
packet checker_parity(vec3p p, packet scale)
{
    packet cells = floor(p.x / scale) + floor(p.z / scale);
    return cells - 2.0 * floor(cells * 0.5);
}

// Checkerboard in the xz-plane: color_a where floor(x/s) + floor(z/s) is even.
vec3p checker(vec3p p, vec3p color_a, vec3p color_b, packet scale)
{
    return choose(checker_parity(p, scale) == 0.0, color_a, color_b);
}

// Fold one bounce into the pixel's path label (glsl/shading.glsl says why). In float64 a
// upacket is ulong16, not uint16 (a mask's integers must be as wide as the reals): the
// arithmetic is then modulo 2^64 instead of 2^32, but the low 24 bits, all that is kept,
// are the same, since 2^32 and 2^64 are multiples of 2^24.
upacket path_step(upacket path, ipacket id, upacket features)
{
    return ((path * 1009u + convert_upacket(id + 1)) * 64u + features) & 0xFFFFFFu;
}

// |N| as a colour: x red, y green, z blue.
vec3p shade_normals(vec3p normal)
{
    return abs(normal);
}

// Grey 1 - t / max_distance: white at the eye, black at max_distance.
vec3p shade_depth(packet t, real max_distance)
{
    packet grey = clamp(1.0 - t / max_distance, 0.0, 1.0);
    return pack3(grey, grey, grey);
}

// Exponential fog (Quilez, "Fog"): mix toward the fog colour by 1 - exp(-density t).
vec3p apply_fog(vec3p color, packet t, vec3 fog_color, real density)
{
    packet amount = 1.0 - exp(-density * t);
    return add(color, mul(amount, sub(fog_color, color)));
}

// A solid colour for rays that hit nothing.
vec3p background_solid(vec3p direction, vec3 color)
{
    return splat3(color);
}

// The sky: bottom to top by a = (d.y + 1) / 2 ("Ray Tracing in One Weekend").
vec3p background_sky(vec3p direction, vec3 bottom, vec3 top)
{
    packet a = (direction.y + 1.0) / 2.0;
    return add(splat3(bottom), mul(a, top - bottom));
}
