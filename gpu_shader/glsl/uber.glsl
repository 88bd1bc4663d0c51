// The uber shader's interpreter: one program for every supported scene (gpu_shader/uber.py).
// The specialised generator (gpu_shader/generate.py) writes a scene's SDF, lights and
// shading out as code; here the scene is data in the parameter block and these functions
// walk it: a loop over the objects with a switch on each one's shape, a loop over the
// lights with a switch on each one's kind, and a switch on the shading mode.
// compare_specialised_uber times the two against each other.
//
// Every expression that makes a number is the one the generator writes, in the same order,
// so the two programs render the same Frame (tests/gpu/test_uber_shader.py). The records
// are read through the macros OBJECT, LIGHT, MATERIAL and HEAT, and the codes (SHAPE_...,
// LIGHT_..., SHADING_...) are #defines, all written by gpu_shader/uber.py.

// --- the scene's distance, read from the object table ------------------------------------

// The query point in object i's own frame: its transforms applied outermost first, as the
// tree walk of gpu_shader/sdf_code.py moves p on its way down to the primitive.
vec3 object_point(int i, vec3 p)
{
    int transforms = int(OBJECT(i, 0).y);
    for (int k = 0; k < transforms; k++) {
        vec4 t = OBJECT(i, TRANSFORM_ROW + 3 * k);
        switch (int(t.w)) {
        case TRANSFORM_TRANSLATE:
            p = op_translate(p, t.xyz);
            break;
        case TRANSFORM_ROTATE:
            p = op_rotate(p, t.xyz, OBJECT(i, TRANSFORM_ROW + 3 * k + 1).xyz,
                          OBJECT(i, TRANSFORM_ROW + 3 * k + 2).xyz);
            break;
        case TRANSFORM_SCALE:
            p = op_scale(p, t.x);
            break;
        }
    }
    return p;
}

// The distance to one primitive, centred on the origin; a and b are its parameter rows,
// laid out as gpu_shader/sdf_code.py's primitive_parameters lays them out.
real shape_sdf(int shape, vec3 q, vec4 a, vec4 b)
{
    switch (shape) {
    case SHAPE_SPHERE:
        return sdf_sphere(q, a.x);
    case SHAPE_BOX:
        return sdf_box(q, a.xyz);
    case SHAPE_ROUND_BOX:
        return sdf_round_box(q, a.xyz, a.w);
    case SHAPE_PLANE:
        return sdf_plane(q, a.xyz, a.w);
    case SHAPE_TORUS:
        return sdf_torus(q, a.x, a.y);
    case SHAPE_CAPPED_CYLINDER:
        return sdf_capped_cylinder(q, a.x, a.y);
    case SHAPE_CAPSULE:
        return sdf_capsule(q, a.xyz, b.xyz, a.w);
    case SHAPE_CONE:
        return sdf_cone(q, a.x, a.y);
    case SHAPE_PYRAMID:
        return sdf_pyramid(q, a.x, a.y);
    case SHAPE_DISK:
        return sdf_disk(q, a.x, a.y);
    case SHAPE_HEX_PRISM:
        return sdf_hex_prism(q, a.x, a.y);
    }
    return INFINITY;
}

// The distance to object i. A scale divides the point on the way down and multiplies the
// distance on the way back up, innermost scale first, as the tree walk does.
real object_sdf(int i, vec3 p)
{
    vec4 head = OBJECT(i, 0);
    real d = shape_sdf(int(head.x), object_point(i, p), OBJECT(i, SHAPE_ROW),
                       OBJECT(i, SHAPE_ROW + 1));
    for (int k = int(head.y) - 1; k >= 0; k--) {
        vec4 t = OBJECT(i, TRANSFORM_ROW + 3 * k);
        if (int(t.w) == TRANSFORM_SCALE) {
            d = d * t.x;
        }
    }
    return d;
}

// The distance from p to the nearest surface: the union of the objects, folded in order.
real scene_sdf(vec3 p)
{
    if (OBJECT_COUNT == 0) {
        return MAX_DISTANCE * 2.0;      // an empty scene: every ray misses
    }
    real d = object_sdf(0, p);
    for (int i = 1; i < OBJECT_COUNT; i++) {
        d = op_union(d, object_sdf(i, p));
    }
    return d;
}

// The object whose distance the union chose at p: the first of the nearest, as the fold
// of gpu_shader/sdf_code.py keeps the earlier id on a tie.
int scene_object_id(vec3 p)
{
    if (OBJECT_COUNT == 0) {
        return -1;
    }
    real d = object_sdf(0, p);
    int id = 0;
    for (int i = 1; i < OBJECT_COUNT; i++) {
        real di = object_sdf(i, p);
        id = d <= di ? id : i;
        d = op_union(d, di);
    }
    return id;
}

// Bit b of the result is set where the ray may reach the object whose bit is b
// (reference_cpu/culling.py, object_bits): always where it has no bounding sphere (radius
// -1), else where the ray meets its sphere, OBJECT(i, BOUND_ROW), widened by 2 epsilon on
// the CPU. Objects without a bit (-1) are always in.
uint ray_objects(vec3 origin, vec3 direction)
{
    uint objects = 0u;
    for (int i = 0; i < OBJECT_COUNT; i++) {
        int bit = int(OBJECT(i, 0).z);
        vec4 sphere = OBJECT(i, BOUND_ROW);
        if (bit >= 0 && (sphere.w < 0.0 || ray_meets_sphere(origin, direction, sphere))) {
            objects = objects | (1u << uint(bit));
        }
    }
    return objects;
}

// The scene's distance for one march: the union of the objects its ray may reach. With
// no bits (culling off, shadows that keep their own object) this is scene_sdf.
real march_sdf(vec3 p, uint objects)
{
    if (OBJECT_COUNT == 0) {
        return MAX_DISTANCE * 2.0;
    }
    real d = INFINITY;
    for (int i = 0; i < OBJECT_COUNT; i++) {
        int bit = int(OBJECT(i, 0).z);
        if (bit < 0 || (objects & (1u << uint(bit))) != 0u) {
            d = op_union(d, object_sdf(i, p));
        }
    }
    return d;
}

// --- normals, lights, materials ------------------------------------------------------------

// Normal by finite differences over the stencil in the parameter block (central: 6 unit
// axes, tetrahedron: 4 corners; reference_cpu/normals.py): n = normalize(sum_k k sdf(p + h k)),
// zero where the gradient vanishes.
vec3 estimate_normal(vec3 p)
{
    real h = NORMAL_STEP;
    vec3 g = vec3(0.0);
    for (int i = 0; i < STENCIL_SIZE; i++) {
        vec3 k = STENCIL(i);
        g = g + scene_sdf(p + h * k) * k;
    }
    real size = sqrt(dot(g, g));
    return size > 0.0 ? g / size : vec3(0.0);
}

// Where light i comes from at p and how strongly, by its kind.
LightSample light_sample(int i, vec3 p)
{
    vec4 head = LIGHT(i, 0);
    switch (int(head.w)) {
    case LIGHT_DIRECTIONAL:
        return light_directional(head.xyz, LIGHT(i, 1).xyz);
    case LIGHT_POINT:
        return light_point(p, head.xyz, LIGHT(i, 1).xyz, LIGHT(i, 2).xyz);
    }
    return light_spot(p, head.xyz, LIGHT(i, 1).xyz, LIGHT(i, 2).xyz, LIGHT(i, 3).xyz,
                      LIGHT(i, 4).xy);
}

// The bit of object id where its hard shadow rays leave it out (OBJECT(id, 0).w = 1: a
// convex object, render.shadow_skip_own), else 0u (reference_cpu/shadows.py).
uint own_object(int id)
{
    return OBJECT(id, 0).w > 0.0 ? 1u << uint(int(OBJECT(id, 0).z)) : 0u;
}

// How much of light s reaches p on object id: shadow rays start SURFACE_OFFSET off the
// surface (else they find the surface itself: shadow acne). Points facing away from the
// light, or where it sends nothing, need no shadow ray: their diffuse and specular terms
// are zero anyway.
real light_visible(vec3 p, vec3 n, LightSample s, int id)
{
    if (!(dot(n, s.to_light) > 0.0 && max(s.radiance.x, max(s.radiance.y, s.radiance.z)) > 0.0)) {
        return 1.0;
    }
    vec3 origin = p + SURFACE_OFFSET * n;
    if (SHADOW_MODE == SHADOWS_HARD) {
        return hard_shadow(origin, s.to_light, s.distance, own_object(id));
    }
    return soft_shadow(origin, s.to_light, s.distance);
}

// The albedo of object id at p: its colour, or its checker pattern.
vec3 surface_albedo(vec3 p, int id)
{
    if (MATERIAL(id, 3).w > 0.0) {
        return checker(p, MATERIAL(id, 2).xyz, MATERIAL(id, 3).xyz, MATERIAL(id, 2).w);
    }
    return MATERIAL(id, 0).xyz;
}

// The checker cell at p (0 or 1) for the path label; 0 for a plain material.
real surface_checker_parity(vec3 p, int id)
{
    return MATERIAL(id, 3).w > 0.0 ? checker_parity(p, MATERIAL(id, 2).w) : 0.0;
}

// --- shading -------------------------------------------------------------------------------

// The diffuse factor of the shading mode: Lambert's, banded for toon.
real diffuse_term(vec3 n, vec3 l)
{
    real x = diffuse(n, l);
    return SHADING_MODE == SHADING_TOON ? toon_band(x, TOON_BANDS) : x;
}

// The specular factor: Phong's (also for toon, banded) or Blinn-Phong's.
real specular_term(vec3 n, vec3 l, vec3 v, real shininess)
{
    if (SHADING_MODE == SHADING_BLINN_PHONG) {
        return specular_blinn_phong(n, l, v, shininess);
    }
    real x = specular_phong(n, l, v, shininess);
    return SHADING_MODE == SHADING_TOON ? toon_band(x, TOON_BANDS) : x;
}

// The lit modes (reference_cpu/shading.py) summed over the lights, plus ambient. Returns
// (colour, features): features codes the checker cell and, one bit per light, whether a
// hard shadow blocked it (for the path label).
vec4 shade_lit(vec3 p, vec3 n, vec3 v, int id)
{
    vec3 albedo = surface_albedo(p, id);
    real ka = MATERIAL(id, 0).w;
    real kd = MATERIAL(id, 1).x;
    real ks = MATERIAL(id, 1).y;
    real shininess = MATERIAL(id, 1).z;
    vec3 color = ka * albedo * AMBIENT;
    real features = surface_checker_parity(p, id);
    for (int i = 0; i < LIGHT_COUNT; i++) {
        LightSample s = light_sample(i, p);
        if (SHADOW_MODE != SHADOWS_NONE) {
            real visible = light_visible(p, n, s, id);
            s.radiance = visible * s.radiance;
            features = 2.0 * features + (SHADOW_MODE == SHADOWS_HARD && visible == 0.0 ? 1.0 : 0.0);
        } else {
            features = 2.0 * features;
        }
        color = color + s.radiance * (kd * diffuse_term(n, s.to_light) * albedo
                                      + ks * specular_term(n, s.to_light, v, shininess));
    }
    return vec4(color, features);
}

// What a ray that hits nothing sees. A solid background stores its colour as the bottom.
vec3 background(vec3 direction)
{
    if (BACKGROUND_KIND == BACKGROUND_SOLID) {
        return background_solid(direction, BACKGROUND_BOTTOM);
    }
    return background_sky(direction, BACKGROUND_BOTTOM, BACKGROUND_TOP);
}

// The heat ramp of scene_model/colormaps.py, linear between its stops (HEAT(i, 0): colour and
// x at the segment's start, HEAT(i, 1): at its end, HEAT(i, 2).x: its width).
vec3 heat(real x)
{
    x = clamp(x, 0.0, 1.0);
    for (int i = 0; i < HEAT_SEGMENTS; i++) {
        vec4 lo = HEAT(i, 0);
        vec4 hi = HEAT(i, 1);
        if (x <= hi.w || i == HEAT_SEGMENTS - 1) {
            return lo.xyz + (hi.xyz - lo.xyz) * ((x - lo.w) / HEAT(i, 2).x);
        }
    }
    return vec3(0.0);
}

// A lit pixel: shading, fog and Whitted's mirror reflections. Each bounce adds its shaded
// colour weighted by the product of the kr seen so far; a ray that hits nothing adds the
// background; a weight of at most MIN_RAY_WEIGHT ends the chain. The path label is the sum
// of the bounces' labels whose weight is more than LABEL_WEIGHT (glsl/pipeline/trace.glsl).
// Without a mirror (or with REFLECTION_DEPTH 0) the loop stops after the first bounce, where
// colour and path are those of a loopless pixel exactly (0 + 1 x = x).
vec4 lit_pixel_color(vec3 origin, vec3 direction, Hit h, vec3 n, int id)
{
    vec3 color = vec3(0.0);
    uint path = 0u;
    uint label = 0u;
    real weight = 1.0;
    vec3 o = origin;
    vec3 d = direction;
    for (int bounce = 0; bounce <= REFLECTION_DEPTH; bounce++) {
        if (bounce > 0) {
            h = march(o, d, 0.0, MAX_DISTANCE, 0u);
        }
        if (h.hit == 0) {
            color = color + weight * background(d);
            label = path_step(label, -1, 0u);
            if (weight > LABEL_WEIGHT) {
                path = (path + label) & 0xFFFFFFu;
            }
            break;
        }
        precise vec3 p = o + h.t * d;
        if (bounce > 0) {
            n = estimate_normal(p);
            id = scene_object_id(p);
        }
        vec4 lit = shade_lit(p, n, -d, id);
        vec3 shaded = lit.xyz;
        if (FOG_DENSITY > 0.0) {
            shaded = apply_fog(shaded, h.t, FOG_COLOR, FOG_DENSITY);
        }
        color = color + weight * shaded;
        label = path_step(label, id, uint(lit.w));
        if (weight > LABEL_WEIGHT) {
            path = (path + label) & 0xFFFFFFu;
        }
        weight = weight * MATERIAL(id, 1).w;
        if (bounce == REFLECTION_DEPTH || !(weight > MIN_RAY_WEIGHT)) {
            break;
        }
        // Continue just off the mirror on the ray's side, in the mirrored direction.
        vec3 n_facing = dot(d, n) < 0.0 ? n : -n;
        o = p + SURFACE_OFFSET * n_facing;
        d = reflect(d, n_facing);
    }
    return vec4(color, float(path));
}

// The colour of one pixel and its path label, by the shading mode (reference_cpu/render.py,
// Tracer.trace): given its primary ray, the march result h and, on a hit, n and id.
vec4 pixel_color(vec3 origin, vec3 direction, Hit h, vec3 n, int id)
{
    switch (SHADING_MODE) {
    case SHADING_STEPS:              // the colour jumps with every step: label them
        return vec4(heat(float(h.steps) / float(MAX_STEPS)),
                    float(path_step(uint(h.steps), id, 0u)));
    case SHADING_NORMALS:
        return vec4(h.hit == 1 ? shade_normals(n) : background(direction),
                    float(path_step(0u, id, 0u)));
    case SHADING_DEPTH:
        return vec4(h.hit == 1 ? shade_depth(h.t, MAX_DISTANCE) : background(direction),
                    float(path_step(0u, id, 0u)));
    }
    return lit_pixel_color(origin, direction, h, n, id);
}
