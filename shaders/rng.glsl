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
