// Glass: the GLSL twin of reference_cpu/refraction.py, function for function (that module
// says where each formula comes from). Snell's law in vector form, Fresnel's split between
// the reflected and the refracted ray, and Beer-Lambert's fading inside the solid.

// cos^2 of the refracted angle by Snell's law, eta = n1 / n2 (de Greve 2006, eq. 22);
// k <= 0 is total internal reflection.
real refract_k(real cos_i, real eta)
{
    return 1.0 - eta * eta * (1.0 - cos_i * cos_i);
}

// The refracted direction eta d + (eta cos_i - cos_t) n, n facing the incoming ray d.
vec3 refract_direction(vec3 d, vec3 n_facing, real cos_i, real eta, real cos_t)
{
    return eta * d + (eta * cos_i - cos_t) * n_facing;
}

// The reflected fraction of unpolarised light: the mean of the s- and p-polarised
// reflectances of Fresnel's equations (de Greve 2006, eqs. 25-27).
real fresnel_exact(real cos_i, real cos_t, real n1, real n2)
{
    real r_s = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    real r_p = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return (r_s * r_s + r_p * r_p) / 2.0;
}

// Schlick's approximation R0 + (1 - R0) (1 - c)^5 (Schlick 1994, eq. 24), c the cosine on
// the less dense side (de Greve 2006, eq. 29).
real fresnel_schlick(real cos_i, real cos_t, real n1, real n2)
{
    real r0 = (n1 - n2) / (n1 + n2);
    r0 = r0 * r0;
    real m = 1.0 - (n1 > n2 ? cos_t : cos_i);
    return r0 + (1.0 - r0) * (m * m * m * m * m);
}

// What is left of the light after `distance` inside a medium: exp(-sigma distance) per
// channel (the Beer-Lambert law).
vec3 beer_lambert(vec3 absorption, real distance)
{
    return vec3(exp(-(absorption.x * distance)), exp(-(absorption.y * distance)),
                exp(-(absorption.z * distance)));
}
