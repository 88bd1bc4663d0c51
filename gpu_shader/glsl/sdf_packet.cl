// Signed distance functions and the operators that combine them, for packets of rays: the
// packet twin of sdf.glsl, function for function and name for name. Formulas from Inigo
// Quilez, "Distance functions" (https://iquilezles.org/articles/distfunctions/).
//
// Each function computes, lane by lane, exactly the operations of its twin in sdf.glsl in the
// same order, so the two agree to the bit (tests/opencl/test_packet_sdf.py). What differs from
// ray to ray (the query point, distances) is a packet or a vec3p; what a scene fixes (radii,
// half-extents, offsets) stays a scalar `real` or `vec3`. OpenCL C has no operator
// overloading, so `p - a` is written sub(p, a) and `h * ba` mul(h, ba) (glsl/packet.cl).
// Like sdf.glsl, this file is a library: the generator copies only the functions a scene uses.

packet length2(packet x, packet y)
{
    return sqrt(x * x + y * y);
}

// --- Primitives, centred on the origin --------------------------------------------------

// Sphere: distance to the centre minus the radius.
packet sdf_sphere(vec3p p, real radius)
{
    return length(p) - radius;
}

// Box with half-extents b: outside, the length of q's positive part; inside, its largest
// (least negative) component.
packet sdf_box(vec3p p, vec3 b)
{
    vec3p q = sub(abs(p), b);
    packet outside = length(max(q, 0.0));
    packet inside = min(max(q.x, max(q.y, q.z)), 0.0);
    return outside + inside;
}

// The box shrunk by `radius` on every side, then inflated by `radius`; the shrunk box is the
// same for every ray, so it stays scalar.
packet sdf_round_box(vec3p p, vec3 b, real radius)
{
    return sdf_box(p, b - radius) - radius;
}

// Half-space normal . x <= offset. The unit normal is a parameter, the same for every ray.
packet sdf_plane(vec3p p, vec3 normal, real offset)
{
    vec3 n = normal / sqrt(dot(normal, normal));
    return dot(p, n) - offset;
}

// Torus around the y axis: distance to the centre circle, minus the tube radius.
packet sdf_torus(vec3p p, real major_radius, real minor_radius)
{
    packet ring = length2(p.x, p.z) - major_radius;
    return length2(ring, p.y) - minor_radius;
}

// Cylinder along y: a 2-D box in the (distance from axis, height) plane.
packet sdf_capped_cylinder(vec3p p, real radius, real half_height)
{
    packet dx = length2(p.x, p.z) - radius;
    packet dy = abs(p.y) - half_height;
    packet outside = length2(max(dx, 0.0), max(dy, 0.0));
    packet inside = min(max(dx, dy), 0.0);
    return outside + inside;
}

// Distance to the segment a-b (closest point by clamped projection), minus the radius. The
// segment ba is a parameter; only the projection h differs from ray to ray.
packet sdf_capsule(vec3p p, vec3 a, vec3 b, real radius)
{
    vec3p pa = sub(p, a);
    vec3 ba = b - a;
    packet h = clamp(dot(pa, ba) / dot(ba, ba), 0.0, 1.0);
    return length(sub(pa, mul(h, ba))) - radius;
}

// Solid cone along y, base disc at y = 0, apex at y = height: Quilez's exact cone (apex at
// the origin) evaluated at p - (0, height, 0). See sdf.glsl and reference_cpu/sdf.py for the
// derivation; the cone's slant (qx, qy) is the same for every ray.
packet sdf_cone(vec3p p, real radius, real height)
{
    packet wx = length2(p.x, p.z);
    packet wy = p.y - height;
    real qx = radius;
    real qy = -height;
    packet s = clamp((wx * qx + wy * qy) / (qx * qx + qy * qy), 0.0, 1.0);
    packet ax = wx - qx * s;
    packet ay = wy - qy * s;
    packet bx = wx - qx * clamp(wx / qx, 0.0, 1.0);
    packet by = wy - qy;
    packet d2 = min(ax * ax + ay * ay, bx * bx + by * by);
    packet inside = sign(max(-(wx * qy - wy * qx), -(wy - qy)));
    return sqrt(d2) * inside;
}

// --- Combining distances (CSG) ------------------------------------------------------------

// Points inside either shape: the nearer distance. Unions, intersections and subtractions
// pick by comparison rather than min/max, whose NaN rules cost llvmpipe two more
// instructions each (6% of the classroom scene's draw); a distance is never NaN.
packet op_union(packet d1, packet d2)
{
    return d1 < d2 ? d1 : d2;
}

// Points inside both shapes: the farther distance.
packet op_intersection(packet d1, packet d2)
{
    return d1 > d2 ? d1 : d2;
}

// Points inside shape 1 and outside shape 2.
packet op_subtraction(packet d1, packet d2)
{
    return d1 > -d2 ? d1 : -d2;
}

// Quilez's polynomial smooth minimum: h blends from shape 2 (h = 0) to shape 1 (h = 1) and
// k h (1 - h) digs the fillet.
packet op_smooth_union(packet d1, packet d2, real k)
{
    packet h = clamp(0.5 + 0.5 * (d2 - d1) / k, 0.0, 1.0);
    return d2 + (d1 - d2) * h - k * h * (1.0 - h);
}

packet op_smooth_subtraction(packet d1, packet d2, real k)
{
    packet h = clamp(0.5 - 0.5 * (d1 + d2) / k, 0.0, 1.0);
    return d1 + (-d2 - d1) * h + k * h * (1.0 - h);
}

packet op_smooth_intersection(packet d1, packet d2, real k)
{
    packet h = clamp(0.5 - 0.5 * (d2 - d1) / k, 0.0, 1.0);
    return d2 + (d1 - d2) * h + k * h * (1.0 - h);
}

// --- Moving the query point (transforms) -----------------------------------------------

vec3p op_translate(vec3p p, vec3 offset)
{
    return sub(p, offset);
}

// R^T p, with R given by its columns: component j is p . (column j).
vec3p op_rotate(vec3p p, vec3 column0, vec3 column1, vec3 column2)
{
    return pack3(dot(p, column0), dot(p, column1), dot(p, column2));
}

vec3p op_scale(vec3p p, real factor)
{
    return div(p, factor);
}

// One axis of op_repeat: fold x into the cell of size `period` around 0 (period 0: leave x).
// The period is a parameter, so the choice is the same for every lane. floor(x + 0.5)
// rounds halves up, as in sdf.glsl.
packet repeat_axis(packet x, real period)
{
    return period > 0.0 ? x - period * floor(x / period + 0.5) : x;
}

vec3p op_repeat(vec3p p, vec3 period)
{
    return pack3(repeat_axis(p.x, period.x), repeat_axis(p.y, period.y),
                 repeat_axis(p.z, period.z));
}

// One axis of op_repeat_limited: only cells -count..count hold a copy.
packet repeat_axis_limited(packet x, real period, real count)
{
    return period > 0.0 ? x - period * clamp(floor(x / period + 0.5), -count, count) : x;
}

vec3p op_repeat_limited(vec3p p, vec3 period, vec3 count)
{
    return pack3(repeat_axis_limited(p.x, period.x, count.x),
                 repeat_axis_limited(p.y, period.y, count.y),
                 repeat_axis_limited(p.z, period.z, count.z));
}
