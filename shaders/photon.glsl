// The 20-byte stored photon: packing and unpacking. CPU twin: src/cpu/photon.rs (bit-identical).
// flux_rg: half-float R (low 16 bits) and G (high 16); flux_b_dir: half-float B (bits 0-15),
// octahedral direction toward the light (u bits 16-22, v bits 23-29), PHOTON_FLAG_* (bits 30-31).
// Flux is stored divided by the map's flux scale so that halves stay near 1. Flux is never negative,
// so the three halves' sign bits carry the signs of the normal the photon landed on (x, y, z).

// f32 -> f16 bits, round to nearest even; values below the smallest normal half flush to zero and
// values above the largest finite half clamp to it. Integer-only so both sides agree exactly.
uint f32_to_f16(float v) {
    uint b = floatBitsToUint(v);
    uint sign = (b >> 16u) & 0x8000u;
    int e = int((b >> 23u) & 0xffu) - 112;  // rebias 127 -> 15
    uint m = b & 0x7fffffu;
    if (e <= 0) return sign;
    if (e >= 31) return sign | 0x7bffu;
    uint h = sign | (uint(e) << 10u) | (m >> 13u);
    uint rest = m & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u) == 1u)) h += 1u;
    return min(h & 0x7fffu, 0x7bffu) | sign;
}

float f16_to_f32(uint h) {
    uint e = (h >> 10u) & 0x1fu;
    if (e == 0u) return 0.0;
    return uintBitsToFloat(((h & 0x8000u) << 16u) | ((e + 112u) << 23u) | ((h & 0x3ffu) << 13u));
}

// Octahedral map of a unit vector to [0, 127]^2 (Meyer et al. 2010).
uint oct_encode(vec3 d) {
    vec3 p = d / (abs(d.x) + abs(d.y) + abs(d.z));
    vec2 q = p.xy;
    if (p.z < 0.0) {
        q = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
    }
    uvec2 u = uvec2(clamp(floor((q * 0.5 + 0.5) * 127.0 + 0.5), 0.0, 127.0));
    return u.x | (u.y << 7u);
}

vec3 oct_decode(uint bits) {
    vec2 q = vec2(float(bits & 127u), float((bits >> 7u) & 127u)) * (2.0 / 127.0) - 1.0;
    vec3 v = vec3(q, 1.0 - abs(q.x) - abs(q.y));
    if (v.z < 0.0) {
        v.xy = (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
    }
    return normalize(v);
}

// A half of a non-negative flux, its sign bit carrying `negative` (the landing side, see the twin).
uint photon_half(float v, bool negative) { return (f32_to_f16(v) & 0x7fffu) | (negative ? 0x8000u : 0u); }

// `side`: the surface's normal facing the photon (zero in a medium).
Photon pack_photon(vec3 position, vec3 flux, float inv_flux_scale, vec3 wi, vec3 side, uint flags) {
    vec3 f = flux * inv_flux_scale;
    Photon p;
    p.position[0] = position.x;
    p.position[1] = position.y;
    p.position[2] = position.z;
    p.flux_rg = photon_half(f.r, side.x < 0.0) | (photon_half(f.g, side.y < 0.0) << 16u);
    p.flux_b_dir = photon_half(f.b, side.z < 0.0) | (oct_encode(wi) << 16u) | (flags << 30u);
    return p;
}

vec3 photon_flux(Photon p, float flux_scale) {
    return vec3(f16_to_f32(p.flux_rg & 0x7fffu), f16_to_f32((p.flux_rg >> 16u) & 0x7fffu), f16_to_f32(p.flux_b_dir & 0x7fffu)) * flux_scale;
}

// The signs of the normal the photon landed on: bit k set where component k is negative.
uint photon_side(Photon p) {
    return ((p.flux_rg >> 15u) & 1u) | ((p.flux_rg >> 30u) & 2u) | ((p.flux_b_dir >> 13u) & 4u);
}

// Whether a photon of normal signs `side` landed on the side a lookup of facing normal n sees
// (see the twin for why the largest component decides).
bool photon_on_side(uint side, vec3 n) {
    vec3 a = abs(n);
    uint k = (a.x >= a.y && a.x >= a.z) ? 0u : (a.y >= a.z ? 1u : 2u);
    float nk = k == 0u ? n.x : (k == 1u ? n.y : n.z);
    return ((side >> k) & 1u) == (nk < 0.0 ? 1u : 0u);
}

vec3 photon_wi(Photon p) { return oct_decode((p.flux_b_dir >> 16u) & 0x3fffu); }

uint photon_flags(Photon p) { return p.flux_b_dir >> 30u; }
