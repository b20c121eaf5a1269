//! Participating media: free-flight sampling, transmittance, the phase function as a `Bsdf`, and
//! which medium a ray is in after crossing a surface; twin of `shaders/medium.glsl`.

use glam::{Vec2, Vec3};

use super::bsdf::Bsdf;
use super::shape::Hit;
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
pub fn medium_transmittance(s: &SceneView, medium: u32, t: f32) -> Vec3 {
    let st = medium_sigma_t(&s.media[medium as usize]);
    Vec3::new(channel_transmittance(st.x, t), channel_transmittance(st.y, t), channel_transmittance(st.z, t))
}

/// Free-flight sampling over a segment of length `t_seg` (infinite for a ray that leaves the
/// scene): `u[0]` picks a channel, `u[1]` a distance with that channel's sigma_t. The pdf is the
/// mean of the three channels' (pbrt-v4's one-sample spectral MIS), so chromatic media stay
/// unbiased; grey media weigh a collision by exactly the albedo and a pass by 1.
pub fn medium_sample(s: &SceneView, medium: u32, t_seg: f32, u: [f32; 2]) -> MediumEvent {
    let m = &s.media[medium as usize];
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
    let tr = medium_transmittance(s, medium, t_seg);
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

/// The medium's phase function as a `Bsdf` (`MATERIAL_PHASE`, see `bsdf.rs`).
pub fn phase_bsdf(s: &SceneView, medium: u32, wo: Vec3) -> Bsdf {
    let m = &s.media[medium as usize];
    Bsdf {
        kind: MATERIAL_PHASE,
        color0: Vec3::ONE,
        color1: Vec3::new(m.phase as f32, 0.0, 0.0),
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
    let p = &s.primitives[prim as usize];
    if p.kind & PRIMITIVE_FLAG_MEDIUM == 0 {
        return medium;
    }
    if d.dot(ng) < 0.0 {
        p.interior
    } else {
        p.exterior
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
