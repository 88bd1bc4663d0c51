// Three ways to march the classroom scene's primary rays on a CPU OpenCL device, for
// benchmarks/bench_opencl_packets.py (issue 4: why the scalar kernel is slow and what would
// make it fast). Appended to the generated program's first part (types, parameters,
// scene_sdf, camera_ray), so all three use the generated code where they can. The rules are
// those of glsl/march.glsl; every kernel writes t (-1 on a miss) and the step count.

// 1. One ray per work-item: the generated kernel's march. PoCL runs it as scalar code, one
//    dependent chain per step (o + t d, p - c, dot, sqrt, min, add).
__kernel void one_ray(PARAMETERS, __global real* restrict out_t, __global int* restrict out_steps)
{
    int column = get_global_id(0), row = get_global_id(1);
    vec3 direction = camera_ray(P, (real)(column) + 0.5, (real)(row) + 0.5);
    real t = 0.0, d = 0.0;
    int step;
    for (step = 1; step <= MAX_STEPS; step++) {
        vec3 p = CAMERA_POSITION + t * direction;
        d = fabs(scene_sdf(P, p));
        if (d < EPSILON) break;
        t = t + d;
        if (t > MAX_DISTANCE) break;
    }
    int pixel = row * (int)(IMAGE_WIDTH) + column;
    out_t[pixel] = d < EPSILON ? t : -1.0;
    out_steps[pixel] = min(step, MAX_STEPS);
}

// 2. LANES rays per work-item, stepped in lock-step with the scalar scene_sdf: independent
//    chains the CPU can overlap, still scalar instructions.
__kernel void interleaved(PARAMETERS, __global real* restrict out_t, __global int* restrict out_steps)
{
    int first = get_global_id(0) * LANES, row = get_global_id(1);
    vec3 direction[LANES];
    real t[LANES], d[LANES];
    int steps[LANES], live[LANES];
    for (int k = 0; k < LANES; k++) {
        direction[k] = camera_ray(P, (real)(first + k) + 0.5, (real)(row) + 0.5);
        t[k] = 0.0; d[k] = 0.0; steps[k] = 0; live[k] = 1;
    }
    for (int step = 1; step <= MAX_STEPS; step++) {
        int any = 0;
        #pragma unroll
        for (int k = 0; k < LANES; k++) {
            if (live[k]) {
                vec3 p = CAMERA_POSITION + t[k] * direction[k];
                d[k] = fabs(scene_sdf(P, p));
                steps[k] = step;
                if (d[k] < EPSILON) {
                    live[k] = 0;
                } else {
                    t[k] = t[k] + d[k];
                    live[k] = t[k] <= MAX_DISTANCE;
                }
            }
            any |= live[k];
        }
        if (!any) break;
    }
    for (int k = 0; k < LANES; k++) {
        int pixel = row * (int)(IMAGE_WIDTH) + first + k;
        out_t[pixel] = d[k] < EPSILON ? t[k] : -1.0;
        out_steps[pixel] = steps[k];
    }
}

// 3. LANES rays per work-item as one packet: every value is a vector with one lane per ray
//    (structure of arrays, x, y and z apart), so each operation is one SIMD instruction for
//    all the rays, as llvmpipe runs a fragment shader. The SDF has to be written for packets:
//    here by hand for the classroom tree (a plane and three translated spheres, the parameter
//    rows of the generated scene_sdf, checked by the benchmark).
#define packet CONCAT(SCALAR, LANES)
#define ipacket CONCAT(INT_OF_REAL, LANES)   // the integer type of the same width, for masks
#define CONCAT(a, b) CONCAT_(a, b)
#define CONCAT_(a, b) a##b
#define vload_packet CONCAT(vload, LANES)
#define vstore_packet CONCAT(vstore, LANES)

packet sdf_sphere_packet(packet x, packet y, packet z, real radius)
{
    return sqrt(x * x + y * y + z * z) - radius;
}

packet scene_sdf_packet(PARAMETERS, packet x, packet y, packet z)
{
    vec3 n = P[9].xyz / sqrt(dot(P[9].xyz, P[9].xyz));
    packet d = x * n.x + y * n.y + z * n.z - P[9].w;
    d = fmin(d, sdf_sphere_packet(x - P[10].x, y - P[10].y, z - P[10].z, P[11].x));
    d = fmin(d, sdf_sphere_packet(x - P[12].x, y - P[12].y, z - P[12].z, P[13].x));
    d = fmin(d, sdf_sphere_packet(x - P[14].x, y - P[14].y, z - P[14].z, P[15].x));
    return d;
}

__kernel void packets(PARAMETERS, __global real* restrict out_t, __global int* restrict out_steps)
{
    int first = get_global_id(0) * LANES, row = get_global_id(1);
    real dx[LANES], dy[LANES], dz[LANES];
    for (int k = 0; k < LANES; k++) {
        vec3 direction = camera_ray(P, (real)(first + k) + 0.5, (real)(row) + 0.5);
        dx[k] = direction.x; dy[k] = direction.y; dz[k] = direction.z;
    }
    packet x = vload_packet(0, dx), y = vload_packet(0, dy), z = vload_packet(0, dz);
    vec3 o = CAMERA_POSITION;
    packet t = 0.0, d = 0.0;
    ipacket steps = 0, live = -1;          // -1: all bits set, OpenCL's vector "true"
    for (int step = 1; step <= MAX_STEPS; step++) {
        packet r = fabs(scene_sdf_packet(P, o.x + t * x, o.y + t * y, o.z + t * z));
        d = select(d, r, live);
        steps = select(steps, (ipacket)(step), live);
        ipacket go_on = live & ~(r < EPSILON);
        packet t_next = t + r;
        t = select(t, t_next, go_on);
        live = go_on & (t_next <= MAX_DISTANCE);
        if (!any(live)) break;
    }
    int pixel = row * (int)(IMAGE_WIDTH) + first;
    vstore_packet(select((packet)(-1.0), t, d < EPSILON), 0, out_t + pixel);
    vstore_packet(CONCAT(convert_int, LANES)(steps), 0, out_steps + pixel);
}
