// Over-relaxed sphere tracing for packets of rays: the packet twin of glsl/relaxed.glsl,
// which states the rules (reference_cpu/relaxation.py derives them). glsl/packet.cl says
// what a packet is; glsl/march_packet.cl how a loop of the scalar program becomes a loop
// over masks of lanes.
//
// The scalar loop has three ways on from a step: take it back (`continue`), stop (hit or
// escape, `break`) or move on. Here each is a mask of lanes, `back`, and then among the
// other marching lanes `hit_now` and `escaped`, and `ahead` for the rest; every variable is
// updated with `?:` only in the lanes whose way updates it in the scalar loop, so each lane
// goes through exactly the scalar sequence of values and steps.

// The relaxed packet march; the same signature and results as the plain packet march of
// glsl/march_packet.cl (`Hit.hit` a mask, -1 on a hit, 0 otherwise; lanes not live get
// hit 0, t -1, steps 0). `steps` keeps the number of the last step a lane evaluated, which
// is the scalar min(step, MAX_STEPS) whether the lane broke out or ran out of steps.
Hit march(vec3p origin, vec3p direction, packet limit, ipacket live)
{
    upacket objects = ray_objects(origin, direction);
    packet t = 0.0;
    packet t_prev = 0.0;        // the last point that was checked, and its distance
    packet r_prev = 0.0;
    ipacket inside_prev = 0;    // the distance at t_prev was negative (a mask)
    packet last_step = 0.0;     // t - t_prev
#if RELAXATION_AUTO
    packet omega = 1.0;         // 2 / (1 - slope), from the averaged slope
    packet slope = -1.0;
#else
    packet omega = OMEGA;       // until the first step back, then 1
#endif
    ipacket steps = 0;
    ipacket hit = 0;
    ipacket marching = live;    // lanes still in the loop
    for (int step = 1; step <= MAX_STEPS && any(marching); step++) {
        vec3p p = add(origin, mul(t, direction));
        packet f = march_sdf(p, objects);
        packet r = abs(f);
        steps = marching ? step : steps;
        // The scalar `continue`: a gap where a surface may hide, or a crossed surface. These
        // lanes go back to the plain step from t_prev; their point decides nothing.
        ipacket back = marching
            & ((r_prev + r < last_step) | ((last_step > r_prev) & ((f < 0.0) != inside_prev)));
        t = back ? t_prev + r_prev : t;
        last_step = back ? r_prev : last_step;
        omega = back ? 1.0 : omega;
#if RELAXATION_AUTO
        slope = back ? -1.0 : slope;
#endif
        // The other marching lanes check their point as the plain march does: a hit at this
        // t, an escape where even the plain step passes the limit, else a step ahead.
        ipacket deciding = marching & ~back;
        ipacket hit_now = deciding & (r < EPSILON);
        ipacket escaped = deciding & ~hit_now & (t + r > limit);
        ipacket ahead = deciding & ~hit_now & ~escaped;
        hit = hit | hit_now;
        marching = marching & ~hit_now & ~escaped;
#if RELAXATION_AUTO
        ipacket measured = ahead & (last_step > 0.0);
        slope = measured ? slope + ((r - r_prev) / last_step - slope) * SLOPE_WEIGHT : slope;
        omega = measured ? 2.0 / (1.0 - clamp(slope, -1.0, 0.0)) : omega;
#endif
        t_prev = ahead ? t : t_prev;
        r_prev = ahead ? r : r_prev;
        inside_prev = ahead ? (f < 0.0) : inside_prev;
        last_step = ahead ? omega * r : last_step;
        t = ahead ? t + last_step : t;
    }
    Hit result;
    result.hit = hit;
    result.t = result.hit ? t : -1.0;
    result.steps = steps;
    return result;
}
