//! Radiance estimates from the photon maps; twin of `shaders/gather.glsl`. The camera path reads
//! them at its end (`render::radiance`): caustics, the indirect preview, and the global map where a
//! final-gather path ends.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::{bsdf_estimate_is_constant, bsdf_eval, bsdf_flags, facing, Bsdf};
use super::photon_index::PhotonIndex;
use super::shape::Hit;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::GridParams;

pub const MAP_GLOBAL: usize = crate::layout::constants::MAP_GLOBAL as usize;
pub const MAP_CAUSTIC: usize = crate::layout::constants::MAP_CAUSTIC as usize;
pub const MAP_VOLUME: usize = crate::layout::constants::MAP_VOLUME as usize;

/// The lookup layout of `map`, which must have left out only photons that `exclude` skips
/// (see `render::excluded_by_every_lookup`).
fn map_index<'a>(s: &SceneView<'a>, map: usize, exclude: u32) -> (&'a PhotonIndex, &'a GridParams) {
    let index = &s.maps.indices[map];
    assert_eq!(index.dropped & !exclude, 0, "map {map} left out photons of flags a lookup keeps");
    (index, &s.maps.grids[map])
}

/// Irradiance at `x` (normal `n`, facing the side photons must arrive from) from the photons of
/// `map` within the map's radius, with the 2D Epanechnikov kernel K = 2/(pi r^2) (1 - d^2/r^2),
/// whose integral over the disc is 1. Photons whose flags intersect `exclude` are skipped, as are
/// photons that arrived from behind the surface or lie off its tangent plane.
pub fn photon_irradiance(s: &SceneView, map: usize, x: Vec3, n: Vec3, exclude: u32) -> Vec3 {
    let (index, g) = map_index(s, map, exclude);
    if g.photon_count == 0 {
        return Vec3::ZERO;
    }
    let r2 = g.radius * g.radius;
    let thickness = PHOTON_DISC_THICKNESS * g.radius;
    let mut sum = Vec3::ZERO;
    index.for_each_near(x, g, |pos, flags, p, d2| {
        let d = pos - x;
        if d.dot(n).abs() > thickness || (flags & exclude) != 0 || p.wi.dot(n) <= 0.0 {
            return;
        }
        sum += p.flux * (1.0 - d2 / r2);
    });
    sum * (2.0 / (PI * r2))
}

/// Radiance toward `wo` at `h` through the estimate lobes of `b`, from the photons of `map`
/// (those with flags in `exclude` skipped): each photon weighted by the BSDF's value for its
/// direction. The volume map (`b` a medium's phase function) is read over the ball of radius r
/// with the 3D Epanechnikov kernel 15/(8 pi r^3) (1 - d^2/r^2): the sum of flux times phase
/// over the collisions near the point, which estimates sigma_t times the in-scattered radiance
/// (Jensen and Christensen 1998); the caller divides by sigma_t.
pub fn photon_radiance(s: &SceneView, map: usize, h: &Hit, b: &Bsdf, wo: Vec3, exclude: u32) -> Vec3 {
    let volume = map == MAP_VOLUME;
    let nf = facing(b, wo);
    // A Lambertian BSDF has one value for every photon: sum the irradiance, apply it once.
    if !volume && bsdf_estimate_is_constant(b) {
        return bsdf_eval(b, wo, nf) * photon_irradiance(s, map, h.p, nf, exclude);
    }
    let (index, g) = map_index(s, map, exclude);
    if g.photon_count == 0 {
        return Vec3::ZERO;
    }
    let r2 = g.radius * g.radius;
    let thickness = if volume { f32::INFINITY } else { PHOTON_DISC_THICKNESS * g.radius };
    // Photons arriving from behind count only where the BSDF transmits.
    let both_sides = volume || bsdf_flags(b) & BSDF_TRANSMISSION != 0;
    let mut sum = Vec3::ZERO;
    index.for_each_near(h.p, g, |pos, flags, p, d2| {
        let d = pos - h.p;
        if d.dot(nf).abs() > thickness || (flags & exclude) != 0 {
            return;
        }
        if !both_sides && p.wi.dot(nf) <= 0.0 {
            return;
        }
        sum += bsdf_eval(b, wo, p.wi) * p.flux * (1.0 - d2 / r2);
    });
    sum * if volume { 15.0 / (8.0 * PI * r2 * g.radius) } else { 2.0 / (PI * r2) }
}
