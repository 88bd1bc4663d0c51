// The camera model, marchlab's contract (docs/scene-format.md, scene_model/camera.py): the
// basis and the half extents tan(fov/2) W/H and tan(fov/2) are computed once on the CPU in
// float64; the per-pixel arithmetic runs here.

// The unit direction of the ray through the pixel centre (x, y) = (column + 0.5, row + 0.5),
// row 0 at the top.
vec3 camera_ray(real x, real y)
{
    precise real sx = (2.0 * x / IMAGE_WIDTH - 1.0) * HALF_WIDTH;
    precise real sy = (1.0 - 2.0 * y / IMAGE_HEIGHT) * HALF_HEIGHT;
    precise vec3 d = CAMERA_FORWARD + sx * CAMERA_RIGHT + sy * CAMERA_UP;
    return d / sqrt(dot(d, d));
}
