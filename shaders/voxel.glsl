// Voxel grids (TEXTURE_VOXELS): trilinear lookup of a block of floats. CPU twin: src/cpu/voxel.rs
// (contract there). The including kernel declares texture_word(i).

#ifndef VOXEL_GLSL
#define VOXEL_GLSL

float voxel_at(uint at, uvec3 n, uint x, uint y, uint z) {
    return uintBitsToFloat(texture_word(at + VOXEL_HEADER_WORDS + x + n.x * (y + n.y * z)));
}

float voxel_lookup(uint at, vec3 p) {
    if (any(lessThan(p, vec3(0.0))) || any(greaterThan(p, vec3(1.0)))) return 0.0;
    uvec3 n = uvec3(texture_word(at), texture_word(at + 1u), texture_word(at + 2u));
    vec3 nf = vec3(n);
    precise vec3 c = p * nf - 0.5;
    vec3 x = clamp(c, vec3(0.0), nf - 1.0);
    uvec3 i0 = uvec3(floor(x));
    uvec3 i1 = min(i0 + 1u, n - 1u);
    precise vec3 f = x - vec3(i0);
    float c00 = pattern_lerp(f.x, voxel_at(at, n, i0.x, i0.y, i0.z), voxel_at(at, n, i1.x, i0.y, i0.z));
    float c10 = pattern_lerp(f.x, voxel_at(at, n, i0.x, i1.y, i0.z), voxel_at(at, n, i1.x, i1.y, i0.z));
    float c01 = pattern_lerp(f.x, voxel_at(at, n, i0.x, i0.y, i1.z), voxel_at(at, n, i1.x, i0.y, i1.z));
    float c11 = pattern_lerp(f.x, voxel_at(at, n, i0.x, i1.y, i1.z), voxel_at(at, n, i1.x, i1.y, i1.z));
    return pattern_lerp(f.z, pattern_lerp(f.y, c00, c10), pattern_lerp(f.y, c01, c11));
}

// POV-Ray's ground fog density at texture-space point p (TEXTURE_GROUND_FOG): 1 up to
// `offset`, 1 / (1 + (y - offset) / alt)^2 above; the point is first moved by turbulence when
// `turb_at` holds a pattern block (its turbulence, octaves, omega and lambda).
float ground_fog_density(vec3 p, float offset, float alt, uint turb_at) {
    precise vec3 q = p;
    if (turb_at != NO_DATA) {
        vec3 turb = pattern_vec3_at(turb_at + PATTERN_TURBULENCE);
        q = p + turbulence_vector(p, texture_word(turb_at + PATTERN_OCTAVES), pattern_word(turb_at + PATTERN_OMEGA),
                                  pattern_word(turb_at + PATTERN_LAMBDA)) * turb;
    }
    precise float h = (q.y - offset) / alt;
    if (!(h > 0.0)) return 1.0;
    precise float k = 1.0 + h;
    return 1.0 / (k * k);
}

#endif  // VOXEL_GLSL
