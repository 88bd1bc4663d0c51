// Bounding-sphere culling for packets of rays: the packet twin of culling.glsl (itself the twin
// of reference_cpu/culling.py, source 000's intersectsBoundingVolume).
//
// Each lane computes exactly the operations of culling.glsl in the same order, so the two agree
// to the bit (tests/opencl/test_packet_sdf.py). The rays are packets, the sphere a parameter.
// Comparisons of packets give masks (-1 where they hold, 0 elsewhere), and OpenCL's || and &&
// combine masks lane by lane, so the answer is a mask: one yes or no per ray.

// Does the ray origin + t direction, t >= 0, touch the sphere (centre xyz, radius w)? See
// culling.glsl for the derivation. Unlike the scalar ||, the lane-wise one evaluates both
// sides; the result is the same.
ipacket ray_meets_sphere(vec3p origin, vec3p direction, vec4 sphere)
{
    vec3p oc = sub(origin, sphere.xyz);
    packet b = oc.x * direction.x + oc.y * direction.y + oc.z * direction.z;
    packet c = (oc.x * oc.x + oc.y * oc.y + oc.z * oc.z) - sphere.w * sphere.w;
    return c <= 0.0 || (b <= 0.0 && b * b - c >= 0.0);
}
