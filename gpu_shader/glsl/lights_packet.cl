// Where each light comes from and how strongly, for packets of rays: the packet twin of
// glsl/lights.glsl (and so of reference_cpu/lights.py). glsl/packet.cl says what a packet
// is. The lights themselves are parameters, the same for every ray (scalar vec3); the
// shaded point, and so the distance and direction to a light, differ from lane to lane.
// Each function does, lane by lane, the scalar one's operations in the same order.

// 1 / (K_c + K_l d + K_q d^2); k = (K_c, K_l, K_q). The scalar text, on a packet of d.
packet attenuation(packet distance, vec3 k)
{
    return 1.0 / (k.x + distance * (k.y + distance * k.z));
}

// 1 inside the inner cone, 0 outside the outer one, linear in cos(theta) between.
// cone = (cos outer, cos inner - cos outer).
packet spot_cone(packet cos_theta, vec2 cone)
{
    return clamp((cos_theta - cone.x) / cone.y, 0.0, 1.0);
}

// A directional light: the same direction and radiance in every lane.
LightSample light_directional(vec3 to_light, vec3 radiance)
{
    LightSample s;
    s.to_light = splat3(to_light);
    s.distance = MAX_DISTANCE;     // a shadow ray toward it stops at max_distance
    s.radiance = splat3(radiance);
    return s;
}

LightSample light_point(vec3p p, vec3 position, vec3 radiance, vec3 k)
{
    LightSample s;
    vec3p offset = sub(position, p);
    s.distance = length(offset);
    s.to_light = div(offset, s.distance);
    s.radiance = mul(attenuation(s.distance, k), radiance);
    return s;
}

LightSample light_spot(vec3p p, vec3 position, vec3 radiance, vec3 k, vec3 axis, vec2 cone)
{
    LightSample s = light_point(p, position, radiance, k);
    s.radiance = mul(spot_cone(-dot(s.to_light, axis), cone), s.radiance);
    return s;
}
