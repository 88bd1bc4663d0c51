// Signed distance functions and the operators that combine them: the GLSL twins of
// reference_cpu/sdf.py, function for function and name for name. Formulas from Inigo Quilez,
// "Distance functions" (https://iquilezles.org/articles/distfunctions/).
//
// This file is a library: the generator copies only the functions a scene uses (and the
// functions those call). Types are `real` and `vec3` so that a second C-like dialect can
// give them its own meaning.

real length2(real x, real y)
{
    return sqrt(x * x + y * y);
}

// --- Primitives, centred on the origin --------------------------------------------------

// Sphere: distance to the centre minus the radius.
real sdf_sphere(vec3 p, real radius)
{
    return length(p) - radius;
}

// Box with half-extents b: outside, the length of q's positive part; inside, its largest
// (least negative) component.
real sdf_box(vec3 p, vec3 b)
{
    vec3 q = abs(p) - b;
    real outside = length(max(q, 0.0));
    real inside = min(max(q.x, max(q.y, q.z)), 0.0);
    return outside + inside;
}

// The box shrunk by `radius` on every side, then inflated by `radius`.
real sdf_round_box(vec3 p, vec3 b, real radius)
{
    return sdf_box(p, b - radius) - radius;
}

// Half-space normal . x <= offset.
real sdf_plane(vec3 p, vec3 normal, real offset)
{
    vec3 n = normal / sqrt(dot(normal, normal));
    return dot(p, n) - offset;
}

// Torus around the y axis: distance to the centre circle, minus the tube radius.
real sdf_torus(vec3 p, real major_radius, real minor_radius)
{
    real ring = length2(p.x, p.z) - major_radius;
    return length2(ring, p.y) - minor_radius;
}

// Cylinder along y: a 2-D box in the (distance from axis, height) plane.
real sdf_capped_cylinder(vec3 p, real radius, real half_height)
{
    real dx = length2(p.x, p.z) - radius;
    real dy = abs(p.y) - half_height;
    real outside = length2(max(dx, 0.0), max(dy, 0.0));
    real inside = min(max(dx, dy), 0.0);
    return outside + inside;
}

// Distance to the segment a-b (closest point by clamped projection), minus the radius.
real sdf_capsule(vec3 p, vec3 a, vec3 b, real radius)
{
    vec3 pa = p - a;
    vec3 ba = b - a;
    real h = clamp(dot(pa, ba) / dot(ba, ba), 0.0, 1.0);
    return length(pa - h * ba) - radius;
}

// Solid cone along y, base disc at y = 0, apex at y = height: Quilez's exact cone (apex at
// the origin) evaluated at p - (0, height, 0). See reference_cpu/sdf.py for the derivation.
real sdf_cone(vec3 p, real radius, real height)
{
    real wx = length2(p.x, p.z);
    real wy = p.y - height;
    real qx = radius;
    real qy = -height;
    real s = clamp((wx * qx + wy * qy) / (qx * qx + qy * qy), 0.0, 1.0);
    real ax = wx - qx * s;
    real ay = wy - qy * s;
    real bx = wx - qx * clamp(wx / qx, 0.0, 1.0);
    real by = wy - qy;
    real d2 = min(ax * ax + ay * ay, bx * bx + by * by);
    real inside = sign(max(-(wx * qy - wy * qx), -(wy - qy)));
    return sqrt(d2) * inside;
}

// --- Combining distances (CSG) ------------------------------------------------------------

// Points inside either shape: the nearer distance. Unions, intersections and subtractions
// pick by comparison rather than min/max, whose NaN rules cost llvmpipe two more
// instructions each (6% of the classroom scene's draw); a distance is never NaN.
real op_union(real d1, real d2)
{
    return d1 < d2 ? d1 : d2;
}

// Points inside both shapes: the farther distance.
real op_intersection(real d1, real d2)
{
    return d1 > d2 ? d1 : d2;
}

// Points inside shape 1 and outside shape 2.
real op_subtraction(real d1, real d2)
{
    return d1 > -d2 ? d1 : -d2;
}

// Quilez's polynomial smooth minimum: h blends from shape 2 (h = 0) to shape 1 (h = 1) and
// k h (1 - h) digs the fillet.
real op_smooth_union(real d1, real d2, real k)
{
    real h = clamp(0.5 + 0.5 * (d2 - d1) / k, 0.0, 1.0);
    return d2 + (d1 - d2) * h - k * h * (1.0 - h);
}

real op_smooth_subtraction(real d1, real d2, real k)
{
    real h = clamp(0.5 - 0.5 * (d1 + d2) / k, 0.0, 1.0);
    return d1 + (-d2 - d1) * h + k * h * (1.0 - h);
}

real op_smooth_intersection(real d1, real d2, real k)
{
    real h = clamp(0.5 - 0.5 * (d2 - d1) / k, 0.0, 1.0);
    return d2 + (d1 - d2) * h + k * h * (1.0 - h);
}

// --- Moving the query point (transforms) -----------------------------------------------

vec3 op_translate(vec3 p, vec3 offset)
{
    return p - offset;
}

// R^T p, with R given by its columns: component j is p . (column j).
vec3 op_rotate(vec3 p, vec3 column0, vec3 column1, vec3 column2)
{
    return vec3(dot(p, column0), dot(p, column1), dot(p, column2));
}

vec3 op_scale(vec3 p, real factor)
{
    return p / factor;
}

// One axis of op_repeat: fold x into the cell of size `period` around 0 (period 0: leave x).
// floor(x + 0.5) rounds halves up in every backend; GLSL's round() would not promise that.
real repeat_axis(real x, real period)
{
    return period > 0.0 ? x - period * floor(x / period + 0.5) : x;
}

vec3 op_repeat(vec3 p, vec3 period)
{
    return vec3(repeat_axis(p.x, period.x), repeat_axis(p.y, period.y),
                repeat_axis(p.z, period.z));
}

// One axis of op_repeat_limited: only cells -count..count hold a copy.
real repeat_axis_limited(real x, real period, real count)
{
    return period > 0.0 ? x - period * clamp(floor(x / period + 0.5), -count, count) : x;
}

vec3 op_repeat_limited(vec3 p, vec3 period, vec3 count)
{
    return vec3(repeat_axis_limited(p.x, period.x, count.x),
                repeat_axis_limited(p.y, period.y, count.y),
                repeat_axis_limited(p.z, period.z, count.z));
}
