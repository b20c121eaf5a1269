//! Procedural 3D patterns with POV-Ray's names and parameters; twin of `shaders/pattern.glsl`.
//!
//! The integer parts (lattice hashes, cell indices, gradient choices, loop orders) are identical
//! on both sides, and the float arithmetic is written in the same order with the GLSL side marked
//! `precise` (no fused multiply-add), so most patterns agree bit for bit. Sines come from the
//! polynomial [`sin_turns`] on both sides for the same reason; only `pow` (agate, `poly` wave,
//! crackle with a metric other than 1 or 2) is the driver's own. `tests/pattern_gpu.rs` measures
//! the agreement.
//!
//! A pattern is a block of [`PATTERN_WORDS`] words in the `texture_data` buffer, written by
//! `scene::pattern::PatternDesc::pack`:
//!
//! | word | content |
//! | --- | --- |
//! | 0 | kind, `PATTERN_*` |
//! | 1 | wave shape, `WAVE_*` |
//! | 2 | octaves, 1..=10 |
//! | 3, 4 | omega, lambda (f32) |
//! | 5, 6, 7 | turbulence amount x, y, z (f32) |
//! | 8, 9 | frequency, phase (f32) |
//! | 10 | exponent of the `poly` wave (f32) |
//! | 11 | reserved, 0 |
//! | 12..20 | per-kind parameters (f32 unless noted), unused words 0 |
//!
//! Per-kind parameters: gradient: direction x, y, z. brick: brick size x, y, z, mortar.
//! crackle: form x, y, z, metric, offset, solid (u32 0 or 1). agate: agate_turb.
//!
//! A colour map is a block of 1 + 4n words: n (1..=256), then n entries (position, r, g, b) in
//! non-decreasing position order.
//!
//! The pipeline is POV-Ray 3.7's (source/core/material/pattern.cpp, ContinuousPattern::Evaluate):
//! the turbulence warp moves the point (except for marble and wood, which use their turbulence
//! themselves), the pattern gives its raw value, then `frequency` and `phase` and the wave shape
//! map it into [0, 1]. The discrete patterns (checker, brick, hexagon) skip the wave stage, as in
//! POV-Ray. The result is clamped to [0, 1].

use glam::Vec3;

// Pattern kinds, wave shapes, block layout and limits: shared with the kernel through
// src/layout/constants.rs.
pub use crate::layout::constants::{
    MAX_COLOR_MAP_ENTRIES, MAX_OCTAVES, MAX_WARPS, PATTERN_AGATE, PATTERN_BOZO, PATTERN_BRICK, PATTERN_BUMPS,
    PATTERN_CHECKER, PATTERN_CRACKLE, PATTERN_DENTS, PATTERN_EXPONENT, PATTERN_FREQUENCY, PATTERN_GRADIENT,
    PATTERN_GRANITE, PATTERN_HEXAGON, PATTERN_KIND, PATTERN_KIND_COUNT, PATTERN_LAMBDA, PATTERN_LEOPARD,
    PATTERN_MARBLE, PATTERN_OCTAVES, PATTERN_OMEGA, PATTERN_ONION, PATTERN_PARAMS, PATTERN_PHASE, PATTERN_RADIAL,
    PATTERN_RIPPLES, PATTERN_SPOTTED, PATTERN_TURBULENCE, PATTERN_WARP_COUNT, PATTERN_WAVE, PATTERN_WAVES,
    PATTERN_WOOD, PATTERN_WORDS, PATTERN_WRINKLES, WARP_BLACK_HOLE, WARP_CYLINDRICAL, WARP_KIND_COUNT, WARP_MATRIX,
    WARP_PARAMS, WARP_PLANAR, WARP_REPEAT, WARP_SPHERICAL, WARP_TOROIDAL, WARP_WORDS, WAVE_CUBIC, WAVE_POLY, WAVE_RAMP,
    WAVE_SCALLOP, WAVE_SINE, WAVE_SOURCES, WAVE_TRIANGLE,
};
use crate::layout::constants::{NOISE_UNIT_SCALE, NOISE_VECTOR_SCALE};

pub fn word(data: &[u32], i: u32) -> f32 {
    f32::from_bits(data[i as usize])
}

pub fn vec3_at(data: &[u32], i: u32) -> Vec3 {
    Vec3::new(word(data, i), word(data, i + 1), word(data, i + 2))
}

/// PCG3D hash of Jarzynski and Olano, "Hash Functions for GPU Rendering" (JCGT 2020).
pub fn pattern_pcg3d(v: [u32; 3]) -> [u32; 3] {
    let mut v = v.map(|x| x.wrapping_mul(1664525).wrapping_add(1013904223));
    pcg3d_mix(&mut v);
    for x in &mut v {
        *x ^= *x >> 16;
    }
    pcg3d_mix(&mut v);
    v
}

fn pcg3d_mix(v: &mut [u32; 3]) {
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
}

/// 24 hash bits as a float in [0, 1), exact in f32.
fn unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// sin(2 pi t): POV-Ray's `cycloidal` (texture.cpp). A degree-13 Taylor polynomial on a quarter
/// period, absolute error below 3e-7 (2.5 ulp at 1), used on both sides so that they agree bit
/// for bit.
pub fn sin_turns(t: f32) -> f32 {
    // Fold t into [-1/4, 1/4] with the same sine: t, 1/2 - t or t - 1. Each step is exact.
    let u = fract(t);
    let y = if u < 0.25 {
        u
    } else if u < 0.75 {
        0.5 - u
    } else {
        u - 1.0
    };
    let y2 = y * y;
    // (-1)^k (2 pi)^(2k+1) / (2k+1)!, rounded to f32.
    let mut s = 3.819_952_5_f32;
    s = s * y2 + -15.094_643;
    s = s * y2 + 42.058_693;
    s = s * y2 + -76.705_86;
    s = s * y2 + 81.605_25;
    s = s * y2 + -41.341_7;
    s = s * y2 + 6.283_185_5;
    s * y
}

/// cos(2 pi t).
pub fn cos_turns(t: f32) -> f32 {
    sin_turns(t + 0.25)
}

/// atan2(s, c) / 2 pi, in (-1/2, 1/2]: the angle in turns of (c, s), for (c, s) not (0, 0).
/// Cephes' atanf (a degree-9 odd polynomial after reducing the ratio below tan(pi/8)), absolute
/// error below 2e-8 turns; used on both sides, like [`sin_turns`], so that they agree bit for bit.
pub fn atan2_turns(s: f32, c: f32) -> f32 {
    let a = s.abs();
    let b = c.abs();
    // The ratio of the smaller to the larger leg, in [0, 1].
    let t = if a > b { b / a } else { a / b };
    let (base, x) = if t > 0.414_213_57 { (0.125f32, (t - 1.0) / (t + 1.0)) } else { (0.0f32, t) };
    let z = x * x;
    let poly = (((0.080_537_446 * z - 0.138_776_85) * z + 0.199_777_11) * z - 0.333_329_5) * z * x + x;
    let mut r = base + poly * 0.159_154_94;
    if a > b {
        r = 0.25 - r;
    }
    if c < 0.0 {
        r = 0.5 - r;
    }
    if s < 0.0 {
        r = -r;
    }
    r
}

// ---------------------------------------------------------------------------------------------
// Noise
// ---------------------------------------------------------------------------------------------

/// Perlin's gradient for hash `h` in 0..16 (the 12 cube edge directions, 4 of them twice), dotted
/// with (x, y, z). Ken Perlin, "Improving Noise", SIGGRAPH 2002.
fn grad(h: u32, x: f32, y: f32, z: f32) -> f32 {
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// Gradient index of lattice point `c` for noise stream `seed`: a hash in place of Perlin's
/// permutation table, so the shader needs no table in memory.
fn lattice_hash(cx: i32, cy: i32, cz: i32, seed: u32) -> u32 {
    let h = pattern_pcg3d([cx as u32, cy as u32, (cz as u32) ^ seed.wrapping_mul(0x9e37_79b9)]);
    h[0] >> 28
}

pub fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Perlin's improved gradient noise (2002) of stream `seed`: signed, about [-1, 1], mean 0,
/// zero at lattice points, C2-continuous.
pub fn noise_signed(p: Vec3, seed: u32) -> f32 {
    let fl = p.floor();
    let (cx, cy, cz) = (fl.x as i32, fl.y as i32, fl.z as i32);
    let (x, y, z) = (p.x - fl.x, p.y - fl.y, p.z - fl.z);
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let (x1, y1, z1) = (x - 1.0, y - 1.0, z - 1.0);
    let (cx1, cy1, cz1) = (cx.wrapping_add(1), cy.wrapping_add(1), cz.wrapping_add(1));
    let g000 = grad(lattice_hash(cx, cy, cz, seed), x, y, z);
    let g100 = grad(lattice_hash(cx1, cy, cz, seed), x1, y, z);
    let g010 = grad(lattice_hash(cx, cy1, cz, seed), x, y1, z);
    let g110 = grad(lattice_hash(cx1, cy1, cz, seed), x1, y1, z);
    let g001 = grad(lattice_hash(cx, cy, cz1, seed), x, y, z1);
    let g101 = grad(lattice_hash(cx1, cy, cz1, seed), x1, y, z1);
    let g011 = grad(lattice_hash(cx, cy1, cz1, seed), x, y1, z1);
    let g111 = grad(lattice_hash(cx1, cy1, cz1, seed), x1, y1, z1);
    let a = lerp(v, lerp(u, g000, g100), lerp(u, g010, g110));
    let b = lerp(v, lerp(u, g001, g101), lerp(u, g011, g111));
    lerp(w, a, b)
}

/// POV-Ray's `Noise`: in [0, 1], mean 1/2, spread like POV-Ray 3.7's default generator.
pub fn noise_unit(p: Vec3) -> f32 {
    (0.5 + NOISE_UNIT_SCALE * noise_signed(p, 0)).clamp(0.0, 1.0)
}

/// POV-Ray's `DNoise`: three independent signed noises, each within [-0.95, 0.95], mean 0.
pub fn noise_vector(p: Vec3) -> Vec3 {
    Vec3::new(noise_signed(p, 1), noise_signed(p, 2), noise_signed(p, 3)) * NOISE_VECTOR_SCALE
}

fn octaves_bounded(octaves: u32) -> u32 {
    octaves.clamp(1, MAX_OCTAVES)
}

/// POV-Ray's scalar `Turbulence` (noise.cpp) with its default noise generator: octave i (from 0)
/// adds omega^i (2 Noise(p lambda^i) - 1/2), the first octave clipped to [0, 1]. Positive
/// everywhere but in rare troughs; about 1 on average for omega 1/2.
pub fn turbulence(p: Vec3, octaves: u32, omega: f32, lambda: f32) -> f32 {
    let mut value = (2.0 * noise_unit(p) - 0.5).clamp(0.0, 1.0);
    let mut l = lambda;
    let mut o = omega;
    for _ in 1..octaves_bounded(octaves) {
        value += o * (2.0 * noise_unit(p * l) - 0.5);
        l *= lambda;
        o *= omega;
    }
    value
}

/// POV-Ray's `DTurbulence`: the vector noise summed over octaves, octave i scaled by omega^i at
/// frequency lambda^i. The turbulence warp moves a point by this times the turbulence amount.
pub fn turbulence_vector(p: Vec3, octaves: u32, omega: f32, lambda: f32) -> Vec3 {
    let mut value = noise_vector(p);
    let mut l = lambda;
    let mut o = omega;
    for _ in 1..octaves_bounded(octaves) {
        value += noise_vector(p * l) * o;
        l *= lambda;
        o *= omega;
    }
    value
}

// ---------------------------------------------------------------------------------------------
// The patterns' raw values (POV-Ray 3.7 pattern.cpp, `EvaluateRaw` of each pattern)
// ---------------------------------------------------------------------------------------------

fn length3(x: f32, y: f32, z: f32) -> f32 {
    (x * x + y * y + z * z).sqrt()
}

/// 3D checker: 1 where floor(x) + floor(y) + floor(z) is odd, else 0.
fn checker(p: Vec3) -> f32 {
    let s = (p.x.floor() as i32).wrapping_add(p.y.floor() as i32).wrapping_add(p.z.floor() as i32);
    if s & 1 == 1 {
        1.0
    } else {
        0.0
    }
}

/// Bricks of `size` with mortar joints `mortar` thick: 0 in the mortar, 1 in a brick (POV-Ray's
/// colour 1 is the mortar). Courses are `size.y` high; alternate courses shift their joints by
/// half a brick along x and along z.
fn brick(p: Vec3, size: Vec3, mortar: f32) -> f32 {
    let x = p.x + mortar;
    let y = p.y + mortar;
    let z = p.z + mortar;
    if fract(y / size.y) <= mortar / size.y {
        return 0.0; // bed joint
    }
    let odd_course = fract(y / size.y * 0.5) > 0.5;
    let joint_x = if odd_course { fract(x / size.x + 0.5) } else { fract(x / size.x) };
    if joint_x <= mortar / size.x {
        return 0.0; // head joint seen from the front
    }
    let joint_z = if odd_course { fract(z / size.z) } else { fract(z / size.z + 0.5) };
    if joint_z <= mortar / size.z {
        return 0.0; // head joint seen from the side
    }
    1.0
}

/// Hexagons in the x-z plane, unit circumradius, corners on the x axis, the one at the origin
/// centred there: 0, 0.5 or 1 for POV-Ray's three colours, laid out as POV-Ray does.
fn hexagon(p: Vec3) -> f32 {
    // Axial coordinates: centres at i (1.5, sqrt(3)/2) + j (0, sqrt(3)); rounded in cube space.
    let q = p.x * 0.666_666_7;
    let r = p.z * 0.577_350_26 - 0.5 * q;
    let s = -q - r;
    let mut rq = (q + 0.5).floor();
    let mut rr = (r + 0.5).floor();
    let rs = (s + 0.5).floor();
    let (dq, dr, ds) = ((rq - q).abs(), (rr - r).abs(), (rs - s).abs());
    if dq > dr && dq > ds {
        rq = -rr - rs;
    } else if dr > ds {
        rr = -rq - rs;
    }
    // The origin's hexagon is colour 0; its neighbour at +z colour 1, at +x colour 2.
    let colour = ((rr as i32).wrapping_sub(rq as i32)).rem_euclid(3);
    colour as f32 * 0.5
}

/// Worley's cellular noise as POV-Ray's crackle: one feature point per unit cell, distances d1 <=
/// d2 <= d3 to the three nearest under `metric`, value form . (d1, d2, d3). `solid` gives each
/// cell the noise at its feature point instead. The 81 cells searched are POV-Ray's: the 3x3x3
/// block around the point and the 3x3 slab beyond each face. A nearer point outside them takes
/// an unlikely layout; the test `crackle_finds_the_nearest_feature_points` finds none.
fn crackle(p: Vec3, form: Vec3, metric: f32, offset: f32, solid: bool) -> f32 {
    let fl = p.floor();
    let (bx, by, bz) = (fl.x as i32, fl.y as i32, fl.z as i32);
    let f = p - fl;
    let (mut d1, mut d2, mut d3) = (3.0e38f32, 3.0e38f32, 3.0e38f32);
    let mut nearest = Vec3::ZERO;
    for dz in -2i32..=2 {
        for dy in -2i32..=2 {
            for dx in -2i32..=2 {
                let far = (dx.abs() == 2) as u32 + (dy.abs() == 2) as u32 + (dz.abs() == 2) as u32;
                if far > 1 {
                    continue;
                }
                let h =
                    pattern_pcg3d([bx.wrapping_add(dx) as u32, by.wrapping_add(dy) as u32, bz.wrapping_add(dz) as u32]);
                let feature = Vec3::new(dx as f32 + unit(h[0]), dy as f32 + unit(h[1]), dz as f32 + unit(h[2]));
                let v = feature - f;
                let d = if metric == 2.0 {
                    v.x * v.x + v.y * v.y + v.z * v.z
                } else if metric == 1.0 {
                    v.x.abs() + v.y.abs() + v.z.abs()
                } else {
                    v.x.abs().powf(metric) + v.y.abs().powf(metric) + v.z.abs().powf(metric)
                };
                if d < d1 {
                    d3 = d2;
                    d2 = d1;
                    d1 = d;
                    nearest = feature;
                } else if d < d2 {
                    d3 = d2;
                    d2 = d;
                } else if d < d3 {
                    d3 = d;
                }
            }
        }
    }
    if solid {
        return noise_unit(fl + nearest);
    }
    let value = if metric == 2.0 {
        let o = offset * offset;
        form.x * (d1 + o).sqrt() + form.y * (d2 + o).sqrt() + form.z * (d3 + o).sqrt()
    } else if metric == 1.0 {
        form.x * (d1 + offset) + form.y * (d2 + offset) + form.z * (d3 + offset)
    } else {
        let o = offset.powf(metric);
        let e = 1.0 / metric;
        form.x * (d1 + o).powf(e) + form.y * (d2 + o).powf(e) + form.z * (d3 + o).powf(e)
    };
    value.clamp(0.0, 1.0)
}

/// Centre of wave source `i` of ripples and waves: a hashed point of the unit sphere (POV-Ray's
/// are its normalised DNoise at (i, 0, 0), also on the unit sphere).
fn wave_source(i: u32) -> Vec3 {
    let h = pattern_pcg3d([i, 0x5eed_0a7e, 0]);
    let z = 1.0 - 2.0 * unit(h[0]);
    let phi = unit(h[1]);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * cos_turns(phi), r * sin_turns(phi), z)
}

/// The next relative frequency of a wave source from `state`: POV-Ray's own sequence (noise.cpp,
/// `Initialize_Waves`: a linear congruential generator from -560851967, 15 bits scaled into
/// [0.01, 1.01)). Its ten values lie in [0.17, 0.99], which keeps `waves`, weighted by 1/f, in
/// range; integer arithmetic, so both sides agree.
fn next_wave_frequency(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(1_812_433_253).wrapping_add(12345);
    ((*state >> 16) & 0x7fff) as f32 * 3.051_851e-5 + 0.01
}

/// Ripples (`waves` = false) or waves: concentric sine waves around 10 sources, averaged. Waves
/// weights each by 1/f and stretches it by f, its own frequency, to give swells of varied length.
fn ripples_or_waves(p: Vec3, frequency: f32, phase: f32, waves: bool) -> f32 {
    let mut sum = 0.0f32;
    let mut state = (-560_851_967i32) as u32;
    for i in 0..WAVE_SOURCES {
        let centre = wave_source(i);
        let f = next_wave_frequency(&mut state);
        let mut length = length3(p.x - centre.x, p.y - centre.y, p.z - centre.z);
        if length == 0.0 {
            length = 1.0;
        }
        if waves {
            sum += sin_turns(length * frequency * f + phase) / f;
        } else {
            sum += sin_turns(length * frequency + phase);
        }
    }
    if waves {
        0.2 * (2.5 + sum * 0.1)
    } else {
        0.5 * (1.0 + sum * 0.1)
    }
}

/// The turbulence parameters of a block.
struct Turb {
    amount: Vec3,
    octaves: u32,
    omega: f32,
    lambda: f32,
}

fn pattern_raw(data: &[u32], at: u32, kind: u32, p: Vec3, t: &Turb) -> f32 {
    let params = at + PATTERN_PARAMS;
    match kind {
        PATTERN_AGATE => {
            let turb = word(data, params) * turbulence(p, t.octaves, t.omega, t.lambda);
            let n = 0.5 * (sin_turns(1.3 * turb + 1.1 * p.z) + 1.0);
            if n <= 0.0 {
                0.0
            } else {
                n.min(1.0).powf(0.77)
            }
        }
        PATTERN_BOZO | PATTERN_BUMPS | PATTERN_SPOTTED => noise_unit(p),
        PATTERN_BRICK => brick(p, vec3_at(data, params), word(data, params + 3)),
        PATTERN_CHECKER => checker(p),
        PATTERN_CRACKLE => crackle(
            p,
            vec3_at(data, params),
            word(data, params + 3),
            word(data, params + 4),
            data[(params + 5) as usize] != 0,
        ),
        PATTERN_DENTS => {
            let n = noise_unit(p);
            n * n * n
        }
        PATTERN_GRADIENT => {
            let g = vec3_at(data, params);
            let v = p.x * g.x + p.y * g.y + p.z * g.z;
            if v > 1.0 {
                fract(v)
            } else {
                v
            }
        }
        PATTERN_GRANITE => {
            // Six octaves of |1 - 2 Noise| clipped at 1/2, at 4x frequency (POV-Ray's granite).
            let p4 = p * 4.0;
            let mut value = 0.0f32;
            let mut freq = 1.0f32;
            for _ in 0..6 {
                let n = (1.0 - 2.0 * noise_unit(p4 * freq)).abs().min(0.5);
                value += n / freq;
                freq *= 2.0;
            }
            value
        }
        PATTERN_HEXAGON => hexagon(p),
        PATTERN_LEOPARD => {
            const INV_TWO_PI: f32 = 0.159_154_94;
            let s = (sin_turns(p.x * INV_TWO_PI) + sin_turns(p.y * INV_TWO_PI) + sin_turns(p.z * INV_TWO_PI))
                * 0.333_333_34;
            s * s
        }
        PATTERN_MARBLE => {
            if t.amount.x != 0.0 {
                p.x + t.amount.x * turbulence(p, t.octaves, t.omega, t.lambda)
            } else {
                p.x
            }
        }
        PATTERN_ONION => fract(length3(p.x, p.y, p.z)),
        PATTERN_RADIAL => {
            // The angle around the y axis from +z towards +x, one turn from 0.25 to 1.25
            // (POV-Ray's radial: 0.25 + (atan2(x, z) + pi) / 2 pi, 0.25 on the axis).
            if p.x.abs() < 0.001 && p.z.abs() < 0.001 {
                0.25
            } else {
                0.75 + atan2_turns(p.x, p.z)
            }
        }
        PATTERN_RIPPLES | PATTERN_WAVES => ripples_or_waves(
            p,
            word(data, at + PATTERN_FREQUENCY),
            word(data, at + PATTERN_PHASE),
            kind == PATTERN_WAVES,
        ),
        PATTERN_WOOD => {
            // Rings around the z axis; turbulence bends them sideways through a sine of the
            // turbulent position (POV-Ray's wood).
            let (mut x, mut y) = (p.x, p.y);
            if t.amount.x != 0.0 || t.amount.y != 0.0 {
                let d = turbulence_vector(p, t.octaves, t.omega, t.lambda);
                x += sin_turns((p.x + d.x) * t.amount.x);
                y += sin_turns((p.y + d.y) * t.amount.y);
            }
            (x * x + y * y).sqrt()
        }
        PATTERN_WRINKLES => {
            // Ten octaves, omega 1/2 and lambda 2 fixed, each clipped to [0, 1].
            let mut value = (2.0 * noise_unit(p) - 0.5).clamp(0.0, 1.0);
            let mut l = 2.0f32;
            let mut o = 0.5f32;
            for _ in 1..10 {
                value += o * (2.0 * noise_unit(p * l) - 0.5).clamp(0.0, 1.0);
                l *= 2.0;
                o *= 0.5;
            }
            value * 0.5
        }
        _ => 0.0, // unreachable: the host packs only known kinds (tested)
    }
}

// ---------------------------------------------------------------------------------------------
// Warps (POV-Ray 3.7 warp.cpp)
// ---------------------------------------------------------------------------------------------

/// An angle in turns in [0, 1) from `atan2_turns`'s (-1/2, 1/2].
fn whole_turn(r: f32) -> f32 {
    if r < 0.0 {
        r + 1.0
    } else {
        r
    }
}

/// The mapping warps' last step (warp.cpp): (x, y, z) as they are for orientation z, else mixed
/// by the orientation vector as POV-Ray mixes them.
fn orient(o: Vec3, x: f32, y: f32, z: f32) -> Vec3 {
    if o.x == 0.0 && o.y == 0.0 && o.z == 1.0 {
        return Vec3::new(x, y, z);
    }
    Vec3::new(o.x * z + o.y * x + o.z * x, o.x * y + o.y * -z + o.z * y, o.x * -x + o.y * y + o.z * z)
}

/// d^e as POV-Ray scales the mapping warps' coordinates by it: 1 for e = 0, d for e = 1.
fn dist_scale(d: f32, e: f32) -> f32 {
    if e == 1.0 {
        d
    } else if e != 0.0 {
        d.powf(e)
    } else {
        1.0
    }
}

/// One warp record at word `w` applied to `p`: the warp itself, then its matrix (which undoes
/// the pattern's transforms written before the warp). Parameters by kind, from word 1:
/// repeat: axis (u32), width, offset x y z, flip x y z (each 1 or -1); black_hole: centre x y z,
/// radius, strength, falloff, inverse (u32), repeat x y z (0: no repeat); cylindrical,
/// spherical, toroidal: orientation x y z, dist_exp, major radius (toroidal); planar:
/// orientation x y z, offset.
pub fn warp_point(data: &[u32], w: u32, p: Vec3) -> Vec3 {
    let kind = data[w as usize];
    let a = w + WARP_PARAMS;
    let mut q = p;
    match kind {
        WARP_REPEAT => {
            let axis = data[a as usize].min(2) as usize;
            let width = word(data, a + 1);
            let offset = vec3_at(data, a + 2);
            let flip = vec3_at(data, a + 5);
            let block = (q[axis] / width).floor();
            q[axis] -= block * width;
            if (block as i32) & 1 != 0 {
                q = Vec3::new(q.x * flip.x, q.y * flip.y, q.z * flip.z);
                if flip[axis] < 0.0 {
                    q[axis] += width;
                }
            }
            q = Vec3::new(q.x + block * offset.x, q.y + block * offset.y, q.z + block * offset.z);
        }
        WARP_BLACK_HOLE => {
            let mut c = vec3_at(data, a);
            let radius = word(data, a + 3);
            let repeat = vec3_at(data, a + 7);
            for i in 0..3 {
                if repeat[i] > 0.0 {
                    c[i] += repeat[i] * (q[i] / repeat[i]).floor();
                }
            }
            let d = Vec3::new(q.x - c.x, q.y - c.y, q.z - c.z);
            let length = length3(d.x, d.y, d.z);
            if length < radius {
                let from_edge = (radius - length) / radius;
                let strength = (from_edge.powf(word(data, a + 5)) * word(data, a + 4)).min(1.0);
                let s = if data[(a + 6) as usize] != 0 { -strength } else { strength };
                q = Vec3::new(q.x + d.x * s, q.y + d.y * s, q.z + d.z * s);
            }
        }
        WARP_CYLINDRICAL => {
            let len = (q.x * q.x + q.z * q.z).sqrt();
            if len != 0.0 {
                let theta = whole_turn(atan2_turns(q.z, q.x)) * dist_scale(len, word(data, a + 3));
                q = orient(vec3_at(data, a), theta, q.y, len);
            }
        }
        WARP_SPHERICAL => {
            let dist = length3(q.x, q.y, q.z);
            if dist != 0.0 {
                let (x, y, z) = (q.x / dist, q.y / dist, q.z / dist);
                let len = (x * x + z * z).sqrt();
                let phi = 0.5 + 2.0 * atan2_turns(y, len);
                let theta = if len == 0.0 { 0.0 } else { whole_turn(atan2_turns(z, x)) };
                let k = dist_scale(dist, word(data, a + 3));
                q = orient(vec3_at(data, a), theta * k, phi * k, dist);
            }
        }
        WARP_TOROIDAL => {
            let len = (q.x * q.x + q.z * q.z).sqrt();
            if len != 0.0 {
                let theta = whole_turn(atan2_turns(q.z, q.x));
                let x = len - word(data, a + 4);
                let tube = (x * x + q.y * q.y).sqrt();
                let phi = if tube == 0.0 { 0.0 } else { whole_turn(atan2_turns(-q.y, -x)) };
                let k = dist_scale(tube, word(data, a + 3));
                q = orient(vec3_at(data, a), theta * k, phi * k, tube);
            }
        }
        WARP_PLANAR => q = orient(vec3_at(data, a), q.x, q.y, word(data, a + 3)),
        _ => {} // unreachable: the host packs only known kinds (tested)
    }
    // The matrix: columns x, y, z and the translation.
    let m = w + WARP_MATRIX;
    let (cx, cy, cz, t) = (vec3_at(data, m), vec3_at(data, m + 3), vec3_at(data, m + 6), vec3_at(data, m + 9));
    Vec3::new(
        cx.x * q.x + cy.x * q.y + cz.x * q.z + t.x,
        cx.y * q.x + cy.y * q.y + cz.y * q.z + t.y,
        cx.z * q.x + cy.z * q.y + cz.z * q.z + t.z,
    )
}

/// Frequency, phase and wave shape, as POV-Ray's `ContinuousPattern::Evaluate`: the value is
/// wrapped by `fmod(v frequency + phase, 1.00001)` (POV-Ray's constant, which keeps 1 at 1) and
/// made positive, then shaped, then clamped to [0, 1].
pub fn pattern_wave(v: f32, wave: u32, frequency: f32, phase: f32, exponent: f32) -> f32 {
    let mut v = v;
    if frequency != 0.0 {
        let a = v * frequency + phase;
        v = a - 1.00001 * (a * 0.99999).trunc();
    }
    if v < 0.0 {
        v -= v.floor();
    }
    let shaped = match wave {
        WAVE_SINE => (1.0 + sin_turns(v)) * 0.5,
        WAVE_TRIANGLE => {
            let offset = fract(v);
            if offset >= 0.5 {
                2.0 * (1.0 - offset)
            } else {
                2.0 * offset
            }
        }
        WAVE_SCALLOP => sin_turns(v * 0.5).abs(),
        WAVE_CUBIC => v * v * (-2.0 * v + 3.0),
        WAVE_POLY => {
            if v <= 0.0 {
                0.0
            } else {
                v.powf(exponent)
            }
        }
        _ => v, // WAVE_RAMP
    };
    shaped.clamp(0.0, 1.0)
}

/// The value in [0, 1] of the pattern block at word `at` at point `p` in pattern space (after
/// the texture transform): turbulence warp, raw pattern, frequency and phase, wave shape.
pub fn pattern_value(data: &[u32], at: u32, p: Vec3) -> f32 {
    let kind = data[(at + PATTERN_KIND) as usize];
    let t = Turb {
        amount: vec3_at(data, at + PATTERN_TURBULENCE),
        octaves: data[(at + PATTERN_OCTAVES) as usize],
        omega: word(data, at + PATTERN_OMEGA),
        lambda: word(data, at + PATTERN_LAMBDA),
    };
    // The warps, in the order packed (POV-Ray's last written first), then turbulence.
    let mut p = p;
    let warps = data[(at + PATTERN_WARP_COUNT) as usize].min(MAX_WARPS);
    for i in 0..warps {
        p = warp_point(data, at + PATTERN_WORDS + i * WARP_WORDS, p);
    }
    let mut q = p;
    if kind != PATTERN_MARBLE && kind != PATTERN_WOOD && t.amount != Vec3::ZERO {
        q = p + turbulence_vector(p, t.octaves, t.omega, t.lambda) * t.amount;
    }
    let raw = pattern_raw(data, at, kind, q, &t);
    if kind == PATTERN_CHECKER || kind == PATTERN_BRICK || kind == PATTERN_HEXAGON {
        return raw;
    }
    pattern_wave(
        raw,
        data[(at + PATTERN_WAVE) as usize],
        word(data, at + PATTERN_FREQUENCY),
        word(data, at + PATTERN_PHASE),
        word(data, at + PATTERN_EXPONENT),
    )
}

/// The pattern's gradient at `p` by central differences of step `h` (6 evaluations), for bump
/// mapping: POV-Ray's `normal { bumps 0.5 }` tilts the normal by amount x this.
pub fn pattern_gradient(data: &[u32], at: u32, p: Vec3, h: f32) -> Vec3 {
    let two_h = h + h;
    let dx =
        pattern_value(data, at, Vec3::new(p.x + h, p.y, p.z)) - pattern_value(data, at, Vec3::new(p.x - h, p.y, p.z));
    let dy =
        pattern_value(data, at, Vec3::new(p.x, p.y + h, p.z)) - pattern_value(data, at, Vec3::new(p.x, p.y - h, p.z));
    let dz =
        pattern_value(data, at, Vec3::new(p.x, p.y, p.z + h)) - pattern_value(data, at, Vec3::new(p.x, p.y, p.z - h));
    Vec3::new(dx / two_h, dy / two_h, dz / two_h)
}

/// The colour of map block `at` at value `v`, as POV-Ray's `BlendMap::Search`: the first
/// colour below the first position, the last at and above the last, linear in between; at a
/// position shared by two entries, the earlier colour below it and the later one above.
pub fn color_map_eval(data: &[u32], at: u32, v: f32) -> Vec3 {
    let n = data[at as usize].min(MAX_COLOR_MAP_ENTRIES);
    if n == 0 {
        return Vec3::ZERO; // unreachable: the host packs at least one entry (validated)
    }
    let position = |i: u32| word(data, at + 1 + 4 * i);
    let colour = |i: u32| vec3_at(data, at + 2 + 4 * i);
    let last = n - 1;
    if v >= position(last) {
        return colour(last);
    }
    let mut i = 0;
    while i < last && v > position(i) {
        i += 1;
    }
    if i == 0 || v == position(i) {
        return colour(i);
    }
    let (p0, p1) = (position(i - 1), position(i));
    let w0 = (p1 - v) / (p1 - p0);
    let w1 = 1.0 - w0;
    let (c0, c1) = (colour(i - 1), colour(i));
    Vec3::new(c0.x * w0 + c1.x * w1, c0.y * w0 + c1.y * w1, c0.z * w0 + c1.z * w1)
}

/// A scalar map is a colour map whose entries are grey; this is its red channel.
pub fn scalar_map_eval(data: &[u32], at: u32, v: f32) -> f32 {
    color_map_eval(data, at, v).x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::rng::rand2;
    use crate::scene::pattern::{ColorMap, PatternDesc, PatternKind, WaveShape, PATTERN_NAMES};

    /// Reproducible points in the cube [-r, r]^3.
    fn points(n: u32, r: f32, seed: u32) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let [a, b] = rand2(i, 0, seed, 0);
                let [c, _] = rand2(i, 0, seed, 2);
                (Vec3::new(a, b, c) * 2.0 - 1.0) * r
            })
            .collect()
    }

    fn packed(desc: &PatternDesc) -> Vec<u32> {
        let mut data = vec![0xdead_beef; 5]; // a block need not start at 0
        assert_eq!(desc.pack(&mut data), 5);
        data
    }

    fn value(desc: &PatternDesc, p: Vec3) -> f32 {
        pattern_value(&packed(desc), 5, p)
    }

    fn kind(name: &str) -> PatternKind {
        PatternKind::from_name(name).unwrap()
    }

    /// Every pattern with its defaults, and again with turbulence, a wave shape and frequency.
    fn variants() -> Vec<PatternDesc> {
        let mut all = Vec::new();
        for name in PATTERN_NAMES {
            let base = PatternDesc::new(kind(name));
            all.push(base);
            all.push(PatternDesc { turbulence: Vec3::new(0.6, 0.3, 0.9), octaves: 10, ..base });
            if !base.kind.is_discrete() {
                all.push(PatternDesc { frequency: -2.5, phase: 0.3, wave: WaveShape::Sine, ..base });
                all.push(PatternDesc { frequency: 3.0, wave: WaveShape::Poly { exponent: 2.5 }, ..base });
                all.push(PatternDesc { wave: WaveShape::Scallop, ..base });
                all.push(PatternDesc { wave: WaveShape::Cubic, turbulence: Vec3::splat(0.5), ..base });
            }
        }
        let crackle = |metric, offset, solid| {
            PatternDesc::new(PatternKind::Crackle { form: Vec3::new(-1.0, 1.0, 0.5), metric, offset, solid })
        };
        all.extend([crackle(1.0, 0.2, false), crackle(3.0, 0.1, false), crackle(2.0, 0.0, true)]);
        all
    }

    #[test]
    fn every_pattern_stays_in_the_unit_interval() {
        let pts = points(4000, 30.0, 1);
        for desc in variants() {
            let data = packed(&desc);
            let (mut lo, mut hi) = (f32::MAX, f32::MIN);
            for &p in &pts {
                let v = pattern_value(&data, 5, p);
                assert!((0.0..=1.0).contains(&v), "{desc:?} at {p}: {v}");
                lo = lo.min(v);
                hi = hi.max(v);
            }
            // Each pattern uses a good part of the range, so none is accidentally constant.
            assert!(hi - lo > 0.3, "{desc:?}: values only in [{lo}, {hi}]");
        }
    }

    #[test]
    fn checker_alternates_between_unit_cubes() {
        let checker = PatternDesc::new(PatternKind::Checker);
        for (p, expected) in [
            ([0.5, 0.5, 0.5], 0.0),
            ([1.5, 0.5, 0.5], 1.0),
            ([1.5, 1.5, 0.5], 0.0),
            ([1.5, 1.5, 1.5], 1.0),
            ([-0.5, 0.5, 0.5], 1.0), // floor -1 + 0 + 0 is odd
            ([-0.5, -0.5, -0.5], 1.0),
            ([-0.5, -0.5, 0.5], 0.0),
            ([0.0, 0.0, 0.0], 0.0),
            ([-1e-3, 0.0, 0.0], 1.0),
            ([10.25, -3.75, 7.5], 1.0), // 10 - 4 + 7 = 13
        ] {
            assert_eq!(value(&checker, Vec3::from(p)), expected, "{p:?}");
        }
    }

    #[test]
    fn gradient_is_linear_along_its_axis() {
        let along_y = PatternDesc::new(PatternKind::Gradient { direction: Vec3::Y });
        for p in points(1000, 20.0, 2) {
            let y = fract(p.y);
            // Ramp of slope 1 in y, whatever x and z.
            assert!((value(&along_y, Vec3::new(p.x, y, p.z)) - y).abs() < 1e-6, "{p}");
        }
        // A longer direction gives a shorter period: 1/|d|.
        let slanted = PatternDesc::new(PatternKind::Gradient { direction: Vec3::new(0.0, 0.0, 4.0) });
        for i in 0..100 {
            let z = i as f32 * 0.0025; // 4z in [0, 1)
            assert!((value(&slanted, Vec3::new(3.0, -2.0, z)) - 4.0 * z).abs() < 1e-6, "{z}");
            assert!((value(&slanted, Vec3::new(3.0, -2.0, z + 0.5)) - 4.0 * z).abs() < 1e-5, "{z}");
        }
    }

    #[test]
    fn noise_is_continuous_with_zero_mean() {
        let pts = points(100_000, 50.0, 3);
        let mut sum = 0.0f64;
        let mut worst_step = 0.0f32;
        for (i, &p) in pts.iter().enumerate() {
            let n = noise_signed(p, 0);
            assert!(n.abs() <= 1.1, "{p}: {n}");
            sum += n as f64;
            if i < 20_000 {
                // Perlin noise's gradient stays below 4 (measured 2.8); a step of 1e-3 moves it < 4e-3.
                let d = Vec3::new(1.0, -1.0, 0.5).normalize() * 1e-3;
                worst_step = worst_step.max((noise_signed(p + d, 0) - n).abs());
            }
        }
        let mean = sum / pts.len() as f64;
        // Standard deviation 0.27, so the mean of 1e5 values has standard error 9e-4.
        println!("noise mean {mean:.5}, largest change over a 1e-3 step {worst_step:.5}");
        assert!(mean.abs() < 0.005, "mean {mean}");
        assert!(worst_step < 4e-3, "{worst_step}");
        // Zero at lattice points, as gradient noise is.
        for p in [Vec3::ZERO, Vec3::new(3.0, -7.0, 12.0)] {
            assert_eq!(noise_signed(p, 0), 0.0);
        }
        // The vector noise's components are independent streams.
        let v = noise_vector(Vec3::new(0.3, 0.6, 0.9));
        assert!(v.x != v.y && v.y != v.z, "{v}");
    }

    #[test]
    fn turbulence_sums_octaves_as_povray_does() {
        // With one octave, turbulence is POV-Ray's clipped 2 Noise - 1/2.
        for p in points(200, 10.0, 4) {
            assert_eq!(turbulence(p, 1, 0.5, 2.0), (2.0 * noise_unit(p) - 0.5).clamp(0.0, 1.0));
            let two = (2.0 * noise_unit(p) - 0.5).clamp(0.0, 1.0) + 0.5 * (2.0 * noise_unit(p * 2.0) - 0.5);
            assert_eq!(turbulence(p, 2, 0.5, 2.0), two);
            assert_eq!(turbulence_vector(p, 2, 0.5, 2.0), noise_vector(p) + noise_vector(p * 2.0) * 0.5);
        }
        // Octaves beyond 10 are clamped, as in the shader.
        let p = Vec3::new(0.1, 0.2, 0.3);
        assert_eq!(turbulence(p, 50, 0.5, 2.0), turbulence(p, 10, 0.5, 2.0));
    }

    #[test]
    fn zero_turbulence_gives_the_plain_pattern() {
        let pts = points(2000, 10.0, 5);
        for name in PATTERN_NAMES {
            let plain = PatternDesc::new(kind(name));
            // Octaves, omega and lambda matter only with an amount (agate uses them regardless).
            let still = PatternDesc { turbulence: Vec3::ZERO, octaves: 3, omega: 0.7, lambda: 2.5, ..plain };
            let with = PatternDesc { turbulence: Vec3::splat(0.5), ..plain };
            let mut changed = 0;
            for &p in &pts {
                if *name != "agate" {
                    assert_eq!(value(&still, p), value(&plain, p), "{name} at {p}");
                }
                changed += (value(&with, p) != value(&plain, p)) as u32;
            }
            assert!(changed > 100, "{name}: turbulence changed only {changed} of 2000 values");
        }
    }

    #[test]
    fn color_map_interpolates_like_povray() {
        let red = [1.0, 0.0, 0.0];
        let green = [0.0, 1.0, 0.0];
        let blue = [0.0, 0.0, 1.0];
        let map = ColorMap::new(vec![(0.2, red), (0.5, green), (0.5, blue), (1.0, [1.0; 3])]).unwrap();
        let mut data = vec![0; 2];
        let at = map.pack(&mut data);
        for (v, expected) in [
            (-1.0, red), // below the first position: the first colour
            (0.1, red),
            (0.2, red),
            (0.35, [0.5, 0.5, 0.0]), // halfway from red to green
            (0.5, green),            // at a shared position: the earlier entry
            (0.75, [0.5, 0.5, 1.0]), // halfway from blue to white
            (1.0, [1.0; 3]),
            (7.0, [1.0; 3]),
        ] {
            let c = color_map_eval(&data, at, v);
            assert!(c.abs_diff_eq(Vec3::from(expected), 1e-6), "{v}: {c}");
        }
        assert_eq!(scalar_map_eval(&data, at, 0.35), 0.5);
        // One entry: one colour everywhere.
        let single = ColorMap::new(vec![(0.5, green)]).unwrap();
        let at = single.pack(&mut data);
        for v in [0.0, 0.5, 1.0] {
            assert_eq!(color_map_eval(&data, at, v), Vec3::from(green));
        }
    }

    #[test]
    fn wave_shapes_match_hand_computed_values() {
        let cases = [
            // (value, wave, frequency, phase, exponent, expected)
            (0.3, WAVE_RAMP, 1.0, 0.0, 1.0, 0.3),
            (0.3, WAVE_RAMP, 2.0, 0.1, 1.0, 0.7),
            (0.6, WAVE_RAMP, 2.0, 0.0, 1.0, 0.199_99), // 1.2 mod 1.00001
            (-0.25, WAVE_RAMP, 1.0, 0.0, 1.0, 0.75),   // negative values wrap up
            (1.0, WAVE_RAMP, 1.0, 0.0, 1.0, 1.0),      // POV-Ray's 1.00001 keeps 1 at 1
            (0.25, WAVE_SINE, 1.0, 0.0, 1.0, 1.0),     // (1 + sin(pi/2)) / 2
            (0.75, WAVE_SINE, 1.0, 0.0, 1.0, 0.0),
            (0.5, WAVE_SINE, 1.0, 0.0, 1.0, 0.5),
            (0.25, WAVE_TRIANGLE, 1.0, 0.0, 1.0, 0.5),
            (0.5, WAVE_TRIANGLE, 1.0, 0.0, 1.0, 1.0),
            (0.75, WAVE_TRIANGLE, 1.0, 0.0, 1.0, 0.5),
            (0.5, WAVE_SCALLOP, 1.0, 0.0, 1.0, 1.0), // |sin(pi/2)|
            (0.25, WAVE_SCALLOP, 1.0, 0.0, 1.0, std::f32::consts::FRAC_1_SQRT_2),
            (0.5, WAVE_CUBIC, 1.0, 0.0, 1.0, 0.5),
            (0.25, WAVE_CUBIC, 1.0, 0.0, 1.0, 0.156_25), // 1/16 (3 - 1/2)
            (0.5, WAVE_POLY, 1.0, 0.0, 2.0, 0.25),
            (0.5, WAVE_POLY, 1.0, 0.0, 0.5, std::f32::consts::FRAC_1_SQRT_2),
            (0.4, WAVE_RAMP, 0.0, 0.3, 1.0, 0.4), // frequency 0: no wrapping, phase unused
        ];
        for (v, wave, frequency, phase, exponent, expected) in cases {
            let got = pattern_wave(v, wave, frequency, phase, exponent);
            assert!((got - expected).abs() < 2e-6, "{v} wave {wave} f {frequency} ph {phase}: {got} vs {expected}");
        }
    }

    #[test]
    fn sin_turns_is_within_3e7_of_sin() {
        let mut worst = 0.0f64;
        for i in -200_000..200_000 {
            let t = i as f32 * 3.1e-5;
            let exact = (t as f64 * std::f64::consts::TAU).sin();
            worst = worst.max((sin_turns(t) as f64 - exact).abs());
        }
        println!("sin_turns worst error {worst:.2e}");
        assert!(worst < 3e-7, "{worst}");
        assert_eq!(sin_turns(0.0), 0.0);
        assert_eq!(cos_turns(0.0), 1.0);
    }

    #[test]
    fn crackle_finds_the_nearest_feature_points() {
        // form [1, 0, 0] gives d1, form [0, 1, 0] d2: compare with a search of 7x7x7 cells.
        let d1 = PatternDesc::new(PatternKind::Crackle { form: Vec3::X, metric: 2.0, offset: 0.0, solid: false });
        let d2 = PatternDesc::new(PatternKind::Crackle { form: Vec3::Y, metric: 2.0, offset: 0.0, solid: false });
        for p in points(3000, 20.0, 6) {
            let fl = p.floor();
            let mut dist: Vec<f32> = Vec::new();
            for dz in -3..=3 {
                for dy in -3..=3 {
                    for dx in -3..=3 {
                        let c = [fl.x as i32 + dx, fl.y as i32 + dy, fl.z as i32 + dz];
                        let h = pattern_pcg3d(c.map(|v| v as u32));
                        let feature =
                            Vec3::new(c[0] as f32 + unit(h[0]), c[1] as f32 + unit(h[1]), c[2] as f32 + unit(h[2]));
                        dist.push(feature.distance(p));
                    }
                }
            }
            dist.sort_by(f32::total_cmp);
            // The distances are clamped to [0, 1] like every crackle value.
            assert!((value(&d1, p) - dist[0].min(1.0)).abs() < 1e-5, "{p}");
            assert!((value(&d2, p) - dist[1].min(1.0)).abs() < 1e-5, "{p}");
        }
    }

    #[test]
    fn hexagons_are_coloured_as_in_povray() {
        let hexagon = PatternDesc::new(PatternKind::Hexagon);
        let h = 3f32.sqrt() / 2.0;
        for (x, z, expected) in [
            (0.0, 0.0, 0.0),     // the hexagon at the origin: colour 1
            (0.9, 0.0, 0.0),     // near its corner on the x axis
            (0.45, 0.8, 0.0),    // just inside its top edge (z = 0.866)
            (0.0, 2.0 * h, 0.5), // the one above it: colour 2
            (0.0, 4.0 * h, 1.0), // and the next: colour 3
            (1.5, h, 1.0),       // up and right: colour 3
            (1.5, -h, 0.5),      // down and right: colour 2
            (-1.5, h, 1.0),      // mirror image of (1.5, h), as POV-Ray's fabs(x) gives
            (0.0, 6.0 * h, 0.0), // period 3 sqrt(3) in z
            (3.0, 0.0, 0.0),     // period 3 in x
        ] {
            assert_eq!(value(&hexagon, Vec3::new(x, 7.0, z)), expected, "({x}, {z})");
        }
    }

    #[test]
    fn bricks_have_povray_proportions() {
        let brick = PatternDesc::new(kind("brick"));
        assert_eq!(value(&brick, Vec3::new(3.0, 1.5, 1.5)), 1.0); // inside a brick
        assert_eq!(value(&brick, Vec3::new(-0.3, 1.5, 1.5)), 0.0); // head joint at x = -0.5
        assert_eq!(value(&brick, Vec3::new(3.0, -0.2, 1.5)), 0.0); // bed joint at y = -0.5
        assert_eq!(value(&brick, Vec3::new(3.0, 4.5, 1.5)), 1.0); // next course, joints shifted
        assert_eq!(value(&brick, Vec3::new(-0.3, 4.5, 1.5)), 1.0);
        assert_eq!(value(&brick, Vec3::new(3.7, 4.5, 1.5)), 0.0); // its joint at x = 3.5
                                                                  // Mortar 0.5 in bricks 8 x 3 x 4.5: brick volume (1 - 1/6)(1 - 1/16)(1 - 1/9) = 0.694.
        let pts = points(40_000, 50.0, 7);
        let fraction = pts.iter().map(|&p| value(&brick, p) as f64).sum::<f64>() / pts.len() as f64;
        println!("brick fraction {fraction:.4}");
        assert!((fraction - 0.6944).abs() < 0.01, "{fraction}");
    }

    #[test]
    fn atan2_turns_matches_the_library_atan2() {
        let mut worst = 0.0f64;
        for (i, p) in points(20_000, 5.0, 11).into_iter().enumerate() {
            // Include points on and near the axes and diagonals, where the branches meet.
            let (s, c) = match i % 5 {
                0 => (p.x, 0.0),
                1 => (0.0, p.x),
                2 => (p.x, p.x.abs() * (1.0 + 1e-6)),
                _ => (p.x, p.y),
            };
            if s == 0.0 && c == 0.0 {
                continue;
            }
            let exact = (s as f64).atan2(c as f64) / std::f64::consts::TAU;
            worst = worst.max((atan2_turns(s, c) as f64 - exact).abs());
        }
        println!("atan2_turns: max error {worst:.2e} turns");
        assert!(worst < 1e-7, "{worst}");
    }

    #[test]
    fn radial_is_povrays_angle_around_y() {
        // POV-Ray 3.7 pattern.cpp: 0.25 + (atan2(x, z) + pi) / 2 pi, 0.25 within 0.001 of the
        // y axis, then wrapped by frequency 1 (fmod 1.00001).
        let radial = PatternDesc::new(kind("radial"));
        let data = packed(&radial);
        for p in points(20_000, 4.0, 12) {
            let raw = if p.x.abs() < 0.001 && p.z.abs() < 0.001 {
                0.25
            } else {
                0.25 + ((p.x as f64).atan2(p.z as f64) + std::f64::consts::PI) / std::f64::consts::TAU
            };
            let expected = raw % 1.00001;
            let got = pattern_value(&data, 5, p) as f64;
            // A value next to the wrap at 1.00001 may land on either side: skip those.
            if (raw - 1.00001).abs() > 1e-5 {
                assert!((got - expected).abs() < 2e-6, "at {p}: {got} against {expected}");
            }
        }
        // Quarter turns: +z is 0.75, +x 1, -x 0.5, -z 1.25 wrapped to 0.25 - 1e-5 (by 1.00001).
        for (p, expected) in
            [(Vec3::Z, 0.75), (Vec3::X, 1.0), (Vec3::NEG_Z, 0.249_99), (Vec3::NEG_X, 0.5), (Vec3::Y, 0.25)]
        {
            assert!((pattern_value(&data, 5, p) - expected).abs() < 1e-6, "{p}");
        }
        // Frequency 8 gives eight sectors: the value repeats every 1/8 turn.
        let eight = PatternDesc { frequency: 8.0, ..radial };
        let a = value(&eight, Vec3::new(0.3f32.sin(), 0.2, 0.3f32.cos()));
        let b = value(
            &eight,
            Vec3::new((0.3f32 + std::f32::consts::FRAC_PI_4).sin(), 0.2, (0.3f32 + std::f32::consts::FRAC_PI_4).cos()),
        );
        assert!((a - b).abs() < 1e-4, "{a} {b}");
    }

    /// POV-Ray 3.7's warps (warp.cpp) in f64, the reference for `warp_point`.
    fn povray_warp(kind: &crate::scene::pattern::WarpKind, p: [f64; 3]) -> [f64; 3] {
        use crate::scene::pattern::WarpKind;
        use std::f64::consts::{PI, TAU};
        let [x, y, z] = p;
        let angle = |x: f64, z: f64, len: f64| {
            // acos(x / len), 2 pi minus that below the x axis: [0, 2 pi).
            if z == 0.0 {
                if x > 0.0 {
                    0.0
                } else {
                    PI
                }
            } else {
                let t = (x / len).clamp(-1.0, 1.0).acos();
                if z < 0.0 {
                    TAU - t
                } else {
                    t
                }
            }
        };
        let scale = |d: f64, e: f64| {
            if e == 1.0 {
                d
            } else if e != 0.0 {
                d.powf(e)
            } else {
                1.0
            }
        };
        let orient = |o: Vec3, x: f64, y: f64, z: f64| {
            let o = o.as_dvec3();
            if o == glam::DVec3::Z {
                [x, y, z]
            } else {
                [o.x * z + o.y * x + o.z * x, o.x * y - o.y * z + o.z * y, -o.x * x + o.y * y + o.z * z]
            }
        };
        match *kind {
            WarpKind::Repeat { axis, width, offset, flip } => {
                let (axis, width) = (axis as usize, width as f64);
                let mut q = p;
                let block = (q[axis] / width).floor();
                q[axis] -= block * width;
                if (block as i64) & 1 != 0 {
                    for i in 0..3 {
                        q[i] *= flip[i] as f64;
                    }
                    if flip[axis] < 0.0 {
                        q[axis] += width;
                    }
                }
                [0, 1, 2].map(|i| q[i] + block * offset[i] as f64)
            }
            WarpKind::BlackHole { center, radius, strength, falloff, inverse, repeat } => {
                let mut c = center.as_dvec3().to_array();
                for i in 0..3 {
                    if repeat[i] > 0.0 {
                        c[i] += repeat[i] as f64 * (p[i] / repeat[i] as f64).floor();
                    }
                }
                let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
                let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if length >= radius as f64 {
                    return p;
                }
                let l = (radius as f64 - length) / radius as f64;
                let s = (l.powf(falloff as f64) * strength as f64).min(1.0);
                let s = if inverse { -s } else { s };
                [0, 1, 2].map(|i| p[i] + d[i] * s)
            }
            WarpKind::Cylindrical { orientation, dist_exp } => {
                let len = (x * x + z * z).sqrt();
                let theta = angle(x, z, len) / TAU * scale(len, dist_exp as f64);
                orient(orientation, theta, y, len)
            }
            WarpKind::Spherical { orientation, dist_exp } => {
                let dist = (x * x + y * y + z * z).sqrt();
                let (x, y, z) = (x / dist, y / dist, z / dist);
                let phi = 0.5 + y.asin() / PI;
                let len = (x * x + z * z).sqrt();
                let theta = if len == 0.0 { 0.0 } else { angle(x, z, len) / TAU };
                let k = scale(dist, dist_exp as f64);
                orient(orientation, theta * k, phi * k, dist)
            }
            WarpKind::Toroidal { orientation, dist_exp, major_radius } => {
                let len = (x * x + z * z).sqrt();
                let theta = angle(x, z, len) / TAU;
                let x = len - major_radius as f64;
                let len = (x * x + y * y).sqrt();
                let mut phi = (-x / len).acos();
                if y > 0.0 {
                    phi = TAU - phi;
                }
                let k = scale(len, dist_exp as f64);
                orient(orientation, theta * k, phi / TAU * k, len)
            }
            WarpKind::Planar { orientation, offset } => orient(orientation, x, y, offset as f64),
        }
    }

    /// Each warp as POV-Ray computes it, for points in a cube; the f32 twin within 2e-5 of the
    /// f64 reference scaled by the size of the coordinates (the angles' polynomial is within
    /// 3e-8 turns, the rest is rounding), away from the seams where a last-bit difference
    /// legitimately jumps a whole period (the repeat's slab edges, the angle's wrap at +x).
    #[test]
    fn warps_follow_povray_formulas() {
        use crate::scene::pattern::{Warp, WarpKind};
        let kinds = [
            WarpKind::Repeat {
                axis: 0,
                width: 2.0,
                offset: Vec3::new(0.0, 0.0, 0.25),
                flip: Vec3::new(1.0, -1.0, 1.0),
            },
            WarpKind::Repeat { axis: 1, width: -1.5, offset: Vec3::ZERO, flip: Vec3::new(1.0, -1.0, -1.0) },
            WarpKind::BlackHole {
                center: Vec3::new(0.5, 0.0, 0.0),
                radius: 2.0,
                strength: 1.5,
                falloff: 2.0,
                inverse: false,
                repeat: Vec3::ZERO,
            },
            WarpKind::BlackHole {
                center: Vec3::ZERO,
                radius: 0.8,
                strength: 1.0,
                falloff: 1.0,
                inverse: true,
                repeat: Vec3::new(2.0, 0.0, 2.0),
            },
            WarpKind::Cylindrical { orientation: Vec3::Z, dist_exp: 0.0 },
            WarpKind::Cylindrical { orientation: Vec3::Y, dist_exp: 1.0 },
            WarpKind::Spherical { orientation: Vec3::Z, dist_exp: 0.0 },
            WarpKind::Spherical { orientation: Vec3::X, dist_exp: 0.5 },
            WarpKind::Toroidal { orientation: Vec3::Z, dist_exp: 0.0, major_radius: 1.0 },
            WarpKind::Toroidal { orientation: Vec3::Z, dist_exp: 1.0, major_radius: 2.5 },
            WarpKind::Planar { orientation: Vec3::Z, offset: 0.0 },
            WarpKind::Planar { orientation: Vec3::Y, offset: 0.3 },
        ];
        for kind in kinds {
            let mut desc = PatternDesc::new(PatternKind::Onion);
            desc.warps[0] = Some(Warp { kind, transform: glam::Affine3A::IDENTITY });
            let data = packed(&desc);
            let mut worst = 0.0f64;
            for p in points(5000, 4.0, 21) {
                let want = povray_warp(&kind, p.as_dvec3().to_array());
                let got = warp_point(&data, 5 + PATTERN_WORDS, p).as_dvec3().to_array();
                let size = want.iter().fold(1.0f64, |m, v| m.max(v.abs()));
                let err = (0..3).map(|i| (got[i] - want[i]).abs()).fold(0.0, f64::max) / size;
                // Seams: a point within 1e-5 of a slab edge, or of the angle's wrap (z = 0, x > 0).
                let near_seam = match kind {
                    WarpKind::Repeat { axis, width, .. } => {
                        let u = p[axis as usize] as f64 / width as f64;
                        (u - u.round()).abs() < 1e-5
                    }
                    _ => p.z.abs() < 1e-4 * p.x.abs().max(1.0) || p.y.abs() < 1e-4,
                };
                if !near_seam {
                    worst = worst.max(err);
                }
            }
            println!("{}: max relative error {worst:.2e}", kind.name());
            assert!(worst < 2e-5, "{kind:?}: {worst}");
        }
        // The matrix after the warp undoes the transforms written before it: planar (x, y, 0),
        // then scale 2 undone.
        let mut desc = PatternDesc::new(PatternKind::Onion);
        let transform = glam::Affine3A::from_scale(Vec3::splat(2.0));
        desc.warps[0] = Some(Warp { kind: WarpKind::Planar { orientation: Vec3::Z, offset: 0.0 }, transform });
        let data = packed(&desc);
        assert_eq!(warp_point(&data, 5 + PATTERN_WORDS, Vec3::new(1.0, 3.0, 7.0)), Vec3::new(0.5, 1.5, 0.0));
    }

    /// Two warps: the point meets the last one written first (POV-Ray's Warp_EPoint).
    #[test]
    fn warps_apply_from_the_last_written() {
        use crate::scene::pattern::{Warp, WarpKind};
        let repeat_x = Warp {
            kind: WarpKind::Repeat { axis: 0, width: 1.0, offset: Vec3::ZERO, flip: Vec3::ONE },
            transform: glam::Affine3A::IDENTITY,
        };
        let halve = Warp {
            kind: WarpKind::Planar { orientation: Vec3::Z, offset: 0.0 },
            transform: glam::Affine3A::from_scale(Vec3::splat(2.0)),
        };
        // gradient x: the value is the x the pattern sees.
        let desc = PatternDesc::new(PatternKind::Gradient { direction: Vec3::X });
        // Written repeat, then planar (with its scale 2): planar first, x / 2 = 1.55, then the
        // repeat: 0.55.
        let first = PatternDesc { warps: [Some(repeat_x), Some(halve), None, None], ..desc };
        assert!((value(&first, Vec3::new(3.1, 0.0, 0.0)) - 0.55).abs() < 1e-5);
        // Written planar, then repeat: the repeat first (0.1), then halved: 0.05.
        let second = PatternDesc { warps: [Some(halve), Some(repeat_x), None, None], ..desc };
        assert!((value(&second, Vec3::new(3.1, 0.0, 0.0)) - 0.05).abs() < 1e-5);
    }
}
