{# A template: gpu_shader/physics.py fills in the static shapes' code below (Jinja). #}
// One step of physics.World with the "simultaneous" (Jacobi) solver, as a compute shader.
//
// Loaded by gpu_shader/physics.py, which prepends "#version 430" and the #defines of the sizes
// (MAX_CONTACTS, MAX_ITERATIONS, MAX_PLANES), of the constants of physics/colliders.py and of
// the STAGE the program runs, writes the static shapes' SDF code in where marked, and runs the
// stages below as separate dispatches, in this order. (One program per stage: the compiler
// then drops the code of the other stages, which makes each dispatch up to several times
// faster on llvmpipe than one program choosing its stage by a uniform.)
//
//   STAGE_GRID_COUNT .. _SCATTER the broad phase: bodies sorted by grid   (physics_grid.glsl)
//                               cell
//   STAGE_BEGIN                 integrate velocities, find contacts        (World._step 1, 2)
//   STAGE_ORDER_SCAN, _SCATTER  the solver's order of the bodies (Order, below)
//   STAGE_COLLIDE_COUNT, _APPLY collision sweep k = 0 .. iterations-1      (_collide_together)
//   STAGE_WARM_START            last step's resting impulses               (_apply_warm_start)
//   STAGE_REST                  resting pass k = 0 .. iterations-1         (_rest)
//   STAGE_POSITIONS             integrate positions, bounce off planes     (World._step 4,
//                               and shapes                                  bounce_off_statics)
//   STAGE_FINISH                stop sphere sweeps, push out, bounds       (stop_sphere_sweeps,
//                                                                           separate_overlaps)
//
// One invocation per body, in the gather form: body i walks its own contact list and sums the
// impulses it receives, in the order np.add.at adds them on the CPU: first the contacts where
// it is a (planes, then shapes by (shape, slot), then the spheres of higher index, by index:
// contacts.find_contacts' order), then those where it is b (the spheres of lower index, by
// index). The list is stored in that order. A contact between two spheres is computed twice,
// once by each, from the same numbers in the same canonical orientation (a = lower index,
// normal from b to a), so both get the same impulse with opposite signs. The other spheres a
// body may touch, or meet on its way, are those of the grid cells near it
// (physics_grid.glsl), as the CPU's broad phase finds them (physics/broadphase.py): about
// O(N) per step instead of every pair's O(N^2).
//
// Jacobi: every pass reads the velocities of slot u_read and writes slot 1 - u_read, so every
// contact of a pass sees the same velocities. A pass the CPU would not run (its loop stopped
// early) still copies the velocities through, so the slots stay in step without a read-back.
//
// Rounding: every sum and product is written in the CPU's order (dot3, not dot), and the
// results the continuous test builds from chains of products are `precise`: without it the
// compiler may regroup a product with a constant, (0.5 t t) A as t (t A) 0.5, and round a
// step differently from NumPy. With both, llvmpipe's float32 steps equal the CPU's bit for bit
// (where a kinematic object moves, to rounding: its pose is applied in float32 here and in
// float64 on the CPU; gpu_shader/physics_shapes.py).

layout(local_size_x = 64) in;

#define STAGE_BEGIN 0
#define STAGE_COLLIDE_COUNT 1
#define STAGE_COLLIDE_APPLY 2
#define STAGE_WARM_START 3
#define STAGE_REST 4
#define STAGE_POSITIONS 5
#define STAGE_FINISH 6
#define STAGE_GRID_COUNT 7
#define STAGE_GRID_SCAN 8
#define STAGE_GRID_SCAN_BLOCKS 9
#define STAGE_GRID_SCATTER 10
#define STAGE_GRID_SCAN_ADD 11
#define STAGE_ORDER_SCAN 12
#define STAGE_ORDER_SCATTER 13

// Event kinds, numbered in the order the CPU records the events of one collision sweep
// (gpu_shader.physics.EVENT_KINDS).
#define KIND_SPHERE_PLANE 0
#define KIND_SPHERE_SHAPE 1
#define KIND_SPHERE_SPHERE 2
#define KIND_LEFT_BOUNDS 3

#define CCD_PASSES 3              // bounce_off_statics(passes=3)
#define SETTLED 1e-9              // physics.solvers.SETTLED (m/s)

// counters[]: largest change per resting pass (float bits: a non-negative float orders like
// its bits), events written, contact lists that overflowed, the farthest any body moves in
// this step (float bits), the bodies the grid's walks met in this step
// (GpuStepper.candidates), the bodies outside the grid (physics_grid.glsl), and the bodies
// with a colliding contact in each sweep (collide_count's list: none, and the sweeps end).
#define COUNT_CHANGE 0
#define COUNT_EVENTS MAX_ITERATIONS
#define COUNT_OVERFLOW (MAX_ITERATIONS + 1)
#define COUNT_TRAVEL (MAX_ITERATIONS + 2)
#define COUNT_CANDIDATES (MAX_ITERATIONS + 3)
#define COUNT_OUTSIDE_GRID (MAX_ITERATIONS + 4)
#define COUNT_LISTED (MAX_ITERATIONS + 5)

struct Body {
    vec4 position;          // x_n (m), the state the step starts from and ends in
    vec4 velocity;          // v_n (m/s)
    vec4 spin;              // w_n (rad/s)
    vec4 orientation;       // unit quaternion (w, x, y, z)
    vec4 start_position;    // copies of x_n, v_n, w_n made by STAGE_BEGIN
    vec4 start_velocity;
    vec4 start_spin;
    vec4 end_position;      // x_{n+1} before the sphere sweep test
    float radius;
    float inverse_mass;
    float inverse_inertia;  // 1 / (2/5 m r^2)
    float restitution;
    float friction;
    int in_world;           // World.active ("active" is a reserved word in GLSL)
    int start_in_world;     // `moving` in World._step: active when the step began
    int colliding;          // contacts of this body colliding in the current sweep
    int contact_count[2];   // length of the contact list of each parity
    int landing_count;      // faces of shapes it is arriving at this step (at the list's end)
    int grid_rank;          // its place among the bodies of its grid slot (physics_grid.glsl)
};

struct Motion {             // SolverBodies row: velocity and spin during the solver
    vec4 velocity;          // w: the body's inverse mass times its share (mass splitting)
    vec4 spin;              // w: r^2 times its inverse inertia times its share
};

struct Contact {            // one entry of a body's contact list (physics.contacts.Contacts)
    vec4 normal_gap;        // xyz: unit normal from b to a; w: gap (m)
    vec4 tangent_total;     // xyz: accumulated friction impulse on a (N s); w: unused
    vec4 surface_velocity;  // xyz: velocity of b's surface at the contact (m/s): a moving
                            // shape's (a kinematic object), 0 for the others; w: the other
                            // sphere's radius, 0 for the static world
    int other;              // the other sphere's index, plane_code(p) or shape_code(q)
    int slot;               // which of the ball's contacts with that shape (0 for the others)
    float normal_total;     // accumulated normal impulse (N s)
    float gravity_part;     // h n.g for a contact with the static world, 0 between spheres
    vec2 coefficients;      // the pair's restitution max(e_a, e_b), friction sqrt(mu_a mu_b)
    vec2 pad;
};

struct Plane {
    vec4 normal_offset;     // plane normal . x = offset
    float restitution;
    float friction;
    float pad0;
    float pad1;
};

struct Event {              // physics.events.EVENT_DTYPE, plus what orders it as on the CPU
    int step;
    int stage;              // the collision sweep, 100 + the continuous pass, or 200: bounds
    int kind;
    int body;
    int other;              // the plane, shape or sphere, -1 for bounds
    float speed;
    float impulse;
    int slot;               // Contact.slot
};

layout(std430, binding = 0) buffer Bodies { Body bodies[]; };
layout(std430, binding = 1) buffer Motions { Motion motion[]; };         // 2 N: two slots
layout(std430, binding = 2) buffer Contacts { Contact contacts[]; };     // 2 N MAX_CONTACTS
layout(std430, binding = 3) buffer Planes { Plane planes[]; };
layout(std430, binding = 4) buffer Counters { uint counters[]; };
layout(std430, binding = 5) buffer Events { Event events[]; };
// The grid (physics_grid.glsl): bodies per slot of the hash table, where each slot's bodies
// start within its block of slots and where each block starts, and the bodies sorted by slot.
layout(std430, binding = 6) buffer CellCounts { uint cell_count[]; };    // u_table_size
layout(std430, binding = 7) buffer CellStarts { uint cell_start[]; };    // u_table_size + 1
layout(std430, binding = 8) buffer BlockStarts { uint block_start[]; };  // blocks + 1
layout(std430, binding = 9) buffer GridEntries { ivec4 grid_entries[]; }; // N: cell, body
// The order in which the solver's dispatches take the bodies: by their number of contacts.
// Each invocation of a sweep or pass loops over one body's contacts, and llvmpipe runs 8
// invocations in step, for as long as the one with the most contacts; bodies with neighbouring
// indices lie anywhere in a pile, with 0 to a dozen contacts. Which body an invocation takes
// changes no result: each writes only its own body's rows.
layout(std430, binding = 10) buffer Order {
    uint order_count[MAX_CONTACTS + 1];   // bodies with each number of contacts (begin_step)
    uint order_start[MAX_CONTACTS + 1];   // where each count's bodies start in `order`
    int order[];                          // 2 N: the bodies by contact count; each body's rank
};                                        // in begin_step, then each sweep's colliding bodies

uniform int u_pass;          // the sweep or resting pass this dispatch runs
uniform int u_read;          // velocity slot read by this dispatch (0 or 1)
uniform int u_list;          // contact-list parity of this step (0 or 1)
uniform int u_step;          // step number once this step is done (World.steps + 1)
uniform int u_count;         // N spheres
uniform int u_planes;        // planes in the Planes buffer
uniform int u_shapes;        // static shapes (the code below has one branch for each)
uniform int u_integrator;    // 0 explicit, 1 semi_implicit, 2 verlet
uniform int u_event_capacity;
uniform int u_has_bounds;
uniform float u_h;           // dt (s)
uniform float u_weight;      // c of integrators.py: 0, 1 or 1/2
uniform float u_threshold;   // restitution threshold (m/s)
uniform float u_slop;        // m
uniform float u_skin;        // continuous.SKIN_SLOPS slops (m)
uniform float u_push_out;    // fraction of a deep overlap removed per step
uniform vec3 u_gravity;      // m/s^2
uniform vec3 u_low;          // bounds (m)
uniform vec3 u_high;
uniform float u_max_radius;  // the largest sphere's radius (m)
uniform float u_cell_size;   // side of a grid cell (m)
uniform int u_table_size;    // slots of the grid's hash table, a power of two
uniform int u_scan_block;    // slots per block of the scan, a power of two
uniform int u_all_pairs;     // 1: every walk tests every body (the textbook loop)

// --- reads through buffer textures ---------------------------------------------------------
//
// The solver's dispatches and the grid's walks read a few dozen words per contact or per body
// met, at scattered places, and llvmpipe loads a storage buffer one word and one invocation at
// a time (a loop over the 8 invocations it runs in step, for each word). A buffer texture over
// the same buffer reads 16 bytes for all 8 in one gather: with TEXEL_READS (GpuStepper makes
// the textures, RGBA32I views of the buffers, at the units named below) those reads go through
// them, about 3 times as fast per word on llvmpipe (docs/performance.md). The words come as
// integers and are turned into floats bit for bit (intBitsToFloat), so the numbers are those
// the storage buffer holds, on any GPU. Writes still go to the storage buffers; each
// dispatch's memory barrier makes them visible to the next one's texel fetches, and no
// dispatch uses a word fetched through a texture that another of its invocations writes
// (begin_step and finish_step fetch other bodies' texel 9 for one flag while each writes
// another flag of its own body's). The later stages' loops over a body's own contacts still
// read the storage buffer: through the texture they saved no time three rounds could see.
#if TEXEL_READS
layout(binding = CONTACT_TEXELS) uniform isamplerBuffer contact_texels;   // 5 per Contact
layout(binding = MOTION_TEXELS) uniform isamplerBuffer motion_texels;     // 2 per Motion
layout(binding = BODY_TEXELS) uniform isamplerBuffer body_texels;         // 11 per Body
layout(binding = ENTRY_TEXELS) uniform isamplerBuffer entry_texels;       // 1 per grid entry

vec4 contact_texel(int k) { return intBitsToFloat(texelFetch(contact_texels, k)); }

Contact contact_at(int index) {
    int t = 5 * index;
    ivec4 words = texelFetch(contact_texels, t + 3);      // other, slot, normal_total, gravity_part
    return Contact(contact_texel(t), contact_texel(t + 1), contact_texel(t + 2), words.x, words.y,
                   intBitsToFloat(words.z), intBitsToFloat(words.w), contact_texel(t + 4).xy,
                   vec2(0.0));
}

Motion motion_at(int index) {
    return Motion(intBitsToFloat(texelFetch(motion_texels, 2 * index)),
                  intBitsToFloat(texelFetch(motion_texels, 2 * index + 1)));
}

// Texel t of body j: 0 position, 4 start_position, 7 end_position, 8 (radius, inverse_mass,
// inverse_inertia, restitution), 9 (friction, in_world, start_in_world, colliding), 10
// (contact_count[2], landing_count, grid_rank).
ivec4 body_texel(int j, int t) { return texelFetch(body_texels, 11 * j + t); }
vec3 position_of(int j) { return intBitsToFloat(body_texel(j, 0).xyz); }
vec3 start_position_of(int j) { return intBitsToFloat(body_texel(j, 4).xyz); }
vec3 end_position_of(int j) { return intBitsToFloat(body_texel(j, 7).xyz); }
vec4 mass_row_of(int j) { return intBitsToFloat(body_texel(j, 8)); }
ivec4 flags_of(int j) { return body_texel(j, 9); }
ivec2 contact_counts_of(int j) { return body_texel(j, 10).xy; }

ivec4 entry_at(int k) { return texelFetch(entry_texels, k); }
#else
Contact contact_at(int index) { return contacts[index]; }
Motion motion_at(int index) { return motion[index]; }
vec3 position_of(int j) { return bodies[j].position.xyz; }
vec3 start_position_of(int j) { return bodies[j].start_position.xyz; }
vec3 end_position_of(int j) { return bodies[j].end_position.xyz; }
vec4 mass_row_of(int j) {
    return vec4(bodies[j].radius, bodies[j].inverse_mass, bodies[j].inverse_inertia,
                bodies[j].restitution);
}
ivec4 flags_of(int j) {
    return ivec4(floatBitsToInt(bodies[j].friction), bodies[j].in_world,
                 bodies[j].start_in_world, bodies[j].colliding);
}
ivec2 contact_counts_of(int j) {
    return ivec2(bodies[j].contact_count[0], bodies[j].contact_count[1]);
}
ivec4 entry_at(int k) { return grid_entries[k]; }
#endif

// --- the static shapes: the renderer's SDF code for each (generated) ------------------------
//
// Written in by gpu_shader/physics_shapes.py for the shapes of this world: for each shape q,
// shape_distance_q, shape_object_id_q and shape_normal_q from the scene object's tree, as
// the renderer writes it, then the same by shape index: shape_distance(q, p), shape_normal,
// shape_surface (restitution, friction), shape_velocity (of a moving shape's surface, where
// the step starts: Shape.at), shape_lipschitz and shape_normal_step.

#define real float
{{ shapes }}

// --- small helpers -------------------------------------------------------------------------

// dot written out in the CPU's order, (a.x b.x + a.y b.y) + a.z b.z (scene_model.geometry.dot).
float dot3(vec3 a, vec3 b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }

// counters[c] = max(counters[c], value), for the maxima over all bodies of a dispatch (a
// resting pass's largest change, a step's farthest travel; float bits, which order as the
// non-negative floats do). An atomic only where value exceeds what was read: the counter only
// grows within the dispatch, so a value no larger than a (possibly stale) read cannot be the
// maximum. A pass then makes a few atomics on that one word instead of one per body (on
// llvmpipe a resting pass took 1.53 ms against 1.64: docs/performance.md).
void atomic_max_float(int c, float value) {
    if (floatBitsToUint(value) > counters[c]) atomicMax(counters[c], floatBitsToUint(value));
}

// Row-wise cross product p x q (physics.impulses.cross).
vec3 cross3(vec3 p, vec3 q) {
    return vec3(p.y * q.z - p.z * q.y, p.z * q.x - p.x * q.z, p.x * q.y - p.y * q.x);
}

int list_start(int body, int parity) { return (parity * u_count + body) * MAX_CONTACTS; }

// --- the broad phase: which other spheres to test (physics_grid.glsl) ----------------------

{% include "physics_grid.glsl" %}

void record_event(int stage, int kind, int body, int other, int slot, float speed,
                  float impulse) {
    uint index = atomicAdd(counters[COUNT_EVENTS], 1u);
    if (int(index) < u_event_capacity) {
        events[index] = Event(u_step, stage, kind, body, other, speed, impulse, slot);
    }
}

// Contact.other names what a ball touches: another sphere by its index (>= 0), or a part of
// the static world by a negative code: plane p, then shape q after the MAX_PLANES planes.
int plane_code(int p) { return -1 - p; }
int shape_code(int q) { return -1 - MAX_PLANES - q; }
bool is_plane(int other) { return other < 0 && other >= -MAX_PLANES; }
bool is_shape(int other) { return other < -MAX_PLANES; }
int plane_of(int other) { return -1 - other; }
int shape_of(int other) { return -1 - MAX_PLANES - other; }

// What a contact event names: its kind and the plane, shape or sphere (contacts.Contacts.kind
// and .other).
int event_kind(int other) {
    return is_plane(other) ? KIND_SPHERE_PLANE
         : is_shape(other) ? KIND_SPHERE_SHAPE : KIND_SPHERE_SPHERE;
}
int event_other(int other) {
    return is_plane(other) ? plane_of(other) : is_shape(other) ? shape_of(other) : other;
}

// Whether body i is a of its contact with `other` in the CPU's orientation: a is the lower
// index, or the sphere of a contact with the static world (other < 0).
bool is_a(int i, int other) { return other < 0 || i < other; }

// The bodies of a contact of body i in that orientation: a, and b (the higher index, or -1
// for the static world).
void contact_bodies(int i, int other, out int a, out int b) {
    if (other < 0) { a = i; b = -1; }
    else { a = min(i, other); b = max(i, other); }
}

vec3 velocity_of(int body) {
    return body < 0 ? vec3(0.0) : motion_at(u_read * u_count + body).velocity.xyz;
}
vec3 spin_of(int body) {
    return body < 0 ? vec3(0.0) : motion_at(u_read * u_count + body).spin.xyz;
}
float radius_of(int body) { return body < 0 ? 0.0 : mass_row_of(body).x; }
float inverse_mass_of(int body) { return body < 0 ? 0.0 : mass_row_of(body).y; }
float friction_of(int body) { return intBitsToFloat(flags_of(body).x); }
int contact_count_of(int body) { return contact_counts_of(body)[u_list]; }

// --- the formulas of physics/impulses.py ---------------------------------------------------

// The other body of a contact, as a sweep or pass reads it: one row of the Motion buffer,
// velocity and spin, with its mass terms in their w components, and its radius from the
// contact (surface_velocity.w). llvmpipe gathers a storage buffer lane by lane, one load of
// each vector or scalar at a time: two vec4 loads per contact instead of a dozen scattered
// reads of the other body's 172-byte Body made the solver's dispatches about a third faster
// (docs/performance.md, "Stage by stage").
struct Other {
    vec3 velocity, spin;
    float radius;
    vec2 masses;            // inverse mass and r^2 times inverse inertia, times the share
};

// The other body of body i's contact with `other` (a sphere's index, or < 0: the static world,
// which has no velocity, spin or mass). `contact` is the contact's surface_velocity.
Other other_body(int other, vec4 contact) {
    if (other < 0) return Other(vec3(0.0), vec3(0.0), 0.0, vec2(0.0));
    Motion row = motion_at(u_read * u_count + other);
    return Other(row.velocity.xyz, row.spin.xyz, contact.w, vec2(row.velocity.w, row.spin.w));
}

// A body's mass terms under mass splitting (solvers._masses): its inverse mass times `share`,
// and r^2 times its inverse inertia times `share`, in the order the CPU multiplies them.
vec2 shared_masses(int body, float share) {
    vec4 row = mass_row_of(body);
    float ii = row.z * share, r = row.x;
    return vec2(row.y * share, r * r * ii);
}

// v_rel of a's contact point relative to b's: v_a - v_b - (r_a w_a + r_b w_b) x n, less the
// velocity `surface` of a moving static surface b (a kinematic object; 0 for the others).
// Body i is a or b; its velocity, spin and radius (v_i, w_i, r_i, this sweep's) were read
// once for all its contacts. The arithmetic is that of impulses.relative_velocity, in the
// same order.
vec3 relative_velocity(bool first, vec3 v_i, vec3 w_i, float r_i, Other o, vec3 n,
                       vec3 surface) {
    vec3 lever = first ? r_i * w_i + o.radius * o.spin : o.radius * o.spin + r_i * w_i;
    vec3 v_ab = first ? v_i - o.velocity : o.velocity - v_i;
    return v_ab - cross3(lever, n) - surface;
}

// k_n = 1/m_a + 1/m_b and k_t = k_n + r_a^2/I_a + r_b^2/I_b (impulses.effective_masses), from
// each body's shared_masses: body i's (`own`) and the other's, a's terms added first.
vec2 effective_masses(bool first, vec2 own, Other o) {
    vec2 a = first ? own : o.masses, b = first ? o.masses : own;
    float k_normal = a.x + b.x;
    float k_tangent = k_normal + a.y + b.y;
    return vec2(k_normal, k_tangent);
}

// Coulomb friction: -v_t / k_t, shortened to length `limit` where longer: limit / len, else
// len / len = 1, with a length below SHORTEST counted as SHORTEST (impulses.SHORTEST).
const float SHORTEST = 1e-37;
vec3 friction_impulse(vec3 v_tangent, float k_tangent, float limit) {
    vec3 sticking = -v_tangent / k_tangent;
    float len = sqrt(dot3(sticking, sticking));
    float scale = min(limit, len) / max(len, SHORTEST);
    return sticking * scale;
}

// The impulse on a of one collision (impulses.collision_impulse); j and the approach speed
// (gravity_part - n.v_rel) come back through `out`.
vec3 collision_impulse(vec3 v_rel, vec3 n, float gravity_part, float restitution,
                       float friction, vec2 k, float threshold, out float j, out float approach) {
    float u = dot3(v_rel, n);
    approach = gravity_part - u;
    bool colliding = approach > threshold;
    j = colliding ? (restitution * approach - u) / k.x : 0.0;
    j = max(j, 0.0);
    vec3 v_tangent = v_rel - u * n;
    vec3 tangent = friction_impulse(v_tangent, k.y, friction * j);
    if (!colliding) tangent = vec3(0.0);
    return j * n + tangent;
}

// One resting pass of one contact (impulses.contact_impulse): the accumulated impulses stay
// in the friction cone; returns the increment to apply to a.
vec3 contact_impulse(vec3 v_rel, vec3 n, float target, float friction, vec2 k,
                     inout float normal_total, inout vec3 tangent_total) {
    float u = dot3(v_rel, n);
    float new_normal = max(normal_total + (target - u) / k.x, 0.0);
    vec3 v_tangent = v_rel - u * n;
    vec3 new_tangent = friction_impulse(v_tangent - tangent_total * k.y, k.y,
                                        friction * new_normal);
    vec3 impulse = (new_normal - normal_total) * n + (new_tangent - tangent_total);
    normal_total = new_normal;
    tangent_total = new_tangent;
    return impulse;
}

// apply_impulse, for one of the two bodies: P to a (`first`), -P to b; both spins turn the
// same way. `own` is the body's inverse mass and its radius times its inverse inertia.
void apply_impulse(bool first, vec3 n, vec3 impulse, vec2 own, inout vec3 velocity,
                   inout vec3 spin) {
    vec3 turn = cross3(n, impulse);
    if (first) velocity += impulse * own.x;
    else velocity += -impulse * own.x;
    spin += -own.y * turn;
}

// Body i's inverse mass and radius times inverse inertia, as apply_impulse takes them.
vec2 impulse_masses(int i) {
    vec4 row = mass_row_of(i);
    return vec2(row.y, row.x * row.z);
}

// Pair coefficients, mixed as Box2D does: max of restitutions, sqrt of the frictions' product
// (contacts.find_contacts). A sphere and the static surface (e, mu) it touches:
vec2 static_coefficients(int i, float restitution, float friction) {
    return vec2(max(bodies[i].restitution, restitution), sqrt(bodies[i].friction * friction));
}

// Two spheres, in the canonical orientation (a the lower index):
vec2 sphere_coefficients(int i, int other) {
    int a = min(i, other), b = max(i, other);
    return vec2(max(mass_row_of(a).w, mass_row_of(b).w), sqrt(friction_of(a) * friction_of(b)));
}

// --- static shapes: the functions of physics/colliders.py ------------------------------------
//
// A ball of radius r centred at x touches shape q where d(x) - r <= slop, with the normal the
// SDF's gradient (colliders.py explains the probes for concave corners and the ridges).

// colliders.shape_normals: the unit normal of `shape` at p, FALLBACK_NORMAL (+y) where the
// gradient vanishes or is not finite.
vec3 shape_normals(int shape, vec3 p) {
    vec3 normal = shape_normal(shape, p);
    float size = dot3(normal, normal);
    bool finite = !isinf(size) && !isnan(size);
    return finite && size > 0.5 ? normal : FALLBACK_NORMAL;
}

// colliders.surface_near: the unit normal of the surface a ball centred at p meets; `distance`
// comes in as the SDF at p and goes out as that surface's distance. On a ridge (a point as near
// to two faces as the finite differences can tell, where a ball resting in a corner sits) the
// gradient blends the faces' normals, and the derivative along it falls below RIDGE; there the
// normal is taken OFF_RIDGE_STEPS steps away along the fixed direction OFF_RIDGE, where one face
// is strictly nearest, and the distance is measured along that normal.
vec3 surface_near(int shape, vec3 p, inout float distance) {
    float h = shape_normal_step(shape);
    vec3 normal = shape_normals(shape, p);
    float slope = (shape_distance(shape, p + h * normal)
                   - shape_distance(shape, p - h * normal)) / (2.0 * h);
    if (!(slope >= RIDGE)) {
        precise vec3 step = (OFF_RIDGE_STEPS * h) * OFF_RIDGE;
        vec3 off = p + step;
        normal = shape_normals(shape, off);
        distance = shape_distance(shape, off) - dot3(normal, step);
    }
    return normal;
}

// Append a contact to the list of length `count` that starts at `start`; false (and the
// overflow flag raised) when the list is full. The list's last `landing` entries hold the
// faces of shapes the ball is arriving at (landing_face).
bool append_contact(int start, inout int count, int landing, Contact contact) {
    if (count + landing == MAX_CONTACTS) {
        atomicOr(counters[COUNT_OVERFLOW], 1u);
        return false;
    }
    contacts[start + count] = contact;
    count++;
    return true;
}

// The k-th face of a shape that a ball is arriving at: a contact the solver leaves alone
// (gap >= 0, approaching), kept for the continuous test, which meets it on its tangent plane
// normal . x = offset (World._step's `landing`). Stored from the end of the ball's list.
int landing_face(int start, int k) { return start + MAX_CONTACTS - 1 - k; }

// colliders.shape_contacts for ball i and one shape, with World._step's removal of contacts
// still arriving: every surface of the shape within reach (slop) of the ball, up to
// MAX_SHAPE_CONTACTS, appended in slot order. Slot 0 is the nearest surface; each further
// slot looks from a probe moved along the last normal found just past that surface's reach,
// where the SDF sees only the other surfaces (the corner of a box's inside has three).
void shape_contacts(int i, int shape, int start, inout int count, inout int landing) {
    Body self = bodies[i];
    vec3 x = self.position.xyz;
    float r = self.radius, reach = u_slop;
    float distance_here = shape_distance(shape, x);
    if (!(distance_here - r <= reach)) return;
    vec3 offset = vec3(0.0);
    vec3 seen[MAX_SHAPE_CONTACTS];                  // the normals found so far
    for (int slot = 0; slot < MAX_SHAPE_CONTACTS; slot++) {
        vec3 probe = x + offset;
        if (slot > 0) distance_here = shape_distance(shape, probe);
        vec3 m = surface_near(shape, probe, distance_here);
        // The surface's distance from the centre, along its own normal (planar estimate).
        float gap = distance_here - dot3(offset, m) - r;
        bool new_surface = gap <= reach;
        for (int k = 0; k < slot; k++) {
            new_surface = new_surface && dot3(m, seen[k]) < SAME_SURFACE;
        }
        if (!new_surface) return;
        // The coefficients of the material at the contact point, on the surface below the ball,
        // and the velocity of the surface there (at the touching point x - (gap + r) m).
        vec2 surface = shape_surface(shape, probe - (gap + r) * m);
        vec3 velocity = shape_velocity(shape, x - (gap + r) * m);
        // World._step: approaching relative to the surface; only a still surface is left to
        // bounce_off_statics (`still`: the continuous test does not follow a moving one).
        float approach = -dot3(m, self.velocity.xyz - velocity);
        bool still = all(equal(velocity, vec3(0.0)));
        bool arriving = still && gap >= 0.0 && approach > u_threshold;
        Contact contact = Contact(vec4(m, gap), vec4(0.0), vec4(velocity, 0.0),
                                  shape_code(shape), slot, 0.0, u_h * dot3(m, u_gravity),
                                  static_coefficients(i, surface.x, surface.y), vec2(0.0));
        if (arriving) {
            // its tangent plane, n . x = offset, for the continuous test
            contact.normal_gap.w = dot3(m, x) - gap - r;
            if (count + landing == MAX_CONTACTS) {
                atomicOr(counters[COUNT_OVERFLOW], 1u);
                return;
            }
            contacts[landing_face(start, landing)] = contact;
            landing++;
        } else if (!append_contact(start, count, landing, contact)) {
            return;
        }
        // Move the probe past this surface's reach and look again from there: farther than a
        // ridge's normal is looked for (surface_near), so that look cannot find it again.
        float h = shape_normal_step(shape);
        float shift = r + 2.0 * reach + 2.0 * OFF_RIDGE_STEPS * h - distance_here;
        offset = offset + max(shift, 0.0) * m;
        seen[slot] = m;
    }
}

// colliders.parabola: the point x0 + t u + t^2 A / 2 of a ball's path over the step.
vec3 parabola(vec3 start, vec3 u, vec3 acceleration, float t) {
    precise vec3 p = start + t * u + (0.5 * t * t) * acceleration;
    return p;
}

// colliders.first_shape_hit: the first time in [0, duration] at which the ball on its parabola
// comes within `touch` of the shape, by conservative advancement; -1 if it does not. Its speed
// is at most V = max(|u|, |u + A duration|), so in the time gap / (L V) it cannot reach the
// surface: stepping by that never passes through a wall, however thin. A path that has not
// converged after MAX_ADVANCE steps (grazing the surface) counts as touching where it got to.
float first_shape_hit(int shape, vec3 start, vec3 u, vec3 acceleration, float radius,
                      float duration, float touch) {
    vec3 end = u + duration * acceleration;
    float speed = max(sqrt(dot3(u, u)), sqrt(dot3(end, end)));
    if (!(speed > 0.0)) return -1.0;
    float t = 0.0;
    for (int attempt = 0; attempt < MAX_ADVANCE; attempt++) {
        float gap = shape_distance(shape, parabola(start, u, acceleration, t)) - radius;
        if (gap <= touch || attempt == MAX_ADVANCE - 1) return t;
        float later = t + max(gap, 0.0) / (shape_lipschitz(shape) * speed);
        if (!(later <= duration)) return -1.0;
        t = later;
    }
    return -1.0;
}

// The contact of sphere i with sphere j, in the canonical orientation (a = the lower index,
// normal from b to a, contacts.sphere_sphere_normals); its gap is normal_gap.w (m).
Contact sphere_contact(int i, int j) {
    int a = min(i, j), b = max(i, j);
    vec3 d = position_of(a) - position_of(b);
    float distance = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    // coincident centres: the fixed fallback normal +y (contacts.FALLBACK_NORMAL)
    vec3 n = distance == 0.0 ? FALLBACK_NORMAL : d / distance;
    float gap = distance - (mass_row_of(a).x + mass_row_of(b).x);
    return Contact(vec4(n, gap), vec4(0.0), vec4(vec3(0.0), mass_row_of(j).x), j, 0, 0.0, 0.0,
                   sphere_coefficients(i, j), vec2(0.0));
}

// continuous.stop_sphere_sweeps for one pair: whether spheres i and j, moving in straight
// lines from start_position to end_position, come within touching (having started more than
// slop apart) while they approach, and when, as a fraction t of the step (t may be >= 1).
bool sweep_hit(int i, int j, out float t) {
    int a = min(i, j), b = max(i, j);
    vec3 sa = start_position_of(a), sb = start_position_of(b);
    vec3 p = sa - sb;
    vec3 q = (end_position_of(a) - sa) - (end_position_of(b) - sb);
    float reach = mass_row_of(a).x + mass_row_of(b).x;
    // |p + t q|^2 = R^2: the first root, as c / (-b + sqrt(b^2 - a c))
    float qa = dot3(q, q), qb = dot3(p, q), qc = dot3(p, p) - reach * reach;
    float discriminant = qb * qb - qa * qc;
    float denominator = -qb + sqrt(max(discriminant, 0.0));
    bool separate = sqrt(max(qc + reach * reach, 0.0)) - reach > u_slop;
    t = 0.0;
    if (!(separate && qb < 0.0 && discriminant >= 0.0 && denominator > 0.0)) return false;
    t = qc / denominator;
    return true;
}

// --- stages --------------------------------------------------------------------------------

// integrators.integrate_velocities and contacts.find_contacts (with World._step's removal of
// plane and shape contacts still arriving: the continuous test bounces those). Carries last
// step's accumulated impulses over to contacts that persist (solvers.warm_start).
void begin_step(int i) {
    if (i == 0) {
        for (int c = 0; c < COUNT_EVENTS; c++) counters[c] = 0u;
        for (int c = 0; c < MAX_ITERATIONS; c++) counters[COUNT_LISTED + c] = 0u;
        counters[COUNT_TRAVEL] = 0u;
    }
    Body self = bodies[i];
    bodies[i].start_position = self.position;
    bodies[i].start_velocity = self.velocity;
    bodies[i].start_spin = self.spin;
    bodies[i].start_in_world = self.in_world;
    vec3 v = self.velocity.xyz + (u_h * u_gravity) * float(self.in_world);
    motion[i] = Motion(vec4(v, 0.0), self.spin);

    int start = list_start(i, u_list), old = list_start(i, 1 - u_list);
    int old_count = self.contact_count[1 - u_list];
    int count = 0, landing = 0;
    if (self.in_world != 0) {
        vec3 x = self.position.xyz;
        for (int p = 0; p < u_planes; p++) {
            vec3 n = planes[p].normal_offset.xyz;
            float gap = dot3(x, n) - planes[p].normal_offset.w - self.radius;
            float approach = -dot3(n, self.velocity.xyz);
            bool arriving = gap >= 0.0 && approach > u_threshold;
            if (gap <= u_slop && !arriving) {
                Contact contact = Contact(vec4(n, gap), vec4(0.0), vec4(0.0), plane_code(p), 0,
                                          0.0, u_h * dot3(n, u_gravity),
                                          static_coefficients(i, planes[p].restitution,
                                                              planes[p].friction), vec2(0.0));
                if (!append_contact(start, count, landing, contact)) break;
            }
        }
        for (int q = 0; q < u_shapes; q++) shape_contacts(i, q, start, count, landing);
        // The spheres within slop, from the grid cells within reach (any sphere is at most
        // u_max_radius), met in any order and kept sorted by index, as the CPU orders them:
        // that order fixes the order of the float32 sums over them.
        int near[MAX_CONTACTS];
        int found = 0, room = MAX_CONTACTS - count - landing;
        float reach = GRID_MARGIN * (self.radius + u_max_radius + u_slop);
        GridWalk walk = grid_walk(x - reach, x + reach);
        int j;
        while (next_body(walk, j)) {
            if (j == i || flags_of(j).y == 0) continue;
            if (!(sphere_contact(i, j).normal_gap.w <= u_slop)) continue;
            if (found == room) {                                   // the list would overflow
                atomicOr(counters[COUNT_OVERFLOW], 1u);
                break;
            }
            int k = found++;
            for (; k > 0 && near[k - 1] > j; k--) near[k] = near[k - 1];   // insertion sort
            near[k] = j;
        }
        // Stored in the order of the sums: first where body i is a (the static world came
        // first; then the spheres of higher index), then where it is b (lower index).
        int higher = 0;
        while (higher < found && near[higher] < i) higher++;
        for (int k = higher; k < found; k++) {
            append_contact(start, count, landing, sphere_contact(i, near[k]));
        }
        for (int k = 0; k < higher; k++) {
            append_contact(start, count, landing, sphere_contact(i, near[k]));
        }
    }
    // warm_start: the same contact in last step's list (the same pair, or the same plane, or
    // the same shape and slot: solvers.contact_keys) hands over its accumulated impulses
    // (last step's list read through contact_at: this dispatch writes only this step's)
    for (int c = 0; c < count; c++) {
        int other = contacts[start + c].other, slot = contacts[start + c].slot;
        for (int o = 0; o < old_count; o++) {
            Contact before = contact_at(old + o);
            if (before.other == other && before.slot == slot) {
                contacts[start + c].normal_total = before.normal_total;
                contacts[start + c].tangent_total = before.tangent_total;
                break;
            }
        }
    }
    bodies[i].contact_count[u_list] = count;
    // its place among the bodies with as many contacts (Order)
    order[u_count + i] = int(atomicAdd(order_count[count], 1u));
    bodies[i].landing_count = landing;
}

// The first half of solvers._collide_together: how many of this body's contacts collide in
// sweep u_pass (its mass is split among them), and whether anything collides at all. The
// body's mass terms under that split go into the w components of its Motion row, where
// collide_apply reads them as the other body's (other_body).
//
// It also carries the body's velocity and spin over to the slot this sweep writes, which
// collide_apply overwrites for the bodies it changes, and lists the bodies with a colliding
// contact (in the second half of `order`, COUNT_LISTED + u_pass of them): collide_apply
// runs for those alone, so the 8 invocations llvmpipe runs in step are all bodies with work
// (a quarter of a pile's bodies collide in a sweep, scattered through the order).
void collide_count(int i) {
    vec3 v_i = velocity_of(i), w_i = spin_of(i);
    motion[(1 - u_read) * u_count + i] = Motion(vec4(v_i, 0.0), vec4(w_i, 0.0));
    if (u_pass > 0 && counters[COUNT_LISTED + u_pass - 1] == 0u) return;      // loop ended
    int start = list_start(i, u_list), count = contact_count_of(i);
    float r_i = radius_of(i);
    int colliding = 0;
    for (int c = 0; c < count; c++) {
        Contact k = contact_at(start + c);
        Other o = other_body(k.other, k.surface_velocity);
        vec3 v_rel = relative_velocity(is_a(i, k.other), v_i, w_i, r_i, o, k.normal_gap.xyz,
                                       k.surface_velocity.xyz);
        if (k.gravity_part - dot3(v_rel, k.normal_gap.xyz) > u_threshold) colliding++;
    }
    bodies[i].colliding = colliding;
    vec2 masses = shared_masses(i, float(colliding));
    motion[u_read * u_count + i].velocity.w = masses.x;
    motion[u_read * u_count + i].spin.w = masses.y;
    if (colliding > 0) order[u_count + int(atomicAdd(counters[COUNT_LISTED + u_pass], 1u))] = i;
}

// The second half (solvers._collide): collision impulses with mass split among the colliding
// contacts. Body i sums them in the order of its list: first the contacts where it is a, then
// those where it is b, the order in which np.add.at adds them on the CPU.
//
// Run for the bodies collide_count listed only: a body with no colliding contact gets no
// impulse (collide_count classified its contacts from these very velocities), and its
// velocity and spin are already in the slot this sweep writes.
void collide_apply(int i) {
    vec3 v = velocity_of(i), w = spin_of(i);
    vec3 v_i = v, w_i = w;                        // read once for every contact
    float r_i = radius_of(i);
    vec2 own = shared_masses(i, float(flags_of(i).w)), applied = impulse_masses(i);
    int start = list_start(i, u_list), count = contact_count_of(i);
    for (int c = 0; c < count; c++) {
        Contact k = contact_at(start + c);
        bool first = is_a(i, k.other);
        Other o = other_body(k.other, k.surface_velocity);
        vec3 n = k.normal_gap.xyz;
        vec3 v_rel = relative_velocity(first, v_i, w_i, r_i, o, n, k.surface_velocity.xyz);
        if (k.gravity_part - dot3(v_rel, n) <= u_threshold) continue;
        vec2 mass = effective_masses(first, own, o);
        float j, approach;
        vec3 impulse = collision_impulse(v_rel, n, k.gravity_part, k.coefficients.x,
                                         k.coefficients.y, mass, u_threshold, j,
                                         approach);
        if (!(j > 0.0)) continue;
        apply_impulse(first, n, impulse, applied, v, w);
        if (first) {
            record_event(u_pass, event_kind(k.other), i, event_other(k.other), k.slot,
                         approach, j);
        }
    }
    motion[(1 - u_read) * u_count + i] = Motion(vec4(v, 0.0), vec4(w, 0.0));
}

// solvers._apply_warm_start: last step's resting impulses, friction turned into the current
// tangent plane. The body's mass terms for the resting passes (its mass split among all its
// contacts) go into the w components of its Motion row, and each pass carries them on.
void warm_start_apply(int i) {
    vec3 v = velocity_of(i), w = spin_of(i);
    vec2 applied = impulse_masses(i);
    int start = list_start(i, u_list), count = contact_count_of(i);
    for (int c = 0; c < count; c++) {
        Contact k = contact_at(start + c);
        vec3 n = k.normal_gap.xyz;
        vec3 tangent = k.tangent_total.xyz - dot3(k.tangent_total.xyz, n) * n;
        contacts[start + c].tangent_total.xyz = tangent;
        apply_impulse(is_a(i, k.other), n, k.normal_total * n + tangent, applied, v, w);
    }
    vec2 masses = shared_masses(i, float(count));
    motion[(1 - u_read) * u_count + i] = Motion(vec4(v, masses.x), vec4(w, masses.y));
}

// solvers._rest over every contact, mass split among all of a body's contacts; stops (copies
// through) once the previous pass changed no velocity by more than SETTLED.
void rest_pass(int i) {
    Motion row = motion_at(u_read * u_count + i);
    vec3 v = row.velocity.xyz, w = row.spin.xyz;
    vec3 v_i = v, w_i = w;                        // read once for every contact
    vec2 own = vec2(row.velocity.w, row.spin.w);  // warm_start_apply's shared_masses
    bool running = u_pass == 0
        || uintBitsToFloat(counters[COUNT_CHANGE + u_pass - 1]) >= SETTLED;
    if (running) {
        float r_i = radius_of(i);
        vec2 applied = impulse_masses(i);
        int start = list_start(i, u_list), count = contact_count_of(i);
        float change = 0.0;
        for (int c = 0; c < count; c++) {                 // a's contacts first, then b's
            Contact k = contact_at(start + c);
            bool first = is_a(i, k.other);
            Other o = other_body(k.other, k.surface_velocity);
            vec3 n = k.normal_gap.xyz;
            vec3 v_rel = relative_velocity(first, v_i, w_i, r_i, o, n, k.surface_velocity.xyz);
            vec2 mass = effective_masses(first, own, o);
            float target = -max(k.normal_gap.w, 0.0) / u_h;     // solvers._resting_target
            float normal_total = k.normal_total;
            vec3 tangent_total = k.tangent_total.xyz;
            vec3 impulse = contact_impulse(v_rel, n, target, k.coefficients.y, mass,
                                           normal_total, tangent_total);
            contacts[start + c].normal_total = normal_total;
            contacts[start + c].tangent_total.xyz = tangent_total;
            apply_impulse(first, n, impulse, applied, v, w);
            change = max(change, sqrt(dot3(impulse, impulse)) * mass.y);
        }
        atomic_max_float(COUNT_CHANGE + u_pass, change);
    }
    motion[(1 - u_read) * u_count + i] = Motion(vec4(v, own.x), vec4(w, own.y));
}

// integrators.py: x_{n+1} from x_n, v_n and v_{n+1}, each scheme written as on the CPU.
vec3 integrate_position(vec3 x, vec3 v_old, vec3 v_new) {
    if (u_integrator == 0) return x + u_h * v_old;                  // explicit_euler
    if (u_integrator == 1) return x + u_h * v_new;                  // semi_implicit_euler
    return x + u_h * (0.5 * (v_old + v_new));                       // velocity_verlet
}

// quaternions.quaternion_multiply: the Hamilton product p q.
vec4 quaternion_multiply(vec4 p, vec4 q) {
    return vec4(p.x * q.x - p.y * q.y - p.z * q.z - p.w * q.w,
                p.x * q.y + p.y * q.x + p.z * q.w - p.w * q.z,
                p.x * q.z - p.y * q.w + p.z * q.x + p.w * q.y,
                p.x * q.w + p.y * q.z - p.z * q.y + p.w * q.x);
}

// quaternions.rotate_orientations: turn q by the world-frame rotation vector r, renormalised.
vec4 rotate_orientation(vec4 q, vec3 r) {
    float angle = sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
    float half_sinc = angle > 0.0 ? sin(0.5 * angle) / angle : 0.5;    // sin(angle/2) / angle
    vec4 turned = quaternion_multiply(vec4(cos(0.5 * angle), half_sinc * r), q);
    return turned / sqrt(dot(turned, turned));
}

// continuous.first_plane_hit: first t in (0, duration] with gap + speed t + a t^2/2 = 0, or -1.
float first_plane_hit(float gap, float speed, float acceleration, float duration) {
    float discriminant = speed * speed - 2.0 * acceleration * gap;
    float denominator = -speed + sqrt(max(discriminant, 0.0));
    if (!(discriminant >= 0.0 && denominator > 0.0)) return -1.0;
    float t = 2.0 * gap / denominator;
    return t <= duration ? t : -1.0;
}

// continuous._plane_times and _shape_times, for body i: the first of the planes and shapes
// that it would reach in the time left, as an index `wall` (p for plane p, u_planes + q for
// shape q; -1 for none), the time and, for a shape, the normal of the face met. Ties go to
// the first.
//
// Planes by their exact time of impact (first_plane_hit), skipping those the ball touches
// (bit p of `skip_planes`). Shapes by conservative advancement to within half the slop
// (first_shape_hit), tried only where the ball could get there: its gap now no more than the
// farthest it can travel in the time left. A shape is not skipped because the ball touches
// it, as a ball rolling on the floor of a box must still meet its wall: the ball is advanced
// from its path lifted off each face it rests on (its contacts with the shape, and the faces
// met earlier this step, `met`) by the skin (u_skin), so those faces are out of reach and the
// others are where they were; the time found is moved back, on the tangent plane of the face
// found, to when the real path touched it. A face it rests on is not a new impact: velocity
// Verlet carries the solver's impulse as an acceleration over the step, so the parabola may
// dip into it before turning. A face the ball was arriving at (landing_face; not those of a
// shape in `met_shapes`, met already) is met exactly on its tangent plane, as a plane is.
int first_wall_hit(int i, vec3 position, vec3 velocity, vec3 acceleration, float remaining,
                   uint skip_planes, uint met_shapes, int met_count, int met_shape[CCD_PASSES],
                   vec3 met_normal[CCD_PASSES], out float first, out vec3 face) {
    float radius = bodies[i].radius;
    int wall = -1;
    first = 0.0;
    face = vec3(0.0);
    for (int p = 0; p < u_planes; p++) {
        vec3 n = planes[p].normal_offset.xyz;
        float gap = dot3(position, n) - planes[p].normal_offset.w - radius;
        if ((skip_planes & (1u << uint(p))) != 0u || gap < 0.0) continue;
        float t = first_plane_hit(max(gap, 0.0), dot3(velocity, n), dot3(acceleration, n),
                                  remaining);
        if (t >= 0.0 && (wall < 0 || t < first)) { wall = p; first = t; }
    }
    float touch = 0.5 * u_slop;
    vec3 end_velocity = velocity + remaining * acceleration;
    float travel = remaining * max(sqrt(dot3(velocity, velocity)),
                                   sqrt(dot3(end_velocity, end_velocity)));
    int start = list_start(i, u_list), count = contact_count_of(i);
    int landing = bodies[i].landing_count;
    for (int q = 0; q < u_shapes; q++) {
        float time = -1.0;
        vec3 normal = vec3(0.0);
        vec3 lift = vec3(0.0);                                    // off the `resting` faces
        for (int c = 0; c < count; c++) {
            Contact k = contacts[start + c];
            if (k.other == shape_code(q)) lift += u_skin * k.normal_gap.xyz;
        }
        for (int m = 0; m < met_count; m++) {
            if (met_shape[m] == q) lift += u_skin * met_normal[m];
        }
        vec3 lifted = position + lift;
        float gap = shape_distance(q, lifted) - radius;
        if (gap <= shape_lipschitz(q) * travel + touch) {
            time = first_shape_hit(q, lifted, velocity, acceleration, radius, remaining, touch);
        }
        if (time >= 0.0) {
            vec3 p = parabola(lifted, velocity, acceleration, time);
            vec3 v = velocity + time * acceleration;
            float depth = shape_distance(q, p);
            normal = surface_near(q, p, depth);
            bool again = false;                                   // a `resting` face met again
            for (int c = 0; c < count; c++) {
                Contact k = contacts[start + c];
                if (k.other == shape_code(q) && dot3(normal, k.normal_gap.xyz) > SAME_SURFACE) {
                    again = true;
                }
            }
            for (int m = 0; m < met_count; m++) {
                if (met_shape[m] == q && dot3(normal, met_normal[m]) > SAME_SURFACE) again = true;
            }
            // gap(t) ~ gap_hit + (t - t_hit) v.n on the tangent plane: back to where it was 0.
            float gap_hit = depth - dot3(lift, normal) - radius;
            float closing = dot3(v, normal);
            if (time >= 0.0 && gap_hit < 0.0 && closing < 0.0) {
                time = max(time - gap_hit / closing, 0.0);
            }
            if (again) time = -1.0;
        }
        for (int k = 0; k < landing && (met_shapes & (1u << uint(q))) == 0u; k++) {
            Contact f = contacts[landing_face(start, k)];
            if (shape_of(f.other) != q) continue;
            vec3 n = f.normal_gap.xyz;
            float face_gap = dot3(position, n) - f.normal_gap.w - radius;
            float t = first_plane_hit(max(face_gap, 0.0), dot3(velocity, n),
                                      dot3(acceleration, n), remaining);
            if (t >= 0.0 && (time < 0.0 || t < time)) { time = t; normal = n; }
        }
        if (time >= 0.0 && (wall < 0 || time < first)) {
            wall = u_planes + q;
            first = time;
            face = normal;
        }
    }
    return wall;
}

// continuous._surface: the (restitution, friction) of the plane or shape `wall` met by a
// ball centred at `position` (a shape's where the ball's centre is) ...
vec2 wall_coefficients(int wall, vec3 position) {
    if (wall < u_planes) return vec2(planes[wall].restitution, planes[wall].friction);
    return shape_surface(wall - u_planes, position);
}

// ... and its surface velocity there: a moving shape's where it is at the start of the step
// (the continuous test does not follow it through the step), 0 for a plane.
vec3 wall_velocity(int wall, vec3 position) {
    if (wall < u_planes) return vec3(0.0);
    return shape_velocity(wall - u_planes, position);
}

// The positions stage of World._step, then continuous.bounce_off_statics for this body: follow
// its parabola over the step and bounce off the first plane or shape it would reach (up to 3
// times).
void integrate_positions(int i) {
    Body self = bodies[i];
    vec3 x_old = self.start_position.xyz, v_old = self.start_velocity.xyz;
    precise vec3 v_new = velocity_of(i), spin = spin_of(i);
    precise vec3 x_new = integrate_position(x_old, v_old, v_new);
    vec3 turn = integrate_position(vec3(0.0), self.start_spin.xyz, spin);
    bodies[i].orientation = rotate_orientation(self.orientation, turn);

    // The planes the ball touches, in the solver's contacts (bit p); the shapes' faces met
    // during this step (shape, normal) and the shapes met (bit q).
    uint skip_planes = 0u, met_shapes = 0u;
    int met_count = 0;
    int met_shape[CCD_PASSES];
    vec3 met_normal[CCD_PASSES];
    int start = list_start(i, u_list), count = self.contact_count[u_list];
    for (int c = 0; c < count; c++) {
        int other = contacts[start + c].other;
        if (is_plane(other)) skip_planes |= 1u << uint(plane_of(other));
    }
    precise vec3 acceleration = (v_new - v_old) / u_h;
    precise vec3 position = x_old, velocity = v_old + (u_weight - 0.5) * (v_new - v_old);
    precise float elapsed = 0.0;
    bool bounced = false;
    for (int pass = 0; pass < CCD_PASSES && self.start_in_world != 0; pass++) {
        float t;
        vec3 face;
        int wall = first_wall_hit(i, position, velocity, acceleration, u_h - elapsed,
                                  skip_planes, met_shapes, met_count, met_shape, met_normal,
                                  t, face);
        if (wall < 0) break;
        // Move to the moment of impact, on the parabola.
        position += t * velocity + (0.5 * t * t) * acceleration;
        velocity += t * acceleration;
        elapsed += t;
        bool plane = wall < u_planes;
        vec3 n = plane ? planes[wall].normal_offset.xyz : face;
        vec2 surface = wall_coefficients(wall, position);
        vec3 surface_velocity = wall_velocity(wall, position);
        // continuous._impact: a collision impulse, inelastic below the restitution threshold,
        // relative to the surface's velocity
        vec3 v_rel = velocity - cross3(self.radius * spin, n) - surface_velocity;
        float approach = -dot3(v_rel, n);
        float restitution = approach > u_threshold ? max(self.restitution, surface.x) : 0.0;
        float friction = sqrt(self.friction * surface.y);
        float k_normal = self.inverse_mass + 0.0;
        vec2 k = vec2(k_normal, k_normal + self.radius * self.radius * self.inverse_inertia);
        float j;
        vec3 impulse = collision_impulse(v_rel, n, 0.0, restitution, friction, k, 0.0, j,
                                         approach);
        velocity += impulse * self.inverse_mass;
        spin -= (self.radius * self.inverse_inertia) * cross3(n, impulse);
        record_event(100 + pass, plane ? KIND_SPHERE_PLANE : KIND_SPHERE_SHAPE, i,
                     plane ? wall : wall - u_planes, 0, approach, j);
        // Landed: it would fall back through before the step ends, so the surface holds it
        // (u_n relative to a moving surface).
        float left = u_h - elapsed;
        float u_n = dot3(velocity - surface_velocity, n), a_n = dot3(acceleration, n);
        precise float fall = u_n * left + 0.5 * a_n * left * left;
        if (fall <= 0.0) {
            velocity -= u_n * n;
            acceleration -= min(a_n, 0.0) * n;
        }
        if (plane) {
            skip_planes |= 1u << uint(wall);                  // the ball now touches it ...
        } else {                                              // ... or rests on this face
            met_shape[met_count] = wall - u_planes;
            met_normal[met_count] = n;
            met_count++;
            met_shapes |= 1u << uint(wall - u_planes);        // ... and has landed on its faces
        }
        bounced = true;
    }
    if (bounced) {
        precise float left = u_h - elapsed;
        x_new = position + left * velocity + (0.5 * left * left) * acceleration;
        vec3 end_velocity = velocity + left * acceleration;
        v_new = end_velocity - ((u_weight - 0.5) * u_h) * acceleration;
    }
    bodies[i].end_position = vec4(x_new, 0.0);
    // the farthest any ball moves this step, which widens the sweep test's walks (finish_step)
    vec3 d = x_new - x_old;
    float travel = sqrt(dot3(d, d));
    if (self.start_in_world != 0 && finite3(d)) {
        atomic_max_float(COUNT_TRAVEL, travel);
    }
    bodies[i].velocity = vec4(v_new, 0.0);
    bodies[i].spin = vec4(spin, 0.0);
}

// continuous.stop_sphere_sweeps, solvers.separate_overlaps and World._remove_out_of_bounds,
// for body i.
void finish_step(int i) {
    Body self = bodies[i];
    vec3 start = self.start_position.xyz, end = self.end_position.xyz;
    if (self.start_in_world != 0) {
        // The earliest hit among the spheres of the grid cells that body i's path could
        // reach: a sphere j it meets at time t started within r_i + r_j + t |d_j| of a point
        // of that path, so within the largest radius and the farthest travel of any sphere.
        bool hit = false;
        float first = 0.0;
        vec3 d_i = end - start;
        float travel = uintBitsToFloat(counters[COUNT_TRAVEL]);
        float reach = GRID_MARGIN * (self.radius + u_max_radius + u_slop + travel);
        GridWalk walk = grid_walk(min(start, end) - reach, max(start, end) + reach);
        int j;
        while (next_body(walk, j)) {
            float t;
            if (j == i || flags_of(j).z == 0 || !sweep_hit(i, j, t)) continue;
            if (t < 1.0 && (!hit || t < first)) {     // the minimum, whatever the order met
                hit = true;
                first = t;
            }
        }
        if (hit) end = start + first * d_i;
    }

    // separate_overlaps: contacts deeper than slop, shared by inverse mass, mean of requests
    vec3 total = vec3(0.0);
    int deep = 0;
    int list = list_start(i, u_list), count = self.contact_count[u_list];
    for (int c = 0; c < count; c++) {                     // a's contacts first, then b's
        Contact k = contacts[list + c];
        int a, b;
        contact_bodies(i, k.other, a, b);
        if (!(k.normal_gap.w < -u_slop)) continue;
        float ima = inverse_mass_of(a), imb = inverse_mass_of(b);
        float depth = u_push_out * (-k.normal_gap.w - u_slop) / (ima + imb);
        vec3 push = depth * k.normal_gap.xyz;
        total += i == a ? push * ima : -push * imb;
        deep++;
    }
    end += total / float(max(deep, 1));

    bodies[i].position = vec4(end, 0.0);
    bool outside = any(lessThan(end, u_low)) || any(greaterThan(end, u_high));
    if (u_has_bounds != 0 && self.in_world != 0 && outside) {
        vec3 v = bodies[i].velocity.xyz;
        record_event(200, KIND_LEFT_BOUNDS, i, -1, 0, sqrt(dot3(v, v)), 0.0);
        bodies[i].in_world = 0;
        bodies[i].velocity = vec4(0.0);
        bodies[i].spin = vec4(0.0);
    }
}

// STAGE_ORDER_SCAN, one invocation: where the bodies of each contact count start in `order`
// (an exclusive prefix sum), the counts emptied for the next step.
void order_scan() {
    uint running = 0u;
    for (int c = 0; c <= MAX_CONTACTS; c++) {
        order_start[c] = running;
        running += order_count[c];
        order_count[c] = 0u;
    }
}

// STAGE_ORDER_SCATTER: body i at its place in `order`.
void order_scatter(int i) {
    order[order_start[bodies[i].contact_count[u_list]] + uint(order[u_count + i])] = i;
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (STAGE == STAGE_ORDER_SCAN) {                     // one invocation
        if (i == 0) order_scan();
        return;
    }
    if (STAGE == STAGE_GRID_SCAN) {                      // one invocation per block of slots
        if (i < u_table_size / u_scan_block) scan_block(i);
        return;
    }
    if (STAGE == STAGE_GRID_SCAN_ADD) {                  // one invocation per slot, and the end
        if (i <= u_table_size) scan_add(uint(i));
        return;
    }
    if (STAGE == STAGE_GRID_SCAN_BLOCKS) {               // one invocation
        if (i == 0) scan_block_totals();
        return;
    }
    if (i >= u_count) return;                              // the others: one per body
    if (STAGE == STAGE_COLLIDE_APPLY) {
        if (uint(i) >= counters[COUNT_LISTED + u_pass]) return;
        i = order[u_count + i];                            // collide_count's list
    } else if (STAGE == STAGE_COLLIDE_COUNT || STAGE == STAGE_WARM_START
            || STAGE == STAGE_REST) {
        i = order[i];                                      // the solver's order (Order)
    } else if (STAGE == STAGE_BEGIN || STAGE == STAGE_FINISH) {
        i = walk_order(i);                                 // by grid slot (physics_grid.glsl)
    }
    if (STAGE == STAGE_ORDER_SCATTER) order_scatter(i);
    else if (STAGE == STAGE_GRID_COUNT) grid_count(i);
    else if (STAGE == STAGE_GRID_SCATTER) grid_scatter(i);
    else if (STAGE == STAGE_BEGIN) begin_step(i);
    else if (STAGE == STAGE_COLLIDE_COUNT) collide_count(i);
    else if (STAGE == STAGE_COLLIDE_APPLY) collide_apply(i);
    else if (STAGE == STAGE_WARM_START) warm_start_apply(i);
    else if (STAGE == STAGE_REST) rest_pass(i);
    else if (STAGE == STAGE_POSITIONS) integrate_positions(i);
    else if (STAGE == STAGE_FINISH) finish_step(i);
}
