// Bounding-sphere culling: the GLSL twin of reference_cpu/culling.py (bounding spheres as in
// Whitted 1980). The generator writes ray_objects, which calls this once per bounded object
// before a march, and march_sdf, which leaves out the objects a ray misses.

// Does the ray origin + t direction, t >= 0, touch the sphere (centre xyz, radius w)?
// With oc = o - c, b = oc . d and c' = |oc|^2 - r^2 the line meets it where
// t^2 + 2 b t + c' = 0 has real roots; one is at t >= 0 if the ray starts inside (c' <= 0)
// or the sphere lies ahead (b <= 0).
bool ray_meets_sphere(vec3 origin, vec3 direction, vec4 sphere)
{
    precise vec3 oc = origin - sphere.xyz;
    precise real b = oc.x * direction.x + oc.y * direction.y + oc.z * direction.z;
    precise real c = (oc.x * oc.x + oc.y * oc.y + oc.z * oc.z) - sphere.w * sphere.w;
    return c <= 0.0 || (b <= 0.0 && b * b - c >= 0.0);
}
