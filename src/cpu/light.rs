//! Lights behind one interface: pick by power, a light sample toward a point, a photon leaving a
//! light; twin of `shaders/light.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::material_emission;
use super::sampling::{cone_direction, cosine_direction, disc_point, onb};
use super::shape::shape_sample;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Light;

/// Index of the light whose cdf interval holds `u`: lights are picked in proportion to power,
/// among those that cast direct light (`photons` false: `cdf`) or emit photons (`photons` true:
/// `photon_cdf`). A light left out of a distribution has an empty interval and is never picked.
pub fn pick_light(s: &SceneView, u: f32, photons: bool) -> u32 {
    let (mut lo, mut hi) = (0u32, s.frame.light_count - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        let l = &s.lights[mid as usize];
        if u < (if photons { l.photon_cdf } else { l.cdf }) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// Intensity profile of point and spot lights along unit direction `w` (away from the light):
/// a smooth step (3t^2 - 2t^3, as pbrt-v4 and POV-Ray's `cubic_spline`) in cos from the outer
/// cone to the inner one, times cos^exponent (POV-Ray's tightness). A point light's cone is the
/// whole sphere, so its profile is 1.
pub fn spot_falloff(l: &Light, w: Vec3) -> f32 {
    let c = w.dot(Vec3::from(l.direction));
    let t = ((c - l.cos_outer) * l.falloff_scale).clamp(0.0, 1.0);
    let tight = if l.exponent > 0.0 { c.max(0.0).powf(l.exponent) } else { 1.0 };
    t * t * (3.0 - 2.0 * t) * tight
}

/// Light `l` as seen from `x`: the direction `wi` toward it, a point `p` to aim the shadow ray
/// at (beyond the scene for a distant light) and `weight`, the radiance arriving along -wi
/// divided by the solid-angle pdf of the sample (so the direct light is f |cos| weight / pick
/// probability).
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub p: Vec3,
    pub wi: Vec3,
    pub weight: Vec3,
}

pub fn light_sample(s: &SceneView, l: &Light, x: Vec3, u: [f32; 2]) -> LightSample {
    match l.kind {
        LIGHT_AREA => {
            // Uniform by area: L cos' / d^2 times the area.
            let h = shape_sample(s, l.primitive, u);
            let to_light = h.p - x;
            let dist2 = to_light.dot(to_light);
            let wi = to_light / dist2.sqrt();
            let cos_l = -h.ng.dot(wi);
            let weight = if cos_l > 0.0 {
                material_emission(s, &s.materials[h.material as usize], &h) * (cos_l * l.area / dist2)
            } else {
                Vec3::ZERO
            };
            LightSample { p: h.p, wi, weight }
        }
        LIGHT_DISTANT => {
            // Uniform in the cone of directions; intensity holds radiance times the cone's solid angle.
            let wi = -cone_direction(Vec3::from(l.direction), l.cos_outer, u);
            let beyond = (x - Vec3::from(l.position)).length() + 2.0 * l.radius;
            LightSample { p: x + wi * beyond, wi, weight: Vec3::from(l.intensity) }
        }
        _ => {
            // Point and spot lights: I(w) / d^2.
            let p = Vec3::from(l.position);
            let to_light = p - x;
            let dist2 = to_light.dot(to_light);
            let wi = to_light / dist2.sqrt();
            LightSample { p, wi, weight: Vec3::from(l.intensity) * (spot_falloff(l, -wi) / dist2) }
        }
    }
}

/// A photon leaving light `l`: (origin, direction, power before the division by the pick
/// probability and the path count). Area lights emit from a uniform point in a
/// cosine-distributed direction (Lambertian); point and spot lights uniformly in their cone,
/// weighted by the spot's profile; distant lights from a uniform point of the disc of the
/// scene's bounding sphere that faces them, uniformly in their cone of directions.
pub fn light_emit(s: &SceneView, l: &Light, u_pos: [f32; 2], u_dir: [f32; 2]) -> (Vec3, Vec3, Vec3) {
    let axis = Vec3::from(l.direction);
    match l.kind {
        LIGHT_AREA => {
            let h = shape_sample(s, l.primitive, u_pos);
            let emitted = material_emission(s, &s.materials[h.material as usize], &h);
            (h.p + h.ng * s.frame.ray_epsilon, cosine_direction(h.ng, u_dir), PI * l.area * emitted)
        }
        LIGHT_DISTANT => {
            let (t, b) = onb(axis);
            let q = disc_point(u_pos);
            let (qx, qy) = (q[0] * l.radius, q[1] * l.radius);
            let o = Vec3::from(l.position) - axis * l.radius + qx * t + qy * b;
            let d = cone_direction(axis, l.cos_outer, u_dir);
            // Flux through the disc: radiance times solid angle times the projected disc area.
            (o, d, Vec3::from(l.intensity) * (PI * l.radius * l.radius * d.dot(axis)))
        }
        _ => {
            let d = cone_direction(axis, l.cos_outer, u_dir);
            (Vec3::from(l.position), d, Vec3::from(l.intensity) * (2.0 * PI * (1.0 - l.cos_outer) * spot_falloff(l, d)))
        }
    }
}
