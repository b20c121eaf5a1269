// Counter-based random numbers: a pure function of (stream, sample, seed, dimension).
// CPU twin: src/cpu/rng.rs (bit-identical: integer arithmetic only until the final conversion).

// PCG4D hash of Jarzynski and Olano, "Hash Functions for GPU Rendering" (JCGT 2020).
uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v;
}

// 24 random bits scaled into [0, 1): exact in float32, so both sides give the same value.
float rand_unit(uint bits) { return float(bits >> 8u) * (1.0 / 16777216.0); }

// Four uniform numbers in [0, 1) from one hash of `dim`; rand2 and rand1 are its first ones.
vec4 rand4(uint stream, uint sample_index, uint seed, uint dim) {
    uvec4 h = pcg4d(uvec4(stream, sample_index, seed, dim));
    return vec4(rand_unit(h.x), rand_unit(h.y), rand_unit(h.z), rand_unit(h.w));
}

// Two uniform numbers in [0, 1) for `dim` (and the next dimension, which is the same hash).
vec2 rand2(uint stream, uint sample_index, uint seed, uint dim) {
    uvec4 h = pcg4d(uvec4(stream, sample_index, seed, dim));
    return vec2(rand_unit(h.x), rand_unit(h.y));
}

float rand1(uint stream, uint sample_index, uint seed, uint dim) {
    return rand_unit(pcg4d(uvec4(stream, sample_index, seed, dim)).x);
}

// Key that sets the scrambles of qmc2 apart from rand4's hashes of the same dimension.
const uint QMC_KEY = 0x51ed270bu;

// Laine and Karras's hash as Burley improved it ("Practical Hash-based Owen Scrambling", JCGT
// 2020): each bit is flipped by a function of the bits below it, so on reversed bits it is an
// Owen scramble.
uint laine_karras(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// The second dimension of the Sobol sequence, bits reversed: Pascal's triangle mod 2 in five
// shift-and-xor steps (its blocks are [[P, 0], [P, P]]).
uint sobol_y_reversed(uint index) {
    index ^= (index & ~0x55555555u) >> 1u;
    index ^= (index & ~0x33333333u) >> 2u;
    index ^= (index & ~0x0f0f0f0fu) >> 4u;
    index ^= (index & ~0x00ff00ffu) >> 8u;
    index ^= (index & ~0x0000ffffu) >> 16u;
    return index;
}

// The qmc2 stream and index of item `item` of batch `batch`, every batch `size` items long; every
// 2^32 points the stream moves on by 2 (cpu::rng::sequence_point).
uvec2 sequence_point(uint stream, uint batch, uint size, uint item) {
    uint hi, lo;
    umulExtended(batch, size, hi, lo);
    uint index = lo + item;
    if (index < lo) hi += 1u;
    return uvec2(stream + 2u * hi, index);
}

// Point sample_index of a two-dimensional Sobol sequence, Owen-scrambled and shuffled by hashes of
// (stream, seed, dim), after Burley 2020: a pixel's first 2^k samples of one dim form a
// (0, k, 2)-net. Twin of cpu::rng::qmc2.
vec2 sobol_pair(uvec4 h, uint sample_index) {
    uint index = bitfieldReverse(laine_karras(bitfieldReverse(sample_index), h.x));
    uint x = bitfieldReverse(laine_karras(index, h.y));
    uint y = bitfieldReverse(laine_karras(sobol_y_reversed(index), h.z));
    return vec2(rand_unit(x), rand_unit(y));
}

vec2 qmc2(uint stream, uint sample_index, uint seed, uint dim) {
    return sobol_pair(pcg4d(uvec4(stream, seed, dim, QMC_KEY)), sample_index);
}

// Scrambles the choice's own copy of the sequence apart from the pair's shuffle.
const uint CHOICE_KEY = 0x9e3779b9u;

// qmc2's pair (xy) and a number for a choice among lobes (z): the first Sobol dimension again,
// shuffled and scrambled by the hash's fourth word, so it pairs with neither number of the pair
// yet is stratified over a pixel's samples. Twin of cpu::rng::qmc2_choice.
vec3 qmc2_choice(uint stream, uint sample_index, uint seed, uint dim) {
    uvec4 h = pcg4d(uvec4(stream, seed, dim, QMC_KEY));
    uint index = bitfieldReverse(laine_karras(bitfieldReverse(sample_index), h.w));
    uint choice = bitfieldReverse(laine_karras(index, h.w ^ CHOICE_KEY));
    return vec3(sobol_pair(h, sample_index), rand_unit(choice));
}

// The four numbers of a BSDF sample at dim: the lobe choice x stratified along seq (qmc2_choice),
// the delta-or-not choice w hashed from (stream, sample_index), the direction (y, z) point seq.y
// of qmc2's sequence seq.x; twin of cpu::rng::bsdf_numbers.
vec4 bsdf_numbers(uint stream, uint sample_index, uvec2 seq, uint seed, uint dim) {
    vec4 u = rand4(stream, sample_index, seed, dim);
    vec3 q = qmc2_choice(seq.x, seq.y, seed, dim);
    u.xyz = vec3(q.z, q.xy);
    return u;
}
