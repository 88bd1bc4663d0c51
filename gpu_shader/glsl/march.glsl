// Sphere tracing (Hart 1996) and shadow rays: the GLSL twins of reference_cpu/march.py and
// reference_cpu/shadows.py. The rules are marchlab's contract (docs/scene-format.md):
//
//   t starts at `start` (0, or for a camera ray its tile's cone distance: glsl/cone.glsl);
//   the SDF leaves out the objects bounding-sphere culling drops and those whose bits are set
//   in `leave_out` (a hard shadow ray's own convex object; 0u for every other ray);
//   step i (1-based) evaluates d_i = |scene_sdf(o + t d)|; `steps` counts the evaluations;
//   if d_i < EPSILON the ray hits at the current t;
//   else t += d_i, and if t > limit the ray misses;
//   after MAX_STEPS evaluations without a hit the ray misses.
//
// `precise` keeps the compiler from fusing o + t d into one rounding (an FMA), which would
// move the point a little differently from the reference.
//
// The loop only breaks; what the last step found is read after it. llvmpipe runs every
// branch of a shader with lanes masked off, so each extra `return` in the loop body costs
// every step: this form drew the classroom scene about 8% faster than one that filled in
// the result inside the loop (benchmarks/bench_render.py, docs/performance.md).

Hit march(vec3 origin, vec3 direction, real start, real limit, uint leave_out)
{
    uint objects = ray_objects(origin, direction) & ~leave_out;    // culling, if on
    precise real t = start;
    real d = 0.0;
    int step;
    for (step = 1; step <= MAX_STEPS; step++) {
        precise vec3 p = origin + t * direction;
        d = abs(march_sdf(p, objects));
        if (d < EPSILON) {
            break;                  // hit at this t
        }
        t = t + d;
        if (t > limit) {
            break;                  // escaped
        }
    }
    Hit result;
    result.hit = d < EPSILON ? 1 : 0;
    result.t = d < EPSILON ? t : -1.0;
    result.steps = min(step, MAX_STEPS);    // the loop leaves step at MAX_STEPS + 1 when it ran out
    return result;
}

// 1 where the light is visible, 0 where the shadow ray hits something first. `origin` is
// the surface point already pushed off the surface along its normal; `own` is the bit of
// the convex object it lies on (own_object), which the ray cannot meet again: leaving it
// out spares the steps of creeping away from it (reference_cpu/shadows.py).
real hard_shadow(vec3 origin, vec3 to_light, real light_distance, uint own)
{
    real limit = min(light_distance, MAX_DISTANCE);
    return march(origin, to_light, 0.0, limit, own).hit == 1 ? 0.0 : 1.0;
}

// Penumbra estimate in [0, 1] (Quilez, "Soft shadows in raymarched SDFs", 2010): the same
// march, keeping the smallest k h / t seen after the first step; 0 if the ray hits.
real soft_shadow(vec3 origin, vec3 to_light, real light_distance)
{
    real limit = min(light_distance, MAX_DISTANCE);
    real visible = 1.0;
    precise real t = 0.0;
    for (int step = 1; step <= MAX_STEPS; step++) {
        precise vec3 p = origin + t * to_light;
        real h = abs(scene_sdf(p));
        if (step > 1) {
            visible = min(visible, PENUMBRA_K * h / t);
        }
        if (h < EPSILON) {
            return 0.0;
        }
        t = t + h;
        if (t > limit) {
            break;
        }
    }
    return clamp(visible, 0.0, 1.0);
}
