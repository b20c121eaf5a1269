//! Lights behind one interface: pick by power, a point on a light, a photon leaving it; twin of
//! `shaders/light.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::material_emission;
use super::sampling::{cosine_direction, sphere_direction};
use super::shape::shape_sample;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Light;

/// Index of the light whose cdf interval holds `u`: lights are picked in proportion to power.
pub fn pick_light(s: &SceneView, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, s.frame.light_count - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u < s.lights[mid as usize].cdf {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// A point on a light: its position, its normal (zero for a point light) and what it emits
/// there: radiance toward its front side, or a point light's intensity (W/sr).
#[derive(Clone, Copy, Debug)]
pub struct LightPoint {
    pub p: Vec3,
    pub n: Vec3,
    pub emitted: Vec3,
    /// 1/pdf of the point by area (scene units squared); 1 for a point light.
    pub inv_pdf: f32,
    /// Offset of rays that start or end at the point (`Hit::eps`).
    pub eps: f32,
}

/// A point on light `l` (see `shape_sample` for the density of area lights' points).
pub fn light_point(s: &SceneView, l: &Light, u: [f32; 2]) -> LightPoint {
    match l.kind {
        LIGHT_AREA => {
            let (h, inv_pdf) = shape_sample(s, l.primitive, u);
            let emitted = material_emission(s, &s.materials[h.material as usize], &h);
            LightPoint { p: h.p, n: h.ng, emitted, inv_pdf, eps: h.eps }
        }
        _ => LightPoint {
            p: Vec3::from(l.position),
            n: Vec3::ZERO,
            emitted: Vec3::from(l.intensity),
            inv_pdf: 1.0,
            eps: s.frame.ray_epsilon,
        },
    }
}

/// A photon leaving light `l`: (origin, direction, power before the division by the pick
/// probability and the path count). Area lights emit from a uniform point in a
/// cosine-distributed direction (Lambertian), point lights uniformly in all directions.
pub fn light_emit(s: &SceneView, l: &Light, u_pos: [f32; 2], u_dir: [f32; 2]) -> (Vec3, Vec3, Vec3) {
    let lp = light_point(s, l, u_pos);
    match l.kind {
        LIGHT_AREA => (lp.p + lp.n * lp.eps, cosine_direction(lp.n, u_dir), PI * lp.inv_pdf * lp.emitted),
        _ => (lp.p, sphere_direction(u_dir), 4.0 * PI * lp.emitted),
    }
}
