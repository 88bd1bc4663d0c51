// Packets of rays: how the opencl backend runs fast on a CPU (docs/opencl-backend.md).
//
// One work-item traces LANES neighbouring pixels of a row together. Every value that differs
// from ray to ray is a vector with one lane per ray, and a 3-vector is three such vectors
// (structure of arrays: all the x, then all the y, then all the z). So each operation of the
// algorithm is one SIMD instruction for all the rays of the packet, as a GPU runs a group of
// fragments; PoCL compiles one work-item's code and does not vectorise across work-items
// when a kernel has a data-dependent loop (docs/performance.md measures the difference).
//
//   packet   a real per ray          (float16 or double16)
//   ipacket  an integer per ray      (int16 or long16), also a mask: comparisons of packets
//            give -1 (all bits set) in the lanes where they hold and 0 elsewhere, and
//            `mask ? a : b` picks lane by lane
//   upacket  an unsigned integer per ray (path labels, culling bits)
//   vec2p, vec3p, vec4p   a 2-, 3- or 4-vector per ray
//
// Values that are the same for every ray (the parameters P, EPSILON, a sphere's radius) stay
// scalar `real` and `vec3`; OpenCL widens a scalar to every lane where it meets a packet.
//
// The packet program is derived from the one-ray program (gpu_shader/vectorise.py), which
// calls what this file defines. OpenCL C has no operator overloading, so vec3p arithmetic
// is spelled add, sub, mul, div and neg, and the builtins dot, length, normalize, abs, max,
// clamp and reflect get vec3p overloads. Each lane computes exactly what the one-ray program
// computes, operation for operation and in the same order, so the two agree to the bit
// (tests/opencl/test_packet_*.py).

#define OVERLOAD __attribute__((overloadable))

typedef struct
{
    packet x, y;
} vec2p;

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

// --- Building vectors ---------------------------------------------------------------------

// A vector from its packets of components (GLSL's vec2(x, y), vec3(x, y, z), vec4(v, w)).
vec2p pack2(packet x, packet y)
{
    vec2p v = {x, y};
    return v;
}

vec3p pack3(packet x, packet y, packet z)
{
    vec3p v = {x, y, z};
    return v;
}

vec4p pack4(vec3p xyz, packet w)
{
    vec4p v = {xyz, w};
    return v;
}

// The same vector in every lane.
vec2p OVERLOAD splat2(vec2 v)
{
    return pack2((packet)(v.x), (packet)(v.y));
}

vec3p OVERLOAD splat3(vec3 v)
{
    return pack3((packet)(v.x), (packet)(v.y), (packet)(v.z));
}

vec4p OVERLOAD splat4(vec4 v)
{
    return pack4(splat3(v.xyz), (packet)(v.w));
}

// Each lane's x in every component (GLSL's vec3(x)).
vec2p OVERLOAD splat2(packet x)
{
    return pack2(x, x);
}

vec3p OVERLOAD splat3(packet x)
{
    return pack3(x, x, x);
}

vec4p OVERLOAD splat4(packet x)
{
    return pack4(pack3(x, x, x), x);
}

// Lane by lane: a where the mask is set, b elsewhere.
vec2p OVERLOAD choose(ipacket mask, vec2p a, vec2p b)
{
    return pack2(mask ? a.x : b.x, mask ? a.y : b.y);
}

vec3p OVERLOAD choose(ipacket mask, vec3p a, vec3p b)
{
    return pack3(mask ? a.x : b.x, mask ? a.y : b.y, mask ? a.z : b.z);
}

vec4p OVERLOAD choose(ipacket mask, vec4p a, vec4p b)
{
    return pack4(choose(mask, a.xyz, b.xyz), mask ? a.w : b.w);
}

// --- Arithmetic: component by component, a scalar meeting every component (as in GLSL) ---

vec3p OVERLOAD add(vec3p a, vec3p b) { return pack3(a.x + b.x, a.y + b.y, a.z + b.z); }
vec3p OVERLOAD add(vec3p a, vec3 b) { return pack3(a.x + b.x, a.y + b.y, a.z + b.z); }
vec3p OVERLOAD add(vec3 a, vec3p b) { return pack3(a.x + b.x, a.y + b.y, a.z + b.z); }
vec3p OVERLOAD add(vec3p a, packet b) { return pack3(a.x + b, a.y + b, a.z + b); }

vec3p OVERLOAD sub(vec3p a, vec3p b) { return pack3(a.x - b.x, a.y - b.y, a.z - b.z); }
vec3p OVERLOAD sub(vec3p a, vec3 b) { return pack3(a.x - b.x, a.y - b.y, a.z - b.z); }
vec3p OVERLOAD sub(vec3 a, vec3p b) { return pack3(a.x - b.x, a.y - b.y, a.z - b.z); }
vec3p OVERLOAD sub(vec3p a, packet b) { return pack3(a.x - b, a.y - b, a.z - b); }

vec3p OVERLOAD mul(vec3p a, vec3p b) { return pack3(a.x * b.x, a.y * b.y, a.z * b.z); }
vec3p OVERLOAD mul(vec3p a, vec3 b) { return pack3(a.x * b.x, a.y * b.y, a.z * b.z); }
vec3p OVERLOAD mul(vec3 a, vec3p b) { return pack3(a.x * b.x, a.y * b.y, a.z * b.z); }
vec3p OVERLOAD mul(packet s, vec3p v) { return pack3(s * v.x, s * v.y, s * v.z); }
vec3p OVERLOAD mul(vec3p v, packet s) { return pack3(v.x * s, v.y * s, v.z * s); }
vec3p OVERLOAD mul(real s, vec3p v) { return pack3(s * v.x, s * v.y, s * v.z); }
vec3p OVERLOAD mul(vec3p v, real s) { return pack3(v.x * s, v.y * s, v.z * s); }
vec3p OVERLOAD mul(packet s, vec3 v) { return pack3(s * v.x, s * v.y, s * v.z); }
vec3p OVERLOAD mul(vec3 v, packet s) { return pack3(v.x * s, v.y * s, v.z * s); }

vec3p OVERLOAD div(vec3p a, vec3p b) { return pack3(a.x / b.x, a.y / b.y, a.z / b.z); }
vec3p OVERLOAD div(vec3p v, packet s) { return pack3(v.x / s, v.y / s, v.z / s); }
vec3p OVERLOAD div(vec3p v, real s) { return pack3(v.x / s, v.y / s, v.z / s); }

vec3p OVERLOAD neg(vec3p v) { return pack3(-v.x, -v.y, -v.z); }

// --- Builtins over 3-vectors --------------------------------------------------------------

// (a.x b.x + a.y b.y) + a.z b.z, the order of scene_model.geometry.dot.
packet OVERLOAD dot(vec3p a, vec3p b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

packet OVERLOAD dot(vec3p a, vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

packet OVERLOAD dot(vec3 a, vec3p b)
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

vec3p OVERLOAD min(vec3p v, real m)
{
    return pack3(min(v.x, m), min(v.y, m), min(v.z, m));
}

vec3p OVERLOAD clamp(vec3p v, real low, real high)
{
    return pack3(clamp(v.x, low, high), clamp(v.y, low, high), clamp(v.z, low, high));
}

vec3p OVERLOAD floor(vec3p v)
{
    return pack3(floor(v.x), floor(v.y), floor(v.z));
}

// i - 2 (n . i) n, GLSL's reflect (GLSL spec 8.5).
vec3p OVERLOAD reflect(vec3p i, vec3p n)
{
    return sub(i, mul(2.0 * dot(n, i), n));
}

// --- Reading the parameter rows per lane ----------------------------------------------------

// Row index[k] of the parameter table in lane k: a gather, one load per lane (an object's
// material, say, where each ray may have hit another object). Lanes whose index lies outside
// the table (a ray that hit nothing has object id -1) read the nearest row, which they never
// use: no lane reads outside the buffer.
vec4p gather_rows(__global const vec4* rows, ipacket index, int count)
{
    ipacket row = clamp(index, (ipacket)(0), (ipacket)(count - 1));
    real x[LANES], y[LANES], z[LANES], w[LANES];
    for (int k = 0; k < LANES; k++) {
        vec4 m = rows[row[k]];
        x[k] = m.x;
        y[k] = m.y;
        z[k] = m.z;
        w[k] = m.w;
    }
    vec3p xyz = pack3(vload_packet(0, x), vload_packet(0, y), vload_packet(0, z));
    return pack4(xyz, vload_packet(0, w));
}

// gather(index): row index of the program's parameters P, in every lane (PARAMETER_ROWS is
// the number of rows, written by the generator).
#define gather(index) gather_rows(&U[0], (index), PARAMETER_ROWS)

// pow(x, y) of a packet. PoCL 3.1's pow of 8 or 16 doubles (its AVX-512 code) gets some
// lanes wrong, by orders of magnitude (pow(0.391, 91.2) gave 1.9e-10 instead of 6.6e-38),
// while its pow of 4 gives the scalar pow's bits in both precisions
// (tests/opencl/test_packet_shading.py).
//
// In float64 that pow takes about 100 ns a value, seven times PoCL's exp2 and log2 together:
// a tenth of the classroom's frame went to its two lights' highlights. There, for x >= 0 (the
// only callers: the specular term's max(R.V, 0) and the triplanar blend's |n|), x^y is taken
// as 2^(y log2 x), within about y |log2 x| ulps of pow (relative 1e-13 for any colour above
// 1e-300), far inside the float32 colour a Frame keeps. At x = 0 it is 2^-inf = 0 for y > 0,
// as pow is, and y = 0 gives 1, as pow(0, 0) does. In float32 that error would be about an
// ulp of the colour, so float32 keeps pow, and the one-ray program's bits.
#if LANES != 16
#error "power() splits a packet into four quarters: LANES must be 16"
#endif
packet power(packet x, packet y)
{
#if PACKET_DOUBLE
    return select(exp2(y * log2(x)), (packet)(1.0), y == (packet)(0.0));
#else
    return (packet)(pow(x.s0123, y.s0123), pow(x.s4567, y.s4567),
                    pow(x.s89ab, y.s89ab), pow(x.scdef, y.scdef));
#endif
}
