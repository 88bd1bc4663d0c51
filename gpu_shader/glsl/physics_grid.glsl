// The broad phase of the GPU physics step: a uniform grid of hashed cells, rebuilt every step.
//
// Included by physics_step.glsl. It plays the part of physics/broadphase.py: instead of
// testing every other body, a body looks only at the bodies of the grid cells its reach
// overlaps. The grid is built from the positions the step starts from, in four dispatches
// before STAGE_BEGIN (a counting sort of the bodies by cell):
//
//   STAGE_GRID_COUNT         each body: its cell, the cell's slot in the hash table, and its
//                            rank among the bodies of that slot (an atomic counter per slot)
//   STAGE_GRID_SCAN          each block of u_scan_block slots: running totals of the counts
//   STAGE_GRID_SCAN_BLOCKS   one invocation: running totals of the blocks' totals
//   STAGE_GRID_SCAN_ADD      each slot: its block's start added to its own (slot_start: one
//                            read per slot where a walk looks, not two)
//   STAGE_GRID_SCATTER       each body: (cell, index) written at its slot's start + its rank
//
// after which the bodies of slot s are grid_entries[slot_start(s) .. slot_start(s + 1) - 1],
// in no particular order. Cells are cubes of side u_cell_size (twice the largest radius plus
// the slop: the CPU's 2 max(reach)), hashed into a table of u_table_size slots (a power of two,
// at least twice the bodies) as Teschner et al. 2003 do ("Optimized spatial hashing for
// collision detection of deformable objects"); each entry keeps its cell so that a walk skips
// the other cells that share a slot.
//
// A walk (grid_walk, next_body) visits every body whose cell lies in the block of cells under
// a box, each once. A box that covers more cells than there are bodies (a ball flying very
// fast, a position not finite) is walked the textbook way instead, body 0 to N - 1, and so is
// every box when u_all_pairs is set (GpuStepper(all_pairs=True)): the two ways meet the same
// bodies, so the pairs the exact tests keep are the same. Which bodies a walk meets first does
// not matter: find_contacts sorts what it keeps by index, and the sweep test keeps a minimum.
//
// All spheres share one grid, whatever their sizes (the CPU keeps one per size class): right for
// any mix of sizes, but a few large spheres among many small ones put many small ones in each
// cell, and the walks get longer.

#define CELL_LIMIT 1048576.0      // cell coordinates are clamped to +-2^20: int-safe, and far
                                  // away cells merge (more candidates, none lost)
#define GRID_MARGIN 1.01          // boxes 1% wider than their reach: more than covers the
                                  // float32 rounding of the exact tests that follow

// The integer coordinates of the cell holding x, clamped (as floats: any finite x).
vec3 cell_coordinates(vec3 x) {
    return clamp(floor(x / u_cell_size), -CELL_LIMIT, CELL_LIMIT);
}

ivec3 grid_cell(vec3 x) { return ivec3(cell_coordinates(x)); }

// The slot of a cell in the hash table: its coordinates times three large primes, xor-ed
// (Teschner et al. 2003, as broadphase._hash), modulo the table's size.
uint grid_slot(ivec3 cell) {
    uvec3 mixed = uvec3(cell) * uvec3(73856093u, 19349663u, 83492791u);
    return (mixed.x ^ mixed.y ^ mixed.z) & uint(u_table_size - 1);
}

bool finite3(vec3 x) { return !any(isinf(x)) && !any(isnan(x)); }

// Where the bodies of slot s start in grid_entries (s = u_table_size: the end of the last),
// once STAGE_GRID_SCAN_ADD has run.
int slot_start(uint slot) { return int(cell_start[slot]); }

// STAGE_GRID_COUNT: body i's place in its cell's slot, kept in grid_rank; -1 (not in the
// grid) for a body out of the world or at a position that is not finite, which no exact test
// can pair. (And the count of the bodies that this step's walks meet starts from 0.)
void grid_count(int i) {
    if (i == 0) counters[COUNT_CANDIDATES] = 0u;
    vec3 x = bodies[i].position.xyz;
    int rank = -1;
    if (bodies[i].in_world != 0 && finite3(x)) {
        rank = int(atomicAdd(cell_count[grid_slot(grid_cell(x))], 1u));
    }
    bodies[i].grid_rank = rank;
}

// STAGE_GRID_SCAN, for one block of slots: cell_start[s] becomes the number of bodies in the
// slots of the block before s (an exclusive prefix sum) and block_start[block] the block's
// total. The counts are emptied on the way, ready for the next step's STAGE_GRID_COUNT.
void scan_block(int block) {
    uint running = 0u;
    for (int s = block * u_scan_block; s < (block + 1) * u_scan_block; s++) {
        cell_start[s] = running;
        running += cell_count[s];
        cell_count[s] = 0u;
    }
    block_start[block] = running;
}

// STAGE_GRID_SCAN_BLOCKS, one invocation: block_start[b] becomes the number of bodies in the
// blocks before b, and block_start[blocks] the number in the grid. (Serial: u_table_size /
// u_scan_block additions, a few hundred for ten thousand bodies.)
void scan_block_totals() {
    uint running = 0u;
    for (int b = 0; b < u_table_size / u_scan_block; b++) {
        uint total = block_start[b];
        block_start[b] = running;
        running += total;
    }
    block_start[u_table_size / u_scan_block] = running;
}

// STAGE_GRID_SCAN_ADD, for slot s: where its block starts added to where the slot starts
// within its block; for s = u_table_size (no block's), the number in the grid.
void scan_add(uint slot) {
    uint block_of = slot / uint(u_scan_block);
    if (slot == uint(u_table_size)) cell_start[slot] = block_start[block_of];
    else cell_start[slot] += block_start[block_of];
}

// STAGE_GRID_SCATTER: body i and its cell, at its place among the bodies sorted by slot.
void grid_scatter(int i) {
    int rank = bodies[i].grid_rank;
    if (rank < 0) return;
    ivec3 cell = grid_cell(bodies[i].position.xyz);
    grid_entries[slot_start(grid_slot(cell)) + rank] = ivec4(cell, i);
}

// A walk over the bodies in the cells under a box (grid_walk), one body per next_body.
struct GridWalk {
    bool every_body;        // the textbook loop over bodies 0 .. N - 1 instead of the grid
    ivec3 first, last;      // the block of cells to visit, x fastest
    ivec3 cell;             // the cell being visited
    int next, end;          // the entries of its slot still to look at
    int met;                // bodies met so far
};

// The walk over the cells that the box [low, high] (m) overlaps.
GridWalk grid_walk(vec3 low, vec3 high) {
    GridWalk walk;
    vec3 first = cell_coordinates(low), last = cell_coordinates(high);
    vec3 size = last - first + 1.0;
    walk.every_body = u_all_pairs != 0 || !finite3(low) || !finite3(high)
        || size.x * size.y * size.z > float(u_count);
    walk.first = ivec3(first);
    walk.last = ivec3(last);
    walk.cell = walk.first - ivec3(1, 0, 0);            // next_body moves on to `first`
    walk.next = 0;
    walk.end = walk.every_body ? u_count : 0;
    walk.met = 0;
    return walk;
}

// The next body j of the walk; false once every one has been met (then the number met is
// added to the step's count of candidates).
bool next_body(inout GridWalk walk, out int j) {
    j = -1;
    while (true) {
        while (walk.next < walk.end) {
            int k = walk.next++;
            if (walk.every_body) j = k;
            else if (grid_entries[k].xyz == walk.cell) j = grid_entries[k].w;
            else continue;                          // another cell that shares the slot
            walk.met++;
            return true;
        }
        walk.cell.x++;
        if (walk.cell.x > walk.last.x) { walk.cell.x = walk.first.x; walk.cell.y++; }
        if (walk.cell.y > walk.last.y) { walk.cell.y = walk.first.y; walk.cell.z++; }
        if (walk.every_body || walk.cell.z > walk.last.z) {
            atomicAdd(counters[COUNT_CANDIDATES], uint(walk.met));
            return false;
        }
        uint slot = grid_slot(walk.cell);
        walk.next = slot_start(slot);
        walk.end = slot_start(slot + 1u);
    }
}
