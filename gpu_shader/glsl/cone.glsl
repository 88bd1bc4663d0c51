// The cone-marching pre-pass: the twin of reference_cpu/cone_prepass.py, which proves that a
// start found this way skips only empty space (after Keinert et al. 2014, "Enhanced Sphere
// Tracing", and the demoscene's cone marching). One cone per tile of PREPASS_TILE x
// PREPASS_TILE pixels holds the rays of all its pixels; the distance it gets to is where
// each of those rays may start (glsl/march.glsl's `start`). The generator defines
// MIN_PROGRESS and CONE_SLACK from the reference's constants.

// tan of the angle between the unit vectors `axis` and `ray`: |a x r| / (a . r). For the
// small angles of a tile, sqrt(1 - cos^2) would lose most of its digits to cancellation.
real cone_tan(vec3 axis, vec3 ray)
{
    precise vec3 c = vec3(axis.y * ray.z - axis.z * ray.y,
                          axis.z * ray.x - axis.x * ray.z,
                          axis.x * ray.y - axis.y * ray.x);
    return sqrt(dot(c, c)) / dot(axis, ray);
}

// How far along `axis` the cone from `origin` with half-angle tan(theta) = `tan_half` stays
// at least EPSILON from every surface. At axial distance t the cone is w = EPSILON + t tan
// wide (with the margin), and the sphere of radius d = |scene_sdf(c(t))| about its axis
// point holds the whole cone up to t + delta, delta = (d - w) / (1 + tan). It stops when
// delta is at most MIN_PROGRESS w (near a surface the steps only shrink), past MAX_DISTANCE,
// or after MAX_STEPS evaluations.
real cone_march(vec3 origin, vec3 axis, real tan_half)
{
    precise real t = 0.0;
    for (int step = 1; step <= MAX_STEPS; step++) {
        precise vec3 p = origin + t * axis;
        real d = abs(scene_sdf(p));
        precise real width = EPSILON + t * tan_half;
        real delta = (d - width) / (1.0 + tan_half);
        if (!(delta > MIN_PROGRESS * width)) {
            break;
        }
        t = t + delta;
        if (t > MAX_DISTANCE) {
            break;
        }
    }
    return t;
}

// The start of every ray of tile (tx, ty) (tiles counted from the top-left; those at the
// right and bottom edges may be smaller): the cone from the eye through the tile's centre,
// wide enough to hold the rays through its four corners (so, being convex, the ray through
// every point of the tile, anti-aliasing samples included), marched.
real tile_start(real tx, real ty)
{
    real x0 = tx * PREPASS_TILE;
    real y0 = ty * PREPASS_TILE;
    real x1 = min(x0 + PREPASS_TILE, IMAGE_WIDTH);
    real y1 = min(y0 + PREPASS_TILE, IMAGE_HEIGHT);
    vec3 axis = camera_ray(0.5 * (x0 + x1), 0.5 * (y0 + y1));
    real widest = 0.0;
    widest = max(widest, cone_tan(axis, camera_ray(x0, y0)));
    widest = max(widest, cone_tan(axis, camera_ray(x1, y0)));
    widest = max(widest, cone_tan(axis, camera_ray(x0, y1)));
    widest = max(widest, cone_tan(axis, camera_ray(x1, y1)));
    return cone_march(CAMERA_POSITION, axis, widest + CONE_SLACK);
}
