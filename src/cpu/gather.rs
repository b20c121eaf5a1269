//! Radiance estimates from the photon maps; twin of `shaders/gather.glsl`. The camera path reads
//! them at its end (`render::radiance`): caustics, the indirect preview, and the global map where a
//! final-gather path ends.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::{bsdf_estimate_is_constant, bsdf_eval, bsdf_flags, facing, Bsdf};
use super::grid::for_each_photon_near;
use super::photon::{photon_flags, photon_flux, photon_wi};
use super::shape::Hit;
use super::SceneView;
use crate::layout::constants::*;

pub const MAP_GLOBAL: usize = crate::layout::constants::MAP_GLOBAL as usize;
pub const MAP_CAUSTIC: usize = crate::layout::constants::MAP_CAUSTIC as usize;
pub const MAP_VOLUME: usize = crate::layout::constants::MAP_VOLUME as usize;

/// The photons and bucket starts of `map`.
fn map_arrays<'a>(s: &SceneView<'a>, map: usize) -> (&'a [crate::layout::Photon], &'a [u32]) {
    match map {
        MAP_GLOBAL => (s.maps.global_photons, s.maps.global_starts),
        MAP_CAUSTIC => (s.maps.caustic_photons, s.maps.caustic_starts),
        _ => (s.maps.volume_photons, s.maps.volume_starts),
    }
}

/// Irradiance at `x` (normal `n`, facing the side photons must arrive from) from the photons of
/// `map` within the map's radius, with the 2D Epanechnikov kernel K = 2/(pi r^2) (1 - d^2/r^2),
/// whose integral over the disc is 1. Photons whose flags intersect `exclude` are skipped, as are
/// photons that arrived from behind the surface or lie off its tangent plane.
pub fn photon_irradiance(s: &SceneView, map: usize, x: Vec3, n: Vec3, exclude: u32) -> Vec3 {
    let g = &s.maps.grids[map];
    if g.photon_count == 0 {
        return Vec3::ZERO;
    }
    let (photons, starts) = map_arrays(s, map);
    let r2 = g.radius * g.radius;
    let thickness = PHOTON_DISC_THICKNESS * g.radius;
    let mut sum = Vec3::ZERO;
    for_each_photon_near(x, g, photons, starts, |p, d2| {
        let d = Vec3::from(p.position) - x;
        if d.dot(n).abs() > thickness || (photon_flags(p) & exclude) != 0 || photon_wi(p).dot(n) <= 0.0 {
            return;
        }
        sum += photon_flux(p, g.flux_scale) * (1.0 - d2 / r2);
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
    let g = &s.maps.grids[map];
    if g.photon_count == 0 {
        return Vec3::ZERO;
    }
    let (photons, starts) = map_arrays(s, map);
    let r2 = g.radius * g.radius;
    let thickness = if volume { f32::INFINITY } else { PHOTON_DISC_THICKNESS * g.radius };
    // Photons arriving from behind count only where the BSDF transmits.
    let both_sides = volume || bsdf_flags(b) & BSDF_TRANSMISSION != 0;
    let mut sum = Vec3::ZERO;
    for_each_photon_near(h.p, g, photons, starts, |p, d2| {
        let d = Vec3::from(p.position) - h.p;
        if d.dot(nf).abs() > thickness || (photon_flags(p) & exclude) != 0 {
            return;
        }
        let wi = photon_wi(p);
        if !both_sides && wi.dot(nf) <= 0.0 {
            return;
        }
        sum += bsdf_eval(b, wo, wi) * photon_flux(p, g.flux_scale) * (1.0 - d2 / r2);
    });
    sum * if volume { 15.0 / (8.0 * PI * r2 * g.radius) } else { 2.0 / (PI * r2) }
}
