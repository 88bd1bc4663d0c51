// Shadow rays toward two lights marched together, for the one-ray programs (GLSL and the
// one-ray OpenCL kernel). glsl/march.glsl states the marching rules. The packet program is
// derived from a one-ray program without pairs: its loop already steps many rays at once.

// hard_shadow for two lights at once (a point lit by two lights): rays a and b leave the
// same origin and are marched in one loop, a step of each per iteration, by march's rules;
// a ray whose `need` is false is not marched and counts as visible. The answers are those of
// two hard_shadow calls (`own` as theirs), but the two chains of dependent arithmetic
// overlap, and a block of pixels waits once for its slowest pair instead of once per light:
// 8% of the classroom scene's draw on llvmpipe (docs/performance.md).
vec2 hard_shadow_pair(vec3 origin, vec3 to_light_a, real distance_a, bool need_a,
                      vec3 to_light_b, real distance_b, bool need_b, uint own)
{
    uint objects_a = ray_objects(origin, to_light_a) & ~own;
    uint objects_b = ray_objects(origin, to_light_b) & ~own;
    real limit_a = min(distance_a, MAX_DISTANCE);
    real limit_b = min(distance_b, MAX_DISTANCE);
    precise real t_a = 0.0;
    precise real t_b = 0.0;
    bool going_a = need_a;
    bool going_b = need_b;
    bool hit_a = false;
    bool hit_b = false;
    for (int step = 1; step <= MAX_STEPS; step++) {
        if (going_a) {
            precise vec3 p = origin + t_a * to_light_a;
            real d = abs(march_sdf(p, objects_a));
            if (d < EPSILON) {
                hit_a = true;
                going_a = false;
            } else {
                t_a = t_a + d;
                going_a = !(t_a > limit_a);
            }
        }
        if (going_b) {
            precise vec3 p = origin + t_b * to_light_b;
            real d = abs(march_sdf(p, objects_b));
            if (d < EPSILON) {
                hit_b = true;
                going_b = false;
            } else {
                t_b = t_b + d;
                going_b = !(t_b > limit_b);
            }
        }
        if (!(going_a || going_b)) {
            break;
        }
    }
    return vec2(hit_a ? 0.0 : 1.0, hit_b ? 0.0 : 1.0);
}
