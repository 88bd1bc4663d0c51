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
//                            (the bodies not in the grid after all the others)
//
// after which the bodies of slot s are grid_entries[slot_start(s) .. slot_start(s + 1) - 1],
// in no particular order. Cells are cubes of side u_cell_size (twice the largest radius plus
// the slop: the CPU's 2 max(reach)), hashed into a table of u_table_size slots (a power of two,
// at least twice the bodies) after Teschner et al. 2003 ("Optimized spatial hashing for
// collision detection of deformable objects"), but with each row of cells along x in
// consecutive slots (grid_slot); each entry keeps its cell so that a walk skips the other
// cells that share a slot.
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

// The slot of a cell in the hash table: x plus a hash of (y, z), modulo the table's size.
// The hash is Teschner et al.'s (2003, as broadphase._hash: coordinates times large primes,
// xor-ed) on y and z only, so a row of cells along x fills consecutive slots. Sorted by slot,
// the bodies of one row come one after another (STAGE_BEGIN and STAGE_FINISH take them in
// that order, `walk_order`), and the walks of neighbouring bodies, over the same rows of
// cells, read neighbouring slots.
uint grid_slot(ivec3 cell) {
    uint row = (uint(cell.y) * 19349663u) ^ (uint(cell.z) * 83492791u);
    return (uint(cell.x) + row) & uint(u_table_size - 1);
}

bool finite3(vec3 x) { return !any(isinf(x)) && !any(isnan(x)); }

// Where the bodies of slot s start in grid_entries (s = u_table_size: the end of the last),
// once STAGE_GRID_SCAN_ADD has run.
int slot_start(uint slot) { return int(cell_start[slot]); }

// STAGE_GRID_COUNT: body i's place in its cell's slot, kept in grid_rank; for a body out of
// the world or at a position that is not finite, which no exact test can pair, -1 - its place
// among such bodies (they go last in grid_entries, after every slot's). (And the count of the
// bodies that this step's walks meet starts from 0.)
void grid_count(int i) {
    if (i == 0) counters[COUNT_CANDIDATES] = 0u;
    vec3 x = bodies[i].position.xyz;
    int rank;
    if (bodies[i].in_world != 0 && finite3(x)) {
        rank = int(atomicAdd(cell_count[grid_slot(grid_cell(x))], 1u));
    } else {
        rank = -1 - int(atomicAdd(counters[COUNT_OUTSIDE_GRID], 1u));
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
    counters[COUNT_OUTSIDE_GRID] = 0u;       // grid_count has placed them: empty for next step
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

// STAGE_GRID_SCATTER: body i and its cell, at its place among the bodies sorted by slot; a
// body not in the grid at its place from the end (no walk reads there: the last slot ends
// where they begin), so that grid_entries[k].w, k = 0 .. N - 1, names every body once.
void grid_scatter(int i) {
    int rank = bodies[i].grid_rank;
    if (rank < 0) {
        grid_entries[u_count + rank] = ivec4(0, 0, 0, i);
        return;
    }
    ivec3 cell = grid_cell(bodies[i].position.xyz);
    grid_entries[slot_start(grid_slot(cell)) + rank] = ivec4(cell, i);
}

// The body that invocation k of STAGE_BEGIN and STAGE_FINISH takes: the bodies in the order
// of their slots, so that the 8 invocations llvmpipe runs in step (and a GPU's warp) walk
// neighbouring cells, read the same entries, and meet about as many bodies each. Which body an
// invocation takes changes no result: each writes only its own body's rows.
int walk_order(int k) { return entry_at(k).w; }

// A walk over the bodies in the cells under a box (grid_walk), one body per next_body. It goes
// row by row (a row: the box's cells along x at one y and z), and a row's cells fill
// consecutive slots (grid_slot), so their bodies are one run of entries: at most two, where
// the slots wrap around the end of the table.
struct GridWalk {
    bool every_body;        // the textbook loop over bodies 0 .. N - 1 instead of the grid
    ivec3 first, last;      // the block of cells to visit
    ivec2 row;              // the row being visited: its y and z
    int next, end;          // the entries of its run still to look at
    int wrapped_end;        // the end of the run's second part (from entry 0), or -1
    int met;                // bodies met so far
};

// The walk over the cells that the box [low, high] (m) overlaps.
GridWalk grid_walk(vec3 low, vec3 high) {
    GridWalk walk;
    vec3 first = cell_coordinates(low), last = cell_coordinates(high);
    vec3 size = last - first + 1.0;
    // (a row longer than the table, whose run would wrap twice, is walked this way too: it
    // has more cells than there are bodies)
    walk.every_body = u_all_pairs != 0 || !finite3(low) || !finite3(high)
        || size.x * size.y * size.z > float(u_count);
    walk.first = ivec3(first);
    walk.last = ivec3(last);
    walk.row = walk.first.yz - ivec2(1, 0);             // next_body moves on to the first row
    walk.next = 0;
    walk.end = walk.every_body ? u_count : 0;
    walk.wrapped_end = -1;
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
            if (walk.every_body) {
                j = k;
            } else {
                ivec4 entry = entry_at(k);
                // another cell that shares one of the run's slots is skipped
                if (entry.yz != walk.row || entry.x < walk.first.x || entry.x > walk.last.x) {
                    continue;
                }
                j = entry.w;
            }
            walk.met++;
            return true;
        }
        if (walk.wrapped_end >= 0) {                   // the run's part from slot 0
            walk.next = 0;
            walk.end = walk.wrapped_end;
            walk.wrapped_end = -1;
            continue;
        }
        walk.row.x++;
        if (walk.row.x > walk.last.y) { walk.row.x = walk.first.y; walk.row.y++; }
        if (walk.every_body || walk.row.y > walk.last.z) {
            atomicAdd(counters[COUNT_CANDIDATES], uint(walk.met));
            return false;
        }
        uint slot = grid_slot(ivec3(walk.first.x, walk.row));
        uint end = slot + uint(walk.last.x - walk.first.x + 1);
        walk.next = slot_start(slot);
        if (end <= uint(u_table_size)) {
            walk.end = slot_start(end);
        } else {
            walk.end = slot_start(uint(u_table_size));
            walk.wrapped_end = slot_start(end - uint(u_table_size));
        }
    }
}
