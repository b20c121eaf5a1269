// Procedural 3D patterns with POV-Ray's names and parameters, colour maps and bump gradients.
// CPU twin: src/cpu/pattern.rs (contracts, block layout and sources are documented there).
//
// The including kernel declares, before including this file:
//   uint texture_word(uint i), word i of the texture data (scene_fetch.glsl, or a probe's buffer);
// Float arithmetic is written in the twin's order and stored in `precise` variables, which forbid
// fused multiply-adds, so that both sides round alike; sines come from pattern_sin_turns on both.
// Loops are bounded (at most 10 octaves, 125 crackle cells, 10 wave sources, 256 map entries),
// which keeps lavapipe under its limit of 65535 loop iterations per invocation.

#ifndef PATTERN_GLSL
#define PATTERN_GLSL

// Pattern kinds, wave shapes, the block layout and the limits come from constants.glsl
// (src/layout/constants.rs), which the including kernel includes first.

float pattern_word(uint i) { return uintBitsToFloat(texture_word(i)); }

vec3 pattern_vec3_at(uint i) { return vec3(pattern_word(i), pattern_word(i + 1u), pattern_word(i + 2u)); }

// PCG3D hash of Jarzynski and Olano, "Hash Functions for GPU Rendering" (JCGT 2020).
uvec3 pattern_pcg3d(uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    return v;
}

float pattern_unit(uint bits) { return float(bits >> 8u) * (1.0 / 16777216.0); }

float pattern_fract(float x) {
    precise float r = x - floor(x);
    return r;
}

// sin(2 pi t), POV-Ray's cycloidal; see sin_turns in the twin.
float pattern_sin_turns(float t) {
    float u = pattern_fract(t);
    precise float y = u < 0.25 ? u : (u < 0.75 ? 0.5 - u : u - 1.0);
    precise float y2 = y * y;
    precise float s = 3.8199525;
    s = s * y2 + -15.094643;
    s = s * y2 + 42.058693;
    s = s * y2 + -76.70586;
    s = s * y2 + 81.60525;
    s = s * y2 + -41.3417;
    s = s * y2 + 6.2831855;
    precise float r = s * y;
    return r;
}

float pattern_cos_turns(float t) {
    precise float u = t + 0.25;
    return pattern_sin_turns(u);
}

// atan2(s, c) / 2 pi in (-1/2, 1/2], Cephes' atanf; see atan2_turns in the twin.
float pattern_atan2_turns(float s, float c) {
    float a = abs(s);
    float b = abs(c);
    precise float t = a > b ? b / a : a / b;
    precise float base = 0.0;
    precise float x = t;
    if (t > 0.41421357) {
        base = 0.125;
        x = (t - 1.0) / (t + 1.0);
    }
    precise float z = x * x;
    precise float poly = (((0.080537446 * z - 0.13877685) * z + 0.19977711) * z - 0.3333295) * z * x + x;
    precise float r = base + poly * 0.15915494;
    if (a > b) r = 0.25 - r;
    if (c < 0.0) r = 0.5 - r;
    if (s < 0.0) r = -r;
    return r;
}

// ---- Noise ----------------------------------------------------------------------------------

// Perlin's gradient (Improving Noise, SIGGRAPH 2002) for h in 0..16, dotted with (x, y, z).
float pattern_grad(uint h, float x, float y, float z) {
    float u = h < 8u ? x : y;
    float v = h < 4u ? y : ((h == 12u || h == 14u) ? x : z);
    precise float r = ((h & 1u) == 0u ? u : -u) + ((h & 2u) == 0u ? v : -v);
    return r;
}

uint pattern_lattice_hash(ivec3 c, uint seed) {
    return pattern_pcg3d(uvec3(c) ^ uvec3(0u, 0u, seed * 0x9e3779b9u)).x >> 28u;
}

float pattern_lerp(float t, float a, float b) {
    precise float r = a + t * (b - a);
    return r;
}

float pattern_fade(float t) {
    precise float r = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    return r;
}

// Perlin's improved gradient noise of stream `seed`: signed, about [-1, 1], mean 0.
float noise_signed(vec3 p, uint seed) {
    // Never taken where it is false: the host sets it from the scene's patterns (pack.rs,
    // texture_uses_noise), and the driver drops the rest of the function.
    if (!SCENE_HAS_NOISE) return 0.0;
    vec3 fl = floor(p);
    ivec3 c = ivec3(fl);
    precise float x = p.x - fl.x;
    precise float y = p.y - fl.y;
    precise float z = p.z - fl.z;
    float u = pattern_fade(x);
    float v = pattern_fade(y);
    float w = pattern_fade(z);
    precise float x1 = x - 1.0;
    precise float y1 = y - 1.0;
    precise float z1 = z - 1.0;
    float g000 = pattern_grad(pattern_lattice_hash(c + ivec3(0, 0, 0), seed), x, y, z);
    float g100 = pattern_grad(pattern_lattice_hash(c + ivec3(1, 0, 0), seed), x1, y, z);
    float g010 = pattern_grad(pattern_lattice_hash(c + ivec3(0, 1, 0), seed), x, y1, z);
    float g110 = pattern_grad(pattern_lattice_hash(c + ivec3(1, 1, 0), seed), x1, y1, z);
    float g001 = pattern_grad(pattern_lattice_hash(c + ivec3(0, 0, 1), seed), x, y, z1);
    float g101 = pattern_grad(pattern_lattice_hash(c + ivec3(1, 0, 1), seed), x1, y, z1);
    float g011 = pattern_grad(pattern_lattice_hash(c + ivec3(0, 1, 1), seed), x, y1, z1);
    float g111 = pattern_grad(pattern_lattice_hash(c + ivec3(1, 1, 1), seed), x1, y1, z1);
    float a = pattern_lerp(v, pattern_lerp(u, g000, g100), pattern_lerp(u, g010, g110));
    float b = pattern_lerp(v, pattern_lerp(u, g001, g101), pattern_lerp(u, g011, g111));
    return pattern_lerp(w, a, b);
}

// POV-Ray's Noise: in [0, 1], mean 1/2.
float noise_unit(vec3 p) {
    precise float r = 0.5 + NOISE_UNIT_SCALE * noise_signed(p, 0u);
    return clamp(r, 0.0, 1.0);
}

// POV-Ray's DNoise: three independent signed noises.
vec3 noise_vector(vec3 p) {
    precise vec3 r = vec3(noise_signed(p, 1u), noise_signed(p, 2u), noise_signed(p, 3u)) * NOISE_VECTOR_SCALE;
    return r;
}

// POV-Ray's Turbulence with its default noise generator; see turbulence in the twin.
float turbulence(vec3 p, uint octaves, float omega, float lambda) {
    precise float value = clamp(2.0 * noise_unit(p) - 0.5, 0.0, 1.0);
    precise float l = lambda;
    precise float o = omega;
    uint n = clamp(octaves, 1u, MAX_OCTAVES);
    for (uint i = 1u; i < n; i++) {
        precise vec3 q = p * l;
        value += o * (2.0 * noise_unit(q) - 0.5);
        l *= lambda;
        o *= omega;
    }
    return value;
}

// POV-Ray's DTurbulence: vector noise summed over octaves.
vec3 turbulence_vector(vec3 p, uint octaves, float omega, float lambda) {
    precise vec3 value = noise_vector(p);
    precise float l = lambda;
    precise float o = omega;
    uint n = clamp(octaves, 1u, MAX_OCTAVES);
    for (uint i = 1u; i < n; i++) {
        precise vec3 q = p * l;
        value += noise_vector(q) * o;
        l *= lambda;
        o *= omega;
    }
    return value;
}

// ---- The patterns' raw values ---------------------------------------------------------------

float pattern_length3(float x, float y, float z) {
    precise float r = sqrt(x * x + y * y + z * z);
    return r;
}

float pattern_checker(vec3 p) {
    int s = int(floor(p.x)) + int(floor(p.y)) + int(floor(p.z));
    return (s & 1) == 1 ? 1.0 : 0.0;
}

float pattern_brick(vec3 p, vec3 size, float mortar) {
    precise float x = p.x + mortar;
    precise float y = p.y + mortar;
    precise float z = p.z + mortar;
    precise float yh = y / size.y;
    precise float mh = mortar / size.y;
    if (pattern_fract(yh) <= mh) return 0.0;
    precise float course = yh * 0.5;
    bool odd_course = pattern_fract(course) > 0.5;
    precise float xw = x / size.x;
    precise float xw_half = xw + 0.5;
    precise float mw = mortar / size.x;
    float joint_x = odd_course ? pattern_fract(xw_half) : pattern_fract(xw);
    if (joint_x <= mw) return 0.0;
    precise float zd = z / size.z;
    precise float zd_half = zd + 0.5;
    precise float md = mortar / size.z;
    float joint_z = odd_course ? pattern_fract(zd) : pattern_fract(zd_half);
    if (joint_z <= md) return 0.0;
    return 1.0;
}

float pattern_hexagon(vec3 p) {
    precise float q = p.x * 0.6666667;
    precise float r = p.z * 0.57735026 - 0.5 * q;
    precise float s = -q - r;
    precise float rq = floor(q + 0.5);
    precise float rr = floor(r + 0.5);
    precise float rs = floor(s + 0.5);
    precise float dq = abs(rq - q);
    precise float dr = abs(rr - r);
    precise float ds = abs(rs - s);
    if (dq > dr && dq > ds) {
        rq = -rr - rs;
    } else if (dr > ds) {
        rr = -rq - rs;
    }
    // GLSL leaves % of negative numbers undefined, so floor division is spelled out.
    int d = int(rr) - int(rq);
    int colour = d >= 0 ? d - 3 * (d / 3) : d + 3 * ((2 - d) / 3);
    return float(colour) * 0.5;
}

float pattern_crackle(vec3 p, vec3 form, float metric, float offset, bool solid) {
    vec3 fl = floor(p);
    ivec3 base = ivec3(fl);
    precise vec3 f = p - fl;
    float d1 = 3.0e38;
    float d2 = 3.0e38;
    float d3 = 3.0e38;
    vec3 nearest = vec3(0.0);
    for (int dz = -2; dz <= 2; dz++) {
        for (int dy = -2; dy <= 2; dy++) {
            for (int dx = -2; dx <= 2; dx++) {
                // POV-Ray's 81 cells: the 3x3x3 block and the 3x3 slab beyond each face.
                uint outer = uint(abs(dx) == 2) + uint(abs(dy) == 2) + uint(abs(dz) == 2);
                if (outer > 1u) continue;
                uvec3 h = pattern_pcg3d(uvec3(base + ivec3(dx, dy, dz)));
                precise vec3 feature = vec3(float(dx) + pattern_unit(h.x), float(dy) + pattern_unit(h.y),
                                            float(dz) + pattern_unit(h.z));
                precise vec3 v = feature - f;
                precise float d;
                if (metric == 2.0) {
                    d = v.x * v.x + v.y * v.y + v.z * v.z;
                } else if (metric == 1.0) {
                    d = abs(v.x) + abs(v.y) + abs(v.z);
                } else {
                    d = pow(abs(v.x), metric) + pow(abs(v.y), metric) + pow(abs(v.z), metric);
                }
                if (d < d1) {
                    d3 = d2;
                    d2 = d1;
                    d1 = d;
                    nearest = feature;
                } else if (d < d2) {
                    d3 = d2;
                    d2 = d;
                } else if (d < d3) {
                    d3 = d;
                }
            }
        }
    }
    if (solid) {
        precise vec3 cell_point = fl + nearest;
        return noise_unit(cell_point);
    }
    precise float value;
    if (metric == 2.0) {
        precise float o = offset * offset;
        value = form.x * sqrt(d1 + o) + form.y * sqrt(d2 + o) + form.z * sqrt(d3 + o);
    } else if (metric == 1.0) {
        value = form.x * (d1 + offset) + form.y * (d2 + offset) + form.z * (d3 + offset);
    } else {
        float o = pow(offset, metric);
        float e = 1.0 / metric;
        value = form.x * pow(d1 + o, e) + form.y * pow(d2 + o, e) + form.z * pow(d3 + o, e);
    }
    return clamp(value, 0.0, 1.0);
}

// Centre on the unit sphere of wave source i of ripples and waves.
vec3 pattern_wave_source(uint i) {
    uvec3 h = pattern_pcg3d(uvec3(i, 0x5eed0a7eu, 0u));
    precise float z = 1.0 - 2.0 * pattern_unit(h.x);
    float phi = pattern_unit(h.y);
    precise float r = sqrt(max(1.0 - z * z, 0.0));
    precise vec3 source = vec3(r * pattern_cos_turns(phi), r * pattern_sin_turns(phi), z);
    return source;
}

// POV-Ray's sequence of relative wave frequencies; see next_wave_frequency in the twin.
float pattern_next_wave_frequency(inout uint state) {
    state = state * 1812433253u + 12345u;
    precise float f = float((state >> 16u) & 0x7fffu) * 3.051851e-5 + 0.01;
    return f;
}

float pattern_ripples_or_waves(vec3 p, float frequency, float phase, bool waves) {
    precise float sum = 0.0;
    uint state = uint(-560851967);
    for (uint i = 0u; i < WAVE_SOURCES; i++) {
        vec3 source = pattern_wave_source(i);
        float f = pattern_next_wave_frequency(state);
        precise float dx = p.x - source.x;
        precise float dy = p.y - source.y;
        precise float dz = p.z - source.z;
        float dist = pattern_length3(dx, dy, dz);
        if (dist == 0.0) dist = 1.0;
        if (waves) {
            precise float arg = dist * frequency * f + phase;
            sum += pattern_sin_turns(arg) / f;
        } else {
            precise float arg = dist * frequency + phase;
            sum += pattern_sin_turns(arg);
        }
    }
    precise float r = waves ? 0.2 * (2.5 + sum * 0.1) : 0.5 * (1.0 + sum * 0.1);
    return r;
}

float pattern_raw(uint at, uint kind, vec3 p, vec3 turb, uint octaves, float omega, float lambda) {
    uint params = at + PATTERN_PARAMS;
    switch (kind) {
    case PATTERN_AGATE: {
        precise float t = pattern_word(params) * turbulence(p, octaves, omega, lambda);
        precise float arg = 1.3 * t + 1.1 * p.z;
        precise float n = 0.5 * (pattern_sin_turns(arg) + 1.0);
        return n <= 0.0 ? 0.0 : pow(min(n, 1.0), 0.77);
    }
    case PATTERN_BOZO:
    case PATTERN_BUMPS:
    case PATTERN_SPOTTED:
        return noise_unit(p);
    case PATTERN_BRICK:
        return pattern_brick(p, pattern_vec3_at(params), pattern_word(params + 3u));
    case PATTERN_CHECKER:
        return pattern_checker(p);
    case PATTERN_CRACKLE:
        return pattern_crackle(p, pattern_vec3_at(params), pattern_word(params + 3u), pattern_word(params + 4u),
                               texture_word(params + 5u) != 0u);
    case PATTERN_DENTS: {
        float n = noise_unit(p);
        precise float r = n * n * n;
        return r;
    }
    case PATTERN_GRADIENT: {
        vec3 g = pattern_vec3_at(params);
        precise float v = p.x * g.x + p.y * g.y + p.z * g.z;
        return v > 1.0 ? pattern_fract(v) : v;
    }
    case PATTERN_GRANITE: {
        precise vec3 p4 = p * 4.0;
        precise float value = 0.0;
        precise float freq = 1.0;
        for (uint i = 0u; i < 6u; i++) {
            precise vec3 q = p4 * freq;
            precise float n = min(abs(1.0 - 2.0 * noise_unit(q)), 0.5);
            value += n / freq;
            freq *= 2.0;
        }
        return value;
    }
    case PATTERN_HEXAGON:
        return pattern_hexagon(p);
    case PATTERN_LEOPARD: {
        const float INV_TWO_PI = 0.15915494;
        precise float ax = p.x * INV_TWO_PI;
        precise float ay = p.y * INV_TWO_PI;
        precise float az = p.z * INV_TWO_PI;
        precise float s = (pattern_sin_turns(ax) + pattern_sin_turns(ay) + pattern_sin_turns(az)) * 0.33333334;
        precise float r = s * s;
        return r;
    }
    case PATTERN_MARBLE: {
        if (turb.x == 0.0) return p.x;
        precise float r = p.x + turb.x * turbulence(p, octaves, omega, lambda);
        return r;
    }
    case PATTERN_ONION:
        return pattern_fract(pattern_length3(p.x, p.y, p.z));
    case PATTERN_RADIAL: {
        if (abs(p.x) < 0.001 && abs(p.z) < 0.001) return 0.25;
        precise float r = 0.75 + pattern_atan2_turns(p.x, p.z);
        return r;
    }
    case PATTERN_RIPPLES:
    case PATTERN_WAVES:
        return pattern_ripples_or_waves(p, pattern_word(at + PATTERN_FREQUENCY), pattern_word(at + PATTERN_PHASE),
                                        kind == PATTERN_WAVES);
    case PATTERN_WOOD: {
        precise float x = p.x;
        precise float y = p.y;
        if (turb.x != 0.0 || turb.y != 0.0) {
            vec3 d = turbulence_vector(p, octaves, omega, lambda);
            precise float ax = (p.x + d.x) * turb.x;
            precise float ay = (p.y + d.y) * turb.y;
            x += pattern_sin_turns(ax);
            y += pattern_sin_turns(ay);
        }
        precise float r = sqrt(x * x + y * y);
        return r;
    }
    case PATTERN_WRINKLES: {
        precise float value = clamp(2.0 * noise_unit(p) - 0.5, 0.0, 1.0);
        precise float l = 2.0;
        precise float o = 0.5;
        for (uint i = 1u; i < 10u; i++) {
            precise vec3 q = p * l;
            value += o * clamp(2.0 * noise_unit(q) - 0.5, 0.0, 1.0);
            l *= 2.0;
            o *= 0.5;
        }
        precise float r = value * 0.5;
        return r;
    }
    }
    return 0.0;  // unreachable: the host packs only known kinds (tested)
}

// ---- Warps (POV-Ray 3.7 warp.cpp); see warp_point in the twin -------------------------------

float pattern_whole_turn(float r) {
    precise float w = r + 1.0;
    return r < 0.0 ? w : r;
}

vec3 pattern_orient(vec3 o, float x, float y, float z) {
    if (o.x == 0.0 && o.y == 0.0 && o.z == 1.0) return vec3(x, y, z);
    precise float rx = o.x * z + o.y * x + o.z * x;
    precise float ry = o.x * y + o.y * -z + o.z * y;
    precise float rz = o.x * -x + o.y * y + o.z * z;
    return vec3(rx, ry, rz);
}

float pattern_dist_scale(float d, float e) {
    if (e == 1.0) return d;
    if (e != 0.0) return pow(d, e);
    return 1.0;
}

vec3 warp_point(uint w, vec3 p) {
    uint kind = texture_word(w);
    uint a = w + WARP_PARAMS;
    precise vec3 q = p;
    switch (kind) {
    case WARP_REPEAT: {
        uint axis = min(texture_word(a), 2u);
        float width = pattern_word(a + 1u);
        vec3 offset = pattern_vec3_at(a + 2u);
        vec3 flip = pattern_vec3_at(a + 5u);
        precise float block = floor(q[axis] / width);
        q[axis] -= block * width;
        if ((int(block) & 1) != 0) {
            q = vec3(q.x * flip.x, q.y * flip.y, q.z * flip.z);
            if (flip[axis] < 0.0) q[axis] += width;
        }
        q = vec3(q.x + block * offset.x, q.y + block * offset.y, q.z + block * offset.z);
        break;
    }
    case WARP_BLACK_HOLE: {
        precise vec3 c = pattern_vec3_at(a);
        float radius = pattern_word(a + 3u);
        vec3 repeat_by = pattern_vec3_at(a + 7u);
        for (uint i = 0u; i < 3u; i++) {
            if (repeat_by[i] > 0.0) c[i] += repeat_by[i] * floor(q[i] / repeat_by[i]);
        }
        precise vec3 d = vec3(q.x - c.x, q.y - c.y, q.z - c.z);
        float len = pattern_length3(d.x, d.y, d.z);
        if (len < radius) {
            precise float from_edge = (radius - len) / radius;
            precise float strength = min(pow(from_edge, pattern_word(a + 5u)) * pattern_word(a + 4u), 1.0);
            float s = texture_word(a + 6u) != 0u ? -strength : strength;
            q = vec3(q.x + d.x * s, q.y + d.y * s, q.z + d.z * s);
        }
        break;
    }
    case WARP_CYLINDRICAL: {
        precise float len = sqrt(q.x * q.x + q.z * q.z);
        if (len != 0.0) {
            precise float theta = pattern_whole_turn(pattern_atan2_turns(q.z, q.x)) *
                                  pattern_dist_scale(len, pattern_word(a + 3u));
            q = pattern_orient(pattern_vec3_at(a), theta, q.y, len);
        }
        break;
    }
    case WARP_SPHERICAL: {
        float dist = pattern_length3(q.x, q.y, q.z);
        if (dist != 0.0) {
            precise float x = q.x / dist;
            precise float y = q.y / dist;
            precise float z = q.z / dist;
            precise float len = sqrt(x * x + z * z);
            precise float phi = 0.5 + 2.0 * pattern_atan2_turns(y, len);
            float theta = len == 0.0 ? 0.0 : pattern_whole_turn(pattern_atan2_turns(z, x));
            float k = pattern_dist_scale(dist, pattern_word(a + 3u));
            precise float tk = theta * k;
            precise float pk = phi * k;
            q = pattern_orient(pattern_vec3_at(a), tk, pk, dist);
        }
        break;
    }
    case WARP_TOROIDAL: {
        precise float len = sqrt(q.x * q.x + q.z * q.z);
        if (len != 0.0) {
            float theta = pattern_whole_turn(pattern_atan2_turns(q.z, q.x));
            precise float x = len - pattern_word(a + 4u);
            precise float tube = sqrt(x * x + q.y * q.y);
            float phi = tube == 0.0 ? 0.0 : pattern_whole_turn(pattern_atan2_turns(-q.y, -x));
            float k = pattern_dist_scale(tube, pattern_word(a + 3u));
            precise float tk = theta * k;
            precise float pk = phi * k;
            q = pattern_orient(pattern_vec3_at(a), tk, pk, tube);
        }
        break;
    }
    case WARP_PLANAR:
        q = pattern_orient(pattern_vec3_at(a), q.x, q.y, pattern_word(a + 3u));
        break;
    }
    uint m = w + WARP_MATRIX;
    vec3 cx = pattern_vec3_at(m);
    vec3 cy = pattern_vec3_at(m + 3u);
    vec3 cz = pattern_vec3_at(m + 6u);
    vec3 t = pattern_vec3_at(m + 9u);
    precise float rx = cx.x * q.x + cy.x * q.y + cz.x * q.z + t.x;
    precise float ry = cx.y * q.x + cy.y * q.y + cz.y * q.z + t.y;
    precise float rz = cx.z * q.x + cy.z * q.y + cz.z * q.z + t.z;
    return vec3(rx, ry, rz);
}

// Frequency, phase and wave shape as POV-Ray's ContinuousPattern::Evaluate; see the twin.
float pattern_wave(float value, uint wave, float frequency, float phase, float exponent) {
    precise float v = value;
    if (frequency != 0.0) {
        precise float a = v * frequency + phase;
        precise float q = a * 0.99999;
        v = a - 1.00001 * trunc(q);
    }
    if (v < 0.0) v -= floor(v);
    precise float shaped = v;
    switch (wave) {
    case WAVE_SINE:
        shaped = (1.0 + pattern_sin_turns(v)) * 0.5;
        break;
    case WAVE_TRIANGLE: {
        precise float offset = pattern_fract(v);
        shaped = offset >= 0.5 ? 2.0 * (1.0 - offset) : 2.0 * offset;
        break;
    }
    case WAVE_SCALLOP: {
        precise float half_v = v * 0.5;
        shaped = abs(pattern_sin_turns(half_v));
        break;
    }
    case WAVE_CUBIC:
        shaped = v * v * (-2.0 * v + 3.0);
        break;
    case WAVE_POLY:
        shaped = v <= 0.0 ? 0.0 : pow(v, exponent);
        break;
    }
    return clamp(shaped, 0.0, 1.0);
}

// The pattern block at `at` at point p in pattern space, in [0, 1]. Contract: pattern_value in
// src/cpu/pattern.rs.
float pattern_value(uint at, vec3 p) {
    uint kind = texture_word(at + PATTERN_KIND);
    vec3 turb = pattern_vec3_at(at + PATTERN_TURBULENCE);
    uint octaves = texture_word(at + PATTERN_OCTAVES);
    float omega = pattern_word(at + PATTERN_OMEGA);
    float lambda = pattern_word(at + PATTERN_LAMBDA);
    // The warps, in the order packed (POV-Ray's last written first), then turbulence.
    precise vec3 pw = p;
    uint warps = min(texture_word(at + PATTERN_WARP_COUNT), MAX_WARPS);
    for (uint i = 0u; i < warps; i++) pw = warp_point(at + PATTERN_WORDS + i * WARP_WORDS, pw);
    precise vec3 q = pw;
    if (kind != PATTERN_MARBLE && kind != PATTERN_WOOD && turb != vec3(0.0)) {
        q = pw + turbulence_vector(pw, octaves, omega, lambda) * turb;
    }
    float raw = pattern_raw(at, kind, q, turb, octaves, omega, lambda);
    if (kind == PATTERN_CHECKER || kind == PATTERN_BRICK || kind == PATTERN_HEXAGON) return raw;
    return pattern_wave(raw, texture_word(at + PATTERN_WAVE), pattern_word(at + PATTERN_FREQUENCY),
                        pattern_word(at + PATTERN_PHASE), pattern_word(at + PATTERN_EXPONENT));
}

// Central differences of step h (6 evaluations); contract: pattern_gradient in the twin.
vec3 pattern_gradient(uint at, vec3 p, float h) {
    precise float two_h = h + h;
    precise float xp = p.x + h;
    precise float xm = p.x - h;
    precise float yp = p.y + h;
    precise float ym = p.y - h;
    precise float zp = p.z + h;
    precise float zm = p.z - h;
    precise float dx = pattern_value(at, vec3(xp, p.y, p.z)) - pattern_value(at, vec3(xm, p.y, p.z));
    precise float dy = pattern_value(at, vec3(p.x, yp, p.z)) - pattern_value(at, vec3(p.x, ym, p.z));
    precise float dz = pattern_value(at, vec3(p.x, p.y, zp)) - pattern_value(at, vec3(p.x, p.y, zm));
    precise vec3 g = vec3(dx / two_h, dy / two_h, dz / two_h);
    return g;
}

// The colour map block at `at` at value v (POV-Ray's BlendMap::Search); contract in the twin.
vec3 color_map_eval(uint at, float v) {
    uint n = min(texture_word(at), MAX_COLOR_MAP_ENTRIES);
    if (n == 0u) return vec3(0.0);  // unreachable: the host packs at least one entry (validated)
    uint last = n - 1u;
    if (v >= pattern_word(at + 1u + 4u * last)) return pattern_vec3_at(at + 2u + 4u * last);
    uint i = 0u;
    while (i < last && v > pattern_word(at + 1u + 4u * i)) i++;
    float p1 = pattern_word(at + 1u + 4u * i);
    if (i == 0u || v == p1) return pattern_vec3_at(at + 2u + 4u * i);
    float p0 = pattern_word(at + 1u + 4u * (i - 1u));
    precise float w0 = (p1 - v) / (p1 - p0);
    precise float w1 = 1.0 - w0;
    vec3 c0 = pattern_vec3_at(at + 2u + 4u * (i - 1u));
    vec3 c1 = pattern_vec3_at(at + 2u + 4u * i);
    precise vec3 c = vec3(c0.x * w0 + c1.x * w1, c0.y * w0 + c1.y * w1, c0.z * w0 + c1.z * w1);
    return c;
}

// A scalar map is a colour map with grey entries.
float scalar_map_eval(uint at, float v) { return color_map_eval(at, v).x; }

#endif  // PATTERN_GLSL
