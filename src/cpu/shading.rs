//! Camera rays, path vertices and direct light; twin of `shaders/shading.glsl`.

use glam::Vec3;

use super::bsdf::{bsdf_eval, Bsdf};
use super::light::{light_point, pick_light};
use super::rng::{rand1, rand2};
use super::shape::Hit;
use super::SceneView;
use crate::layout::constants::*;

/// Primary ray direction through film position (sx, sy) in [-1, 1]^2, sy = +1 at the top row.
pub fn camera_direction(s: &SceneView, sx: f32, sy: f32) -> Vec3 {
    let f = s.frame;
    (Vec3::from(f.camera_forward) + sx * Vec3::from(f.camera_right) + sy * Vec3::from(f.camera_up)).normalize()
}

/// Origin of the ray that leaves `h` in a direction sampled from a lobe with `lobe_flags`:
/// offset off the surface to the side the ray goes (`wo`'s side for reflection, the other for
/// transmission).
/// The offset is the hit's own (`Hit::eps`).
pub fn offset_origin(h: &Hit, wo: Vec3, lobe_flags: u32) -> Vec3 {
    let nf = if wo.dot(h.ng) > 0.0 { h.ng } else { -h.ng };
    if lobe_flags & BSDF_TRANSMISSION != 0 {
        h.p - nf * h.eps
    } else {
        h.p + nf * h.eps
    }
}

/// The length of a shadow ray that is not cast: `trace_ray` meets nothing before it.
pub const NO_RAY: f32 = -1.0;

/// A shadow ray toward a point sampled on a light, and the radiance the light reflects at the
/// shading point toward `wo` through the estimate lobes of its BSDF if nothing blocks the ray: a
/// one-sample estimate of the direct light. `t_max` is `NO_RAY` when no ray is needed (no light,
/// or nothing to reflect).
pub struct ShadowRay {
    pub origin: Vec3,
    pub direction: Vec3,
    pub t_max: f32,
    pub unoccluded: Vec3,
}

pub fn direct_light_sample(
    s: &SceneView,
    h: &Hit,
    b: &Bsdf,
    wo: Vec3,
    stream: u32,
    sample: u32,
    dim: u32,
) -> ShadowRay {
    let f = s.frame;
    let none = ShadowRay { origin: h.p, direction: Vec3::Y, t_max: NO_RAY, unoccluded: Vec3::ZERO };
    if f.light_count == 0 {
        return none;
    }
    let li = pick_light(s, rand1(stream, sample, f.seed, dim + RNG_LIGHT_PICK));
    let l = &s.lights[li as usize];
    let lp = light_point(s, l, rand2(stream, sample, f.seed, dim + RNG_LIGHT_U));
    let to_light = lp.p - h.p;
    let dist2 = to_light.dot(to_light);
    let dist = dist2.sqrt();
    let wi = to_light / dist;
    let fr = bsdf_eval(b, wo, wi);
    if fr == Vec3::ZERO {
        return none;
    }
    // Point light: E = I cos / d^2. Area light: L cos cos' / d^2 over the point's pdf by area.
    let mut geometry = b.ns.dot(wi).abs() / dist2;
    // The shadow ray stops short of the light's point by its offset, over the cosine there: a
    // hit on the light's own surface moves along a grazing ray by its error over that cosine.
    let mut shadow_end = lp.eps;
    if l.kind != LIGHT_POINT {
        let cos_l = -lp.n.dot(wi);
        if cos_l <= 0.0 {
            return none;
        }
        geometry *= cos_l * lp.inv_pdf;
        shadow_end = lp.eps / cos_l.max(1e-2);
    }
    // The shadow ray runs from the offset origin to the sampled point itself: aiming along wi from
    // the offset origin would meet the light's plane early at grazing angles.
    let origin = offset_origin(h, wi, BSDF_REFLECTION);
    let to_target = lp.p - origin;
    let shadow_length = to_target.length();
    ShadowRay {
        origin,
        direction: to_target / shadow_length,
        t_max: (shadow_length - shadow_end).max(0.0),
        unoccluded: fr * lp.emitted * (geometry / l.pick_probability),
    }
}
