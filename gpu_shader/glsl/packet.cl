// Packets of rays: how the opencl backend runs fast on a CPU (docs/opencl-backend.md).
//
// One work-item traces LANES neighbouring pixels of a row together. Every value that differs
// from ray to ray is a vector with one lane per ray, and a 3-vector is three such vectors
// (structure of arrays: all the x, then all the y, then all the z). So each operation of the
// algorithm is one SIMD instruction for all the rays of the packet, as a GPU runs a group of
// fragments; PoCL compiles one work-item's code and does not vectorise across work-items
// when a kernel has a data-dependent loop (benchmarks/bench_opencl_packets.py measures the
// difference: 5-6x in float32).
//
//   packet   a real per ray          (float16 or double16)
//   ipacket  an integer per ray      (int16 or long16), also a mask: comparisons of packets
//            give -1 (all bits set) in the lanes where they hold and 0 elsewhere, and
//            `mask ? a : b` picks lane by lane
//   upacket  an unsigned integer per ray (path labels, culling bits)
//   vec3p    a 3-vector per ray
//
// Values that are the same for every ray (the parameters P, EPSILON, a sphere's radius) stay
// scalar `real` and `vec3`; OpenCL widens a scalar to every lane where it meets a packet.
//
// OpenCL C has no operator overloading, so vec3p arithmetic is spelled add, sub, mul, div,
// and the builtins dot, length, normalize, abs, max, clamp and reflect get vec3p overloads.
// Each lane computes exactly what the one-ray program computes, operation for operation and
// in the same order, so the two agree to the bit (tests/opencl/test_packet_*.py).

#define OVERLOAD __attribute__((overloadable))

typedef struct
{
    packet x, y, z;
} vec3p;

// A 3-vector and a real per ray, read as .xyz and .w like a vec4: a colour and its path
// label, or one row of each ray's material.
typedef struct
{
    vec3p xyz;
    packet w;
} vec4p;

// A 3-vector from its three packets of components.
vec3p pack3(packet x, packet y, packet z)
{
    vec3p v = {x, y, z};
    return v;
}

// The same 3-vector in every lane.
vec3p splat3(vec3 v)
{
    return pack3((packet)(v.x), (packet)(v.y), (packet)(v.z));
}

vec4p pack4(vec3p xyz, packet w)
{
    vec4p v = {xyz, w};
    return v;
}

// Lane by lane: a where the mask is set, b elsewhere.
vec3p OVERLOAD choose(ipacket mask, vec3p a, vec3p b)
{
    return pack3(mask ? a.x : b.x, mask ? a.y : b.y, mask ? a.z : b.z);
}

vec3p OVERLOAD add(vec3p a, vec3p b)
{
    return pack3(a.x + b.x, a.y + b.y, a.z + b.z);
}

vec3p OVERLOAD add(vec3p a, vec3 b)
{
    return pack3(a.x + b.x, a.y + b.y, a.z + b.z);
}

// a + b in every component, as GLSL adds a scalar to a vector.
vec3p OVERLOAD add(vec3p a, packet b)
{
    return pack3(a.x + b, a.y + b, a.z + b);
}

vec3p OVERLOAD sub(vec3p a, vec3p b)
{
    return pack3(a.x - b.x, a.y - b.y, a.z - b.z);
}

vec3p OVERLOAD sub(vec3p a, vec3 b)
{
    return pack3(a.x - b.x, a.y - b.y, a.z - b.z);
}

vec3p OVERLOAD sub(vec3 a, vec3p b)
{
    return pack3(a.x - b.x, a.y - b.y, a.z - b.z);
}

// s v, a packet or a scalar times a vector.
vec3p OVERLOAD mul(packet s, vec3p v)
{
    return pack3(s * v.x, s * v.y, s * v.z);
}

vec3p OVERLOAD mul(real s, vec3p v)
{
    return pack3(s * v.x, s * v.y, s * v.z);
}

vec3p OVERLOAD mul(packet s, vec3 v)
{
    return pack3(s * v.x, s * v.y, s * v.z);
}

// Component by component (colour times colour).
vec3p OVERLOAD mul(vec3p a, vec3p b)
{
    return pack3(a.x * b.x, a.y * b.y, a.z * b.z);
}

vec3p OVERLOAD mul(vec3p a, vec3 b)
{
    return pack3(a.x * b.x, a.y * b.y, a.z * b.z);
}

vec3p OVERLOAD div(vec3p v, packet s)
{
    return pack3(v.x / s, v.y / s, v.z / s);
}

vec3p OVERLOAD div(vec3p v, real s)
{
    return pack3(v.x / s, v.y / s, v.z / s);
}

vec3p OVERLOAD neg(vec3p v)
{
    return pack3(-v.x, -v.y, -v.z);
}

// (a.x b.x + a.y b.y) + a.z b.z, the order of scene_model.geometry.dot.
packet OVERLOAD dot(vec3p a, vec3p b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

packet OVERLOAD dot(vec3p a, vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

packet OVERLOAD length(vec3p v)
{
    return sqrt(dot(v, v));
}

// v / |v|, as the reference normalises (scene_model.geometry.normalize) and as the one-ray
// OpenCL program does (gpu_shader/dialects.py); NaN where v = 0.
vec3p OVERLOAD normalize(vec3p v)
{
    return div(v, sqrt(dot(v, v)));
}

vec3p OVERLOAD abs(vec3p v)
{
    return pack3(fabs(v.x), fabs(v.y), fabs(v.z));
}

vec3p OVERLOAD max(vec3p v, real m)
{
    return pack3(max(v.x, m), max(v.y, m), max(v.z, m));
}

vec3p OVERLOAD clamp(vec3p v, real low, real high)
{
    return pack3(clamp(v.x, low, high), clamp(v.y, low, high), clamp(v.z, low, high));
}

// i - 2 (n . i) n, GLSL's reflect (GLSL spec 8.5).
vec3p OVERLOAD reflect(vec3p i, vec3p n)
{
    return sub(i, mul(2.0 * dot(n, i), n));
}

// pow(x, y) lane by lane, taken a quarter packet (4 lanes) at a time. PoCL 3.1's pow of 8 or
// 16 doubles (its AVX-512 code) gets some lanes wrong, by orders of magnitude (pow(0.391,
// 91.2) gave 1.9e-10 instead of 6.6e-38), while its pow of 4 gives the scalar pow's bits in
// both precisions (tests/opencl/test_packet_shading.py).
#if LANES != 16
#error "power() splits a packet into four quarters: LANES must be 16"
#endif
packet power(packet x, packet y)
{
    return (packet)(pow(x.s0123, y.s0123), pow(x.s4567, y.s4567),
                    pow(x.s89ab, y.s89ab), pow(x.scdef, y.scdef));
}
