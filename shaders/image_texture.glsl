// image_texture.glsl: image texture lookups in the shared texture buffer. CPU twin:
// src/cpu/image_texture.rs (the contracts and the block layout are written there, once).
// The including kernel declares
//   uint texture_word(uint i), word i of the texture data (scene_fetch.glsl, or a probe's buffer);
// An image is a block at word offset `at`: width, height, wrap, flags, then the texels row by row
// (row 0 = the file's top row), two words each: half R | half G << 16, half B | half A << 16.

// IMAGE_* constants come from constants.glsl (src/layout/constants.rs).

// Half-float bits to f32, exactly, subnormals included (the host writes no Inf or NaN).
float image_half_to_f32(uint h) {
    uint e = (h >> 10u) & 0x1fu;
    uint m = h & 0x3ffu;
    if (e == 0u) {
        float v = float(m) * uintBitsToFloat(0x33800000u);  // m * 2^-24, exact
        return (h & 0x8000u) != 0u ? -v : v;
    }
    return uintBitsToFloat(((h & 0x8000u) << 16u) | ((e + 112u) << 23u) | (m << 13u));
}

// Texel (i, j) of the block at `at` of width w; i < w, j < height.
vec4 image_fetch(uint at, uint w, uint i, uint j) {
    uint k = at + IMAGE_HEADER_WORDS + 2u * (j * w + i);
    uint rg = texture_word(k);
    uint ba = texture_word(k + 1u);
    return vec4(image_half_to_f32(rg & 0xffffu), image_half_to_f32(rg >> 16u), image_half_to_f32(ba & 0xffffu),
                image_half_to_f32(ba >> 16u));
}

// i modulo n, in [0, n) for negative i too (GLSL's % is undefined for negative operands).
uint image_repeat(int i, uint n) {
    return i >= 0 ? uint(i) % n : n - 1u - uint(-(i + 1)) % n;
}

// An integer texel index mapped into [0, n) by the wrap mode; unknown modes repeat.
uint image_wrap(int i, uint n, uint wrap) {
    if (wrap == IMAGE_WRAP_CLAMP) return uint(clamp(i, 0, int(n) - 1));
    if (wrap == IMAGE_WRAP_MIRROR) {
        uint m = image_repeat(i, 2u * n);
        return m < n ? m : 2u * n - 1u - m;
    }
    return image_repeat(i, n);
}

// A texel coordinate clamped to +-2^24 (where floats stop having fractions), NaN mapped to 0.
float image_coord(float x) {
    return x >= -IMAGE_COORD_LIMIT && x <= IMAGE_COORD_LIMIT ? x
         : x > IMAGE_COORD_LIMIT                             ? IMAGE_COORD_LIMIT
         : x < -IMAGE_COORD_LIMIT                            ? -IMAGE_COORD_LIMIT
                                                             : 0.0;
}

// The uv of texture-space point p under a TEXTURE_PROJECTION_*; contract in
// src/cpu/image_texture.rs. (GLSL's atan(0, 0) is undefined, hence the test.)
vec2 image_projection(vec3 p, uint projection) {
    if (projection != TEXTURE_PROJECTION_SPHERICAL && projection != TEXTURE_PROJECTION_CYLINDRICAL) return p.xy;
    float u = 0.0;
    if (p.x * p.x + p.z * p.z > 0.0) {
        u = atan(p.z, p.x) / 6.28318530717958647692;
        if (u < 0.0) u += 1.0;
    }
    if (projection == TEXTURE_PROJECTION_CYLINDRICAL) return vec2(u, p.y);
    float len = length(p);
    float v = 0.5;
    if (len > 0.0) v = 0.5 + asin(clamp(p.y / len, -1.0, 1.0)) / 3.14159265358979323846;
    return vec2(u, v);
}

// The texel whose square holds uv, no filtering.
vec4 image_texel(uint at, vec2 uv) {
    uint w = texture_word(at);
    uint h = texture_word(at + 1u);
    uint wrap = texture_word(at + 2u);
    precise float x = image_coord(float(w) * uv.x);
    precise float y = image_coord(float(h) * (1.0 - uv.y));
    return image_fetch(at, w, image_wrap(int(floor(x)), w, wrap), image_wrap(int(floor(y)), h, wrap));
}

// Bilinear lookup; contract in src/cpu/image_texture.rs. `precise` forbids fused multiply-adds
// and reordering, so the sums are rounded as on the CPU.
vec4 image_lookup(uint at, vec2 uv) {
    uint w = texture_word(at);
    uint h = texture_word(at + 1u);
    uint wrap = texture_word(at + 2u);
    precise float x = image_coord(float(w) * uv.x - 0.5);
    precise float y = image_coord(float(h) * (1.0 - uv.y) - 0.5);
    float x0 = floor(x);
    float y0 = floor(y);
    precise float fx = x - x0;
    precise float fy = y - y0;
    uint i0 = image_wrap(int(x0), w, wrap);
    uint i1 = image_wrap(int(x0) + 1, w, wrap);
    uint j0 = image_wrap(int(y0), h, wrap);
    uint j1 = image_wrap(int(y0) + 1, h, wrap);
    precise vec4 value = (1.0 - fx) * (1.0 - fy) * image_fetch(at, w, i0, j0) + fx * (1.0 - fy) * image_fetch(at, w, i1, j0)
                       + (1.0 - fx) * fy * image_fetch(at, w, i0, j1) + fx * fy * image_fetch(at, w, i1, j1);
    return value;
}
