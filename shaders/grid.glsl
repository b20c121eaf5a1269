// Hashed spatial grid over photons: cells, hashing and the deterministic order inside a bucket.
// CPU twin: src/cpu/grid.rs.

// Photon i of a map bound as a texel buffer of RGBA32UI texels (the kernels that read maps at
// random read them this way, see scene_bindings.glsl). A photon is five words, so it starts at
// word s = 5i mod 4 of a texel and ends in the next: two fetches and a few selects, where five
// single-word fetches cost lavapipe more.
Photon fetch_photon(usamplerBuffer texels, uint i) {
    uint w = 5u * i;
    int t = int(w >> 2u);
    uvec4 a = texelFetch(texels, t);
    uvec4 b = texelFetch(texels, t + 1);
    uint s = w & 3u;
    uvec4 first = mix(mix(uvec4(a.zw, b.xy), uvec4(a.w, b.xyz), bvec4(s == 3u)),
                      mix(a, uvec4(a.yzw, b.x), bvec4(s == 1u)), bvec4(s < 2u));
    uint last = s < 2u ? (s == 0u ? b.x : b.y) : (s == 2u ? b.z : b.w);
    Photon p;
    p.position = float[3](uintBitsToFloat(first.x), uintBitsToFloat(first.y), uintBitsToFloat(first.z));
    p.flux_rg = first.w;
    p.flux_b_dir = last;
    return p;
}

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

// Cells are as large as the lookup radius, so a lookup around x visits the 3x3x3 cells around
// x's cell; this is cell k (0..26) of them.
ivec3 grid_neighbour(ivec3 c, uint k) {
    return c + ivec3(int(k % 3u), int((k / 3u) % 3u), int(k / 9u)) - 1;
}

// Distances from x to the lower (0) and upper (1) faces of its cell along each axis, shortened by
// a few ulps of x and the cell size (see the twin's grid_face_gaps).
void grid_face_gaps(vec3 x, float cell_size, out vec3 lower, out vec3 upper) {
    vec3 f = x / cell_size;
    f -= floor(f);
    vec3 ax = abs(x);
    float tolerance = (max(max(ax.x, ax.y), ax.z) + cell_size) * GRID_REACH_TOLERANCE;
    lower = max(f * cell_size - tolerance, vec3(0.0));
    upper = max((1.0 - f) * cell_size - tolerance, vec3(0.0));
}

// Whether neighbour k of the point's cell has any point within the radius (r2 its square): the
// lookups skip the buckets of cells out of reach, about a quarter of the 27.
bool grid_neighbour_in_reach(vec3 lower, vec3 upper, float r2, uint k) {
    uvec3 o = uvec3(k % 3u, (k / 3u) % 3u, k / 9u);
    vec3 gap = mix(mix(vec3(0.0), upper, equal(o, uvec3(2u))), lower, equal(o, uvec3(0u)));
    return dot(gap, gap) <= r2;
}

// The neighbours a lookup can reach, as a box of offsets from lo, n cells along each axis: an
// axis's lower (upper) neighbour only where the point's gap to that face is within the radius.
// Where cells are twice the radius wide (vcm's grid) that is at most 8 cells; a loop over the
// box in grid_neighbour's order (x fastest) then visits the 27-loop's cells in its order, and
// lavapipe, which runs a loop's body under masks while any lane goes on, pays 8 turns, not 27.
void grid_reach_box(vec3 lower, vec3 upper, float r2, out ivec3 lo, out ivec3 n) {
    lo = -ivec3(lessThanEqual(lower * lower, vec3(r2)));
    n = ivec3(lessThanEqual(upper * upper, vec3(r2))) - lo + 1;
}

// The grid_neighbour index (0..26) of cell j of the box.
uint grid_box_neighbour(ivec3 lo, ivec3 n, uint j) {
    ivec3 o = lo + ivec3(int(j) % n.x, (int(j) / n.x) % n.y, int(j) / (n.x * n.y)) + 1;
    return uint(o.x + 3 * o.y + 9 * o.z);
}
