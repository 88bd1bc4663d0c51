// Where each light comes from and how strongly: the GLSL twin of reference_cpu/lights.py.
// Point and spot lights fade as 1 / (K_c + K_l d + K_q d^2); a spot light also fades from
// its inner to its outer cone, linearly in cos(theta) (de Vries, LearnOpenGL, "Light
// casters"). A directional light is the same everywhere.

// 1 / (K_c + K_l d + K_q d^2); k = (K_c, K_l, K_q).
real attenuation(real distance, vec3 k)
{
    return 1.0 / (k.x + distance * (k.y + distance * k.z));
}

// 1 inside the inner cone, 0 outside the outer one, linear in cos(theta) between.
// cone = (cos outer, cos inner - cos outer).
real spot_cone(real cos_theta, vec2 cone)
{
    return clamp((cos_theta - cone.x) / cone.y, 0.0, 1.0);
}

// A directional light: to_light was normalised once, on the CPU.
LightSample light_directional(vec3 to_light, vec3 radiance)
{
    LightSample s;
    s.to_light = to_light;
    s.distance = MAX_DISTANCE;     // a shadow ray toward it stops at max_distance
    s.radiance = radiance;
    return s;
}

LightSample light_point(vec3 p, vec3 position, vec3 radiance, vec3 k)
{
    LightSample s;
    vec3 offset = position - p;
    s.distance = length(offset);
    s.to_light = offset / s.distance;
    s.radiance = attenuation(s.distance, k) * radiance;
    return s;
}

LightSample light_spot(vec3 p, vec3 position, vec3 radiance, vec3 k, vec3 axis, vec2 cone)
{
    LightSample s = light_point(p, position, radiance, k);
    s.radiance = spot_cone(-dot(s.to_light, axis), cone) * s.radiance;
    return s;
}
