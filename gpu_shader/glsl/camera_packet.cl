// The camera model for packets of rays: the packet twin of camera.glsl (marchlab's contract,
// docs/scene-format.md, scene_model/camera.py).
//
// Each lane computes exactly the operations of camera.glsl in the same order, so the two agree
// to the bit (tests/opencl/test_packet_sdf.py). The pixel centres are packets; the basis and
// the half extents, computed once on the CPU, are the same for every ray.

// The unit directions of the rays through the pixel centres (x, y) = (column + 0.5, row + 0.5),
// row 0 at the top. The forward vector is splat to every lane so the sum keeps the scalar
// order, (forward + sx right) + sy up.
vec3p camera_ray(packet x, packet y)
{
    packet sx = (2.0 * x / IMAGE_WIDTH - 1.0) * HALF_WIDTH;
    packet sy = (1.0 - 2.0 * y / IMAGE_HEIGHT) * HALF_HEIGHT;
    vec3p d = add(add(splat3(CAMERA_FORWARD), mul(sx, CAMERA_RIGHT)), mul(sy, CAMERA_UP));
    return div(d, sqrt(dot(d, d)));
}
