// Hashed spatial grid over photons: cells, hashing and the deterministic order inside a bucket.
// CPU twin: src/cpu/grid.rs.

ivec3 grid_cell(vec3 p, float cell_size) { return ivec3(floor(p / cell_size)); }

// Spatial hash of Teschner et al. 2003; the three primes are theirs.
uint grid_hash(ivec3 c, uint table_mask) {
    return ((uint(c.x) * 73856093u) ^ (uint(c.y) * 19349663u) ^ (uint(c.z) * 83492791u)) & table_mask;
}

// A total order on photons (by their bits), so a bucket sorted by it no longer depends on the
// order in which atomics placed its photons.
bool photon_less(Photon a, Photon b) {
    uvec3 pa = uvec3(floatBitsToUint(a.position[0]), floatBitsToUint(a.position[1]), floatBitsToUint(a.position[2]));
    uvec3 pb = uvec3(floatBitsToUint(b.position[0]), floatBitsToUint(b.position[1]), floatBitsToUint(b.position[2]));
    if (pa.x != pb.x) return pa.x < pb.x;
    if (pa.y != pb.y) return pa.y < pb.y;
    if (pa.z != pb.z) return pa.z < pb.z;
    if (a.flux_rg != b.flux_rg) return a.flux_rg < b.flux_rg;
    return a.flux_b_dir < b.flux_b_dir;
}

// The buckets a lookup of `radius` (= cell_size / 2) around x must read: the cell holding x and
// its neighbours on the side x is nearer to, per axis. Duplicate buckets (hash collisions among
// the eight) are dropped so that no photon is counted twice; returns how many remain.
uint grid_lookup_buckets(vec3 x, GridParams g, out uint buckets[8]) {
    vec3 q = x / g.cell_size;
    ivec3 c = ivec3(floor(q));
    ivec3 step = ivec3(greaterThanEqual(q - vec3(c), vec3(0.5))) * 2 - 1;
    uint n = 0u;
    for (uint k = 0u; k < 8u; k++) {
        ivec3 cell = c + ivec3(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u) * step;
        uint h = grid_hash(cell, g.table_mask);
        bool seen = false;
        for (uint j = 0u; j < n; j++) seen = seen || buckets[j] == h;
        if (!seen) buckets[n++] = h;
    }
    return n;
}
