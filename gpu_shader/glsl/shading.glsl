// Shading: the GLSL twin of reference_cpu/shading.py.
//
// Phong (Phong 1975):
//     I = ka albedo i_a + sum_m radiance_m (kd max(N.L_m, 0) albedo + ks max(R_m.V, 0)^alpha)
// with R_m = reflect(-L_m, N). Blinn-Phong uses N.H, H = normalize(L + V). The specular
// term is zero where N.L <= 0, so a light behind a surface cannot make a highlight on it.

// Lambert's cosine term max(N.L, 0).
real diffuse(vec3 n, vec3 l)
{
    return max(dot(n, l), 0.0);
}

// max(R.V, 0)^alpha with R = reflect(-L, N).
real specular_phong(vec3 n, vec3 l, vec3 v, real shininess)
{
    vec3 r = reflect(-l, n);
    return dot(n, l) > 0.0 ? pow(max(dot(r, v), 0.0), shininess) : 0.0;
}

// max(N.H, 0)^alpha with the half vector H = normalize(L + V) (Blinn 1977).
real specular_blinn_phong(vec3 n, vec3 l, vec3 v, real shininess)
{
    vec3 h = normalize(l + v);
    return dot(n, l) > 0.0 ? pow(max(dot(n, h), 0.0), shininess) : 0.0;
}

// Quantise x in [0, 1] to `bands` levels; each step is a narrow smoothstep (a tenth of a
// band wide), so a rounding difference in x changes the colour only a little.
real toon_band(real x, real bands)
{
    real q = x * bands;
    real level = floor(q);
    real step = smoothstep(0.9, 1.0, q - level);
    return min((level + step) / (bands - 1.0), 1.0);
}

// A sawtooth of x in [0, 1] with `stripes` teeth, u = fract(stripes x); each tooth falls
// back to 0 over its last tenth by a smoothstep, so the colour stays continuous.
real stripes_band(real x, real stripes)
{
    real q = x * stripes;
    real u = q - floor(q);
    return u * (1.0 - smoothstep(0.9, 1.0, u));
}

// 0 where floor(x/s) + floor(z/s) is even, 1 where it is odd.
real checker_parity(vec3 p, real scale)
{
    real cells = floor(p.x / scale) + floor(p.z / scale);
    return cells - 2.0 * floor(cells * 0.5);
}

// Checkerboard in the xz-plane: color_a where floor(x/s) + floor(z/s) is even.
vec3 checker(vec3 p, vec3 color_a, vec3 color_b, real scale)
{
    return checker_parity(p, scale) == 0.0 ? color_a : color_b;
}

// Fold one bounce into the pixel's path label (reference_cpu/render.py, path_step): a hash
// of the object ids, checker cells and hard-shadow states along the path, kept to 24 bits
// so that a float render target holds it exactly. Where it changes between neighbouring
// pixels the image is discontinuous; the equivalence suite excuses only those pixels.
uint path_step(uint path, int id, uint features)
{
    return ((path * 1009u + uint(id + 1)) * 64u + features) & 0xFFFFFFu;
}

// |N| as a colour: x red, y green, z blue.
vec3 shade_normals(vec3 normal)
{
    return abs(normal);
}

// Grey 1 - t / max_distance: white at the eye, black at max_distance.
vec3 shade_depth(real t, real max_distance)
{
    return vec3(clamp(1.0 - t / max_distance, 0.0, 1.0));
}

// Exponential fog (Quilez, "Fog"): mix toward the fog colour by 1 - exp(-density t).
vec3 apply_fog(vec3 color, real t, vec3 fog_color, real density)
{
    real amount = 1.0 - exp(-density * t);
    return color + (fog_color - color) * amount;
}

// A solid colour for rays that hit nothing.
vec3 background_solid(vec3 direction, vec3 color)
{
    return color;
}

// The sky: bottom to top by a = (d.y + 1) / 2 ("Ray Tracing in One Weekend").
vec3 background_sky(vec3 direction, vec3 bottom, vec3 top)
{
    real a = (direction.y + 1.0) / 2.0;
    return bottom + (top - bottom) * a;
}
