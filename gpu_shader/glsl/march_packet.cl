// Sphere tracing and shadow rays for packets of rays: the packet twin of glsl/march.glsl,
// which states the rules (and reference_cpu/march.py and reference_cpu/shadows.py, where
// they come from). glsl/packet.cl says what a packet is.
//
// Each function has the scalar one's name and does, lane by lane, the same operations in
// the same order, so every ray gets the same t, step count and visibility to the bit. What
// changes is the control flow: the LANES rays of a packet step together, so instead of
// leaving the loop a ray leaves the mask of lanes still marching, and from then on `?:`
// keeps its values as they were. The loop ends when no lane marches. A lane whose `live` is
// 0 (a pixel outside the image, a ray that has already stopped bouncing) is never marched.
// The whole program is compiled with FP_CONTRACT OFF, so no `precise` is needed here.

// The packet march. `Hit.hit` is a mask here: -1 (all bits set) on a hit, 0 otherwise, where
// the scalar march writes 1 and 0, so that it can select lane by lane. Lanes not live get hit
// 0, t -1 and steps 0. `steps` keeps the number of the last step a lane evaluated: the
// scalar min(step, MAX_STEPS), since a lane that runs out evaluated step MAX_STEPS last.
Hit march(vec3p origin, vec3p direction, packet limit, ipacket live)
{
    upacket objects = ray_objects(origin, direction);  // bounding-sphere culling, if on
    packet t = 0.0;
    packet d = 0.0;
    ipacket steps = 0;
    ipacket marching = live;                           // lanes still in the loop
    for (int step = 1; step <= MAX_STEPS && any(marching); step++) {
        vec3p p = add(origin, mul(t, direction));
        packet r = abs(march_sdf(p, objects));
        d = marching ? r : d;
        steps = marching ? step : steps;
        marching = marching & ~(r < EPSILON);          // hit at this t
        t = marching ? t + r : t;
        marching = marching & ~(t > limit);            // escaped
    }
    Hit result;
    result.hit = live & (d < EPSILON);
    result.t = result.hit ? t : -1.0;
    result.steps = steps;
    return result;
}

// 1 where the light is visible, 0 where the shadow ray hits something first; 1 in lanes
// that are not live.
packet hard_shadow(vec3p origin, vec3p to_light, packet light_distance, ipacket live)
{
    Hit hit = march(origin, to_light, min(light_distance, MAX_DISTANCE), live);
    return hit.hit ? (packet)(0.0) : (packet)(1.0);
}

// Penumbra estimate in [0, 1] (glsl/march.glsl, soft_shadow): the smallest k h / t seen
// after the first step, 0 in lanes that hit, 1 in lanes that are not live.
packet soft_shadow(vec3p origin, vec3p to_light, packet light_distance, ipacket live)
{
    packet limit = min(light_distance, MAX_DISTANCE);
    packet visible = 1.0;
    packet t = 0.0;
    ipacket blocked = 0;                               // the scalar `return 0.0`
    ipacket marching = live;
    for (int step = 1; step <= MAX_STEPS && any(marching); step++) {
        vec3p p = add(origin, mul(t, to_light));
        packet h = abs(scene_sdf(p));
        if (step > 1) {
            visible = marching ? min(visible, PENUMBRA_K * h / t) : visible;
        }
        blocked = blocked | (marching & (h < EPSILON));
        marching = marching & ~(h < EPSILON);
        t = marching ? t + h : t;
        marching = marching & ~(t > limit);
    }
    return blocked ? (packet)(0.0) : clamp(visible, 0.0, 1.0);
}
