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

// Square pyramid along y, base of side `base` on y = 0, apex at y = height: Quilez's exact
// pyramid in true lengths, with the base face added (see reference_cpu/sdf.py). Folded onto
// 0 <= z <= x and measured from the base corner, the distance is Pythagoras' sum of the
// height above the +x face's plane and the in-plane distance to the half face.
real sdf_pyramid(vec3 p, real base, real height)
{
    real s = 0.5 * base;
    real h = height;
    real ax = abs(p.x);
    real az = abs(p.z);
    real x = max(ax, az) - s;
    real z = min(ax, az) - s;
    real y = p.y;
    real slant = sqrt(h * h + s * s);
    real above = (h * x + s * y) / slant;
    real up = (h * y - s * x) / slant;
    real edge = max(z, 0.0);
    real edge2 = edge * edge + up * up;
    real t = clamp((slant * up - s * z) / (s * s + slant * slant), 0.0, 1.0);
    real ex = z + s * t;
    real ey = up - slant * t;
    bool on_face = min(up, -(slant * z + s * up)) > 0.0;
    real d2 = on_face ? 0.0 : min(edge2, ex * ex + ey * ey);
    real sides = sqrt(d2 + above * above) * sign(max(above, -y));
    // Below the base plane the nearest point is on the base square.
    real bx = max(x, 0.0);
    real bz = max(z, 0.0);
    real below = sqrt(bx * bx + bz * bz + y * y);
    return y < 0.0 ? below : max(sides, -y);
}

// Round disk in the xz-plane: the distance to the flat circle of radius
// radius - thickness / 2 in y = 0, minus the rounding thickness / 2.
real sdf_disk(vec3 p, real radius, real thickness)
{
    real rounding = 0.5 * thickness;
    real rim = length2(p.x, p.z) - (radius - rounding);
    return length2(max(rim, 0.0), p.y) - rounding;
}

// Hexagonal prism along z, flat sides of the hexagon at y = +-apothem: Quilez's
// sdHexPrism. Folded into x, y >= 0 and mirrored across the 60 degree line (normal
// (-cos 30, 1/2)), the hexagon's distance is that to its top side; the extrusion along z
// combines it with |z| - half_length like a 2-D box.
real sdf_hex_prism(vec3 p, real apothem, real half_length)
{
    real cos30 = 0.8660254037844386;
    real tan30 = 0.5773502691896258;
    real x = abs(p.x);
    real y = abs(p.y);
    real z = abs(p.z);
    real fold = 2.0 * min(-cos30 * x + 0.5 * y, 0.0);
    x = x + fold * cos30;
    y = y - fold * 0.5;
    real half_side = tan30 * apothem;
    real dy = y - apothem;
    real hexagon = length2(x - clamp(x, -half_side, half_side), dy) * sign(dy);
    real along = z - half_length;
    real outside = length2(max(hexagon, 0.0), max(along, 0.0));
    real inside = min(max(hexagon, along), 0.0);
    return inside + outside;
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

// Shape 1 turning into shape 2 as t goes from 0 to 1: mix(d1, d2, t), written out so that
// t = 0 and t = 1 give d1 and d2 exactly and no backend fuses it into one FMA. For t in
// [0, 1] a 1-Lipschitz bound, not an exact distance (reference_cpu/sdf.py, op_morph).
real op_morph(real d1, real d2, real t)
{
    precise real d = (1.0 - t) * d1 + t * d2;
    return d;
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
