// Over-relaxed sphere tracing: the GLSL twin of reference_cpu/relaxation.py, which states
// the rules and where they come from (Keinert et al. 2014; Bán & Valasek 2023). The
// generator defines RELAXATION_AUTO: 0 for a fixed factor OMEGA, 1 for a factor taken from
// the field's slope along the ray. Hit, miss and step counting are those of the plain march
// (glsl/march.glsl); only the length of a step changes, and a step that may have jumped
// over a surface is taken back.

Hit march(vec3 origin, vec3 direction, real start, real limit, uint leave_out)
{
    uint objects = ray_objects(origin, direction) & ~leave_out;
    precise real t = start;
    real t_prev = 0.0;          // the last point that was checked, and its distance
    real r_prev = 0.0;
    bool inside_prev = false;   // the distance at t_prev was negative
    real last_step = 0.0;       // t - t_prev
#if RELAXATION_AUTO
    real omega = 1.0;           // 2 / (1 - slope), from the averaged slope
    real slope = -1.0;
#else
    real omega = OMEGA;         // until the first step back, then 1
#endif
    real r = 0.0;
    int step;
    for (step = 1; step <= MAX_STEPS; step++) {
        precise vec3 p = origin + t * direction;
        real f = march_sdf(p, objects);
        r = abs(f);
        if (r_prev + r < last_step || (last_step > r_prev && (f < 0.0) != inside_prev)) {
            // The empty spheres around t_prev and t leave a gap where a surface may hide,
            // or the relaxed step crossed one: go back to the plain step from t_prev. This
            // point decides nothing.
            t = t_prev + r_prev;
            last_step = r_prev;
            omega = 1.0;
#if RELAXATION_AUTO
            slope = -1.0;
#endif
            continue;
        }
        if (r < EPSILON) {
            break;                  // hit at this t
        }
        if (t + r > limit) {
            break;                  // escaped: even the plain step passes the limit
        }
#if RELAXATION_AUTO
        if (last_step > 0.0) {
            slope = slope + ((r - r_prev) / last_step - slope) * SLOPE_WEIGHT;
            omega = 2.0 / (1.0 - clamp(slope, -1.0, 0.0));
        }
#endif
        t_prev = t;
        r_prev = r;
        inside_prev = f < 0.0;
        last_step = omega * r;
        t = t + last_step;
    }
    Hit result;
    // A ray that ran out of steps left the loop with step = MAX_STEPS + 1.
    result.hit = step <= MAX_STEPS && r < EPSILON ? 1 : 0;
    result.t = result.hit == 1 ? t : -1.0;
    result.steps = min(step, MAX_STEPS);
    return result;
}
