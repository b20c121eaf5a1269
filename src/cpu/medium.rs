//! Participating media: free-flight sampling, transmittance, the phase function as a `Bsdf`, and
//! which medium a ray is in after crossing a surface; twin of `shaders/medium.glsl`.

use glam::{Vec2, Vec3};

use super::bsdf::Bsdf;
use super::rng::{pcg4d, rand_unit};
use super::shape::Hit;
use super::texture::texture_eval;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Medium;

/// What happened on a ray segment inside a medium (see `medium_sample`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MediumEvent {
    /// A collision before the segment's end, at distance `t`.
    pub scattered: bool,
    pub t: f32,
    /// What the path's throughput is multiplied by.
    pub weight: Vec3,
    /// A scattering event: sigma_t T / pdf (the photon stored there carries it).
    pub collision: Vec3,
    /// A scattering event: the medium's emission T / pdf (a collision estimate of its integral).
    pub emission: Vec3,
}

pub fn medium_sigma_t(m: &Medium) -> Vec3 {
    Vec3::from(m.sigma_a) + Vec3::from(m.sigma_s)
}

fn channel_transmittance(sigma: f32, t: f32) -> f32 {
    if sigma > 0.0 {
        (-sigma * t).exp()
    } else {
        1.0
    }
}

/// Beer-Lambert transmittance exp(-sigma_t t) per channel; a channel with sigma_t = 0 is 1 even
/// over an infinite distance.
pub fn medium_beer_lambert(st: Vec3, t: f32) -> Vec3 {
    Vec3::new(channel_transmittance(st.x, t), channel_transmittance(st.y, t), channel_transmittance(st.z, t))
}

// ---- Heterogeneous media: density, delta and ratio tracking ---------------------------------

/// The medium's density at `p`: 1 for a homogeneous medium; else the first channel of its
/// density texture (negative values read as 0) inside its box, and 0 outside it.
pub fn medium_density(s: &SceneView, medium: u32, p: Vec3) -> f32 {
    let m = &s.media[medium as usize];
    if m.density == NO_TEXTURE {
        return 1.0;
    }
    if p.cmplt(Vec3::from(m.bounds_min)).any() || p.cmpgt(Vec3::from(m.bounds_max)).any() {
        return 0.0;
    }
    texture_eval(s, m.density, &medium_hit(p, Vec3::Z)).x.max(0.0)
}

/// Extinction at `p`: sigma_t times the density there.
pub fn medium_sigma_t_at(s: &SceneView, medium: u32, p: Vec3) -> Vec3 {
    medium_sigma_t(&s.media[medium as usize]) * medium_density(s, medium, p)
}

/// The part (t0, t1) of the ray `o + t d`, t in [0, `t_seg`), inside the medium's box; empty
/// unless t0 < t1. Tracking walks only there: outside it the density is 0, and an unbounded
/// segment (a heterogeneous atmosphere) becomes a bounded walk.
pub fn medium_box_span(m: &Medium, o: Vec3, d: Vec3, t_seg: f32) -> (f32, f32) {
    let (mut t0, mut t1) = (0.0f32, t_seg);
    for a in 0..3 {
        let lo = m.bounds_min[a] - o[a];
        let hi = m.bounds_max[a] - o[a];
        if d[a] == 0.0 {
            if lo > 0.0 || hi < 0.0 {
                t1 = -1.0;
            }
        } else {
            let (ta, tb) = (lo / d[a], hi / d[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    (t0, t1)
}

/// a < b; false when either is NaN, so a walk with a NaN bound or weight stops, as the kernel's
/// `!(a < b)` tests do.
fn less(a: f32, b: f32) -> bool {
    a < b
}

/// A tracking walk's random numbers: its two free-flight numbers (24 bits each) as a key,
/// hashed with the number's index, so a walk takes as many as it needs from one dimension.
fn medium_walk_key(u: [f32; 2]) -> [u32; 2] {
    [(u[0] * 16777216.0) as u32, (u[1] * 16777216.0) as u32]
}

fn medium_walk_rand(key: [u32; 2], i: u32) -> f32 {
    rand_unit(pcg4d([key[0], key[1], i, MEDIUM_WALK_SALT])[0])
}

/// Ratio tracking (Novák et al. 2014): tentative collisions at rate `majorant` through the
/// medium's box; the estimate is the product of (1 - sigma_t(x) / majorant) over them, unbiased
/// for exp(-integral of sigma_t) per channel. Russian roulette below `MEDIUM_ROULETTE` keeps it
/// unbiased while ending walks through thick media; at most `MEDIUM_TRACKING_STEPS` collisions
/// (the rest of a longer walk counts as clear: see docs/limits.md).
pub fn medium_ratio_tracking(s: &SceneView, medium: u32, o: Vec3, d: Vec3, t_seg: f32, u: [f32; 2]) -> Vec3 {
    let m = &s.media[medium as usize];
    let st = medium_sigma_t(m);
    let (t0, t1) = medium_box_span(m, o, d, t_seg);
    let mut tr = Vec3::ONE;
    if !less(t0, t1) || !less(0.0, m.majorant) {
        return tr;
    }
    let key = medium_walk_key(u);
    let mut t = t0;
    for i in 0..MEDIUM_TRACKING_STEPS {
        t -= (1.0 - medium_walk_rand(key, 2 * i)).ln() / m.majorant;
        if !less(t, t1) {
            break;
        }
        tr *= (Vec3::ONE - st * (medium_density(s, medium, o + d * t) / m.majorant)).max(Vec3::ZERO);
        let top = tr.max_element();
        if top < MEDIUM_ROULETTE {
            let q = top / MEDIUM_ROULETTE;
            if !less(medium_walk_rand(key, 2 * i + 1), q) {
                return Vec3::ZERO;
            }
            tr /= q;
        }
    }
    tr
}

/// Delta tracking with spectral weights (Kutz et al. 2017's spectral tracking): tentative
/// collisions at rate `majorant`; one at x is real with probability P = mean(w sigma_t(x)) /
/// (majorant mean(w)), where w is the walk's weight so far, and a null one multiplies w by
/// (majorant - sigma_t(x)) / (majorant (1 - P)). A real collision's event carries w sigma_s(x)
/// / (majorant P) (`weight`), w sigma_t(x) / (majorant P) (`collision`) and the emission alike;
/// passing the segment carries w. Grey media get exactly the homogeneous weights: the albedo
/// at a collision, 1 passing. Unbiased with any majorant >= sigma_t (null-scattering path
/// integral, Miller et al. 2019), up to `MEDIUM_TRACKING_STEPS` collisions.
pub fn medium_delta_tracking(s: &SceneView, medium: u32, o: Vec3, d: Vec3, t_seg: f32, u: [f32; 2]) -> MediumEvent {
    let m = &s.media[medium as usize];
    let (ss, st, mu) = (Vec3::from(m.sigma_s), medium_sigma_t(m), m.majorant);
    let mut e = MediumEvent { scattered: false, t: t_seg, weight: Vec3::ONE, ..Default::default() };
    let (t0, t1) = medium_box_span(m, o, d, t_seg);
    if !less(t0, t1) || !less(0.0, mu) {
        return e;
    }
    let key = medium_walk_key(u);
    let mut w = Vec3::ONE;
    let mut t = t0;
    for i in 0..MEDIUM_TRACKING_STEPS {
        t -= (1.0 - medium_walk_rand(key, 2 * i)).ln() / mu;
        if !less(t, t1) {
            break;
        }
        let rho = medium_density(s, medium, o + d * t);
        let stx = st * rho;
        let wsum = w.x + w.y + w.z;
        if !less(0.0, wsum) {
            break;
        }
        let pr = w.dot(stx) / (mu * wsum);
        if medium_walk_rand(key, 2 * i + 1) < pr {
            let over = 1.0 / (mu * pr);
            return MediumEvent {
                scattered: true,
                t,
                weight: w * ss * (rho * over),
                collision: w * stx * over,
                emission: w * Vec3::from(m.emission) * (rho * over),
            };
        }
        w *= (Vec3::splat(mu) - stx).max(Vec3::ZERO) / (mu * (1.0 - pr));
    }
    e.weight = w;
    e
}

/// Transmittance along `o + t d`, t in [0, `t`): Beer-Lambert, exact, for a homogeneous
/// medium; ratio tracking seeded by `u` for a heterogeneous one (an unbiased estimate).
pub fn medium_transmittance(s: &SceneView, medium: u32, o: Vec3, d: Vec3, t: f32, u: [f32; 2]) -> Vec3 {
    let m = &s.media[medium as usize];
    if m.density != NO_TEXTURE {
        return medium_ratio_tracking(s, medium, o, d, t, u);
    }
    medium_beer_lambert(medium_sigma_t(m), t)
}

/// Free-flight sampling along `o + t d` over a segment of length `t_seg` (infinite for a ray
/// that leaves the scene). Homogeneous media: `u[0]` picks a channel, `u[1]` a distance with
/// that channel's sigma_t. The pdf is the mean of the three channels' (pbrt-v4's one-sample
/// spectral MIS), so chromatic media stay unbiased; grey media weigh a collision by exactly the
/// albedo and a pass by 1. Heterogeneous media: delta tracking seeded by `u`
/// (`medium_delta_tracking`).
pub fn medium_sample(s: &SceneView, medium: u32, o: Vec3, d: Vec3, t_seg: f32, u: [f32; 2]) -> MediumEvent {
    let m = &s.media[medium as usize];
    if m.density != NO_TEXTURE {
        return medium_delta_tracking(s, medium, o, d, t_seg, u);
    }
    let (sa, ss) = (Vec3::from(m.sigma_a), Vec3::from(m.sigma_s));
    let st = sa + ss;
    let sc = if u[0] < 1.0 / 3.0 {
        st.x
    } else if u[0] < 2.0 / 3.0 {
        st.y
    } else {
        st.z
    };
    let t = if sc > 0.0 { -(1.0 - u[1]).ln() / sc } else { f32::INFINITY };
    if t < t_seg {
        let tr = (-st * t).exp();
        let pdf = (st * tr).dot(Vec3::splat(1.0 / 3.0));
        let over = |v: Vec3| if pdf > 0.0 { v * tr / pdf } else { Vec3::ZERO };
        return MediumEvent {
            scattered: true,
            t,
            weight: over(ss),
            collision: over(st),
            emission: over(Vec3::from(m.emission)),
        };
    }
    let tr = medium_beer_lambert(st, t_seg);
    let p = tr.dot(Vec3::splat(1.0 / 3.0));
    MediumEvent { scattered: false, t: t_seg, weight: if p > 0.0 { tr / p } else { Vec3::ZERO }, ..Default::default() }
}

/// The scattering point at `p` seen from `wo` as a hit record: no surface, no offset.
pub fn medium_hit(p: Vec3, wo: Vec3) -> Hit {
    Hit {
        p,
        ng: wo,
        ns: wo,
        uv: Vec2::ZERO,
        dpdu: Vec3::ZERO,
        dpdv: Vec3::ZERO,
        prim: NO_LIGHT,
        material: NO_LIGHT,
        eps: 0.0,
        shift: Vec3::ZERO,
    }
}

/// The medium's phase function as a `Bsdf` (`MATERIAL_PHASE`, see `bsdf.rs`); `color1.y` is 1
/// where the scattering point samples point and spot lights itself (heterogeneous media, which
/// have no equiangular shafts).
pub fn phase_bsdf(s: &SceneView, medium: u32, wo: Vec3) -> Bsdf<'static> {
    let m = &s.media[medium as usize];
    Bsdf {
        kind: MATERIAL_PHASE,
        flags: 0,
        data: NO_DATA,
        words: &[],
        color0: Vec3::ONE,
        color1: Vec3::new(m.phase as f32, if m.density != NO_TEXTURE { 1.0 } else { 0.0 }, 0.0),
        color2: Vec3::ONE,
        alpha: Vec2::ZERO,
        ior: m.g,
        ng: wo,
        ns: wo,
        ts: Vec3::ZERO,
        glossy_path: false,
    }
}

/// The medium a ray is in after it crossed primitive `prim` (geometric normal `ng`) going along
/// `d`: a medium boundary's interior when it went against the outward normal, its exterior when
/// it went along it; any other surface leaves the medium as it was.
pub fn medium_after(s: &SceneView, prim: u32, ng: Vec3, d: Vec3, medium: u32) -> u32 {
    let p = &s.primitives[super::instance::hit_primitive(s, prim) as usize];
    if p.kind & PRIMITIVE_FLAG_MEDIUM == 0 {
        return medium;
    }
    if d.dot(ng) < 0.0 {
        p.interior
    } else {
        p.exterior
    }
}

/// The part (t0, t1) of the ray `o + t d`, t in [0, `t_max`), inside the cone of a spot light
/// (apex `c`, unit axis `a`, `cos_outer` the cosine of its half-angle), widened by
/// `SPOT_SPAN_MARGIN` in cosine so that rounding never cuts lit points; empty unless t0 < t1.
/// Equiangular samples toward a spot stay in it: outside, its light is 0, and a narrow beam
/// sampled over the whole segment gives a few bright samples among dark ones (speckles). The
/// cone's front nappe is convex, so the part is one interval. Cones of 90 degrees or more give
/// the whole segment.
pub fn spot_span(o: Vec3, d: Vec3, t_max: f32, c: Vec3, a: Vec3, cos_outer: f32) -> (f32, f32) {
    const EMPTY: (f32, f32) = (0.0, -1.0);
    if !less(SPOT_SPAN_MARGIN, cos_outer) {
        return (0.0, t_max);
    }
    let k = cos_outer - SPOT_SPAN_MARGIN;
    let k2 = k * k;
    let v = o - c;
    let (da, va) = (d.dot(a), v.dot(a));
    // Inside the double cone where A t^2 + 2 B t + C >= 0; in its front nappe where va + t da >= 0.
    let a2 = da * da - k2;
    let b = da * va - k2 * d.dot(v);
    let c0 = va * va - k2 * v.dot(v);
    let (mut lo, mut hi) = (0.0f32, t_max);
    if da > 0.0 {
        lo = lo.max(-va / da);
    } else if da < 0.0 {
        hi = hi.min(-va / da);
    } else if va < 0.0 {
        return EMPTY;
    }
    let disc = b * b - a2 * c0;
    if a2.abs() < 1e-12 {
        if b > 0.0 {
            lo = lo.max(-c0 / (2.0 * b));
        } else if b < 0.0 {
            hi = hi.min(-c0 / (2.0 * b));
        } else if c0 < 0.0 {
            return EMPTY;
        }
        return (lo, hi);
    }
    if disc < 0.0 {
        return if a2 > 0.0 { (lo, hi) } else { EMPTY };
    }
    let q = disc.sqrt();
    let (r1, r2) = ((-b - q) / a2, (-b + q) / a2);
    let (ra, rb) = (r1.min(r2), r1.max(r2));
    if a2 < 0.0 {
        return (lo.max(ra), hi.min(rb));
    }
    let first = lo < hi.min(ra);
    let second = lo.max(rb) < hi;
    match (first, second) {
        (true, true) => (lo, hi),
        (true, false) => (lo, hi.min(ra)),
        (false, true) => (lo.max(rb), hi),
        (false, false) => EMPTY,
    }
}

/// Equiangular sampling (Kulla and Fajardo 2012) of a distance t in [0, `t_end`) along
/// `o + t d` toward the point `c`: uniform in the angle under which `c` sees the ray, so the
/// samples crowd where the ray passes the light. Returns t and its pdf, D / ((theta_b -
/// theta_a) (D^2 + (t - delta)^2)); `t_end` may be infinite.
pub fn equiangular_sample(o: Vec3, d: Vec3, t_end: f32, c: Vec3, u: f32) -> (f32, f32) {
    let delta = (c - o).dot(d);
    let dist = (c - o - delta * d).length().max(1e-7 * (delta.abs() + 1.0));
    let a = (-delta).atan2(dist);
    let b = if t_end == f32::INFINITY { 0.5 * std::f32::consts::PI } else { (t_end - delta).atan2(dist) };
    let t = (delta + dist * (a + (b - a) * u).tan()).clamp(0.0, t_end);
    let e = t - delta;
    let pdf = if b > a { dist / ((b - a) * (dist * dist + e * e)) } else { 0.0 };
    (t, pdf)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point of a segment inside a spot's cone lies in `spot_span`'s interval, and the
    /// interval holds little outside the (widened) cone: brute force over random rays.
    #[test]
    fn spot_span_holds_the_lit_part_of_a_segment() {
        let mut seed = 1u32;
        let mut next = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / 16777216.0
        };
        let c = Vec3::new(0.2, 3.0, -0.1);
        let a = Vec3::new(0.1, -1.0, 0.2).normalize();
        for cos_outer in [0.99f32, 0.95, 0.7, 0.2] {
            for _ in 0..2000 {
                let o = Vec3::new(next() * 8.0 - 4.0, next() * 8.0 - 2.0, next() * 8.0 - 4.0);
                let d = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                let t_max = next() * 10.0;
                let (t0, t1) = spot_span(o, d, t_max, c, a, cos_outer);
                for i in 0..200 {
                    let t = (i as f32 + 0.5) / 200.0 * t_max;
                    let w = (o + d * t - c).normalize();
                    let inside = w.dot(a) > cos_outer;
                    if inside {
                        assert!(t0 <= t && t <= t1, "cos {cos_outer}: t {t} lit but span {t0}..{t1}");
                    } else if t0 < t && t < t1 {
                        let widened = w.dot(a) > cos_outer - 2.0 * SPOT_SPAN_MARGIN;
                        assert!(widened, "cos {cos_outer}: t {t} dark but in span {t0}..{t1}");
                    }
                }
            }
        }
    }

    /// The equiangular pdf integrates to 1 over the segment and its samples follow it: the
    /// mean of 1/pdf over samples is the segment's length (an unbiased length estimate).
    #[test]
    fn equiangular_samples_estimate_the_segment_length() {
        let (o, d, c) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.3, 0.1, 2.0));
        for t_end in [1.0f32, 5.0, 40.0] {
            let n = 100_000;
            let mean: f64 = (0..n)
                .map(|i| {
                    let (t, pdf) = equiangular_sample(o, d, t_end, c, (i as f32 + 0.5) / n as f32);
                    assert!((0.0..=t_end).contains(&t));
                    1.0 / pdf as f64
                })
                .sum::<f64>()
                / n as f64;
            println!("t_end {t_end}: mean 1/pdf {mean:.4}");
            assert!((mean / t_end as f64 - 1.0).abs() < 1e-3, "{mean} vs {t_end}");
        }
    }
}
