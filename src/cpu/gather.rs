//! Radiance estimates from the photon maps and the final gather; twin of `shaders/gather.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::{
    bsdf_estimate_is_constant, bsdf_eval, bsdf_flags, bsdf_path_probability, bsdf_sample, facing, material_bsdf, Bsdf,
};
use super::grid::for_each_photon_near;
use super::photon::{photon_flags, photon_flux, photon_wi};
use super::rng::rand4;
use super::shading::offset_origin;
use super::shape::{shape_hit, Hit};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;

pub const MAP_GLOBAL: usize = 0;
pub const MAP_CAUSTIC: usize = 1;

/// The photons and bucket starts of `map`.
fn map_arrays<'a>(s: &SceneView<'a>, map: usize) -> (&'a [crate::layout::Photon], &'a [u32]) {
    if map == MAP_GLOBAL {
        (s.maps.global_photons, s.maps.global_starts)
    } else {
        (s.maps.caustic_photons, s.maps.caustic_starts)
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
/// direction.
pub fn photon_radiance(s: &SceneView, map: usize, h: &Hit, b: &Bsdf, wo: Vec3, exclude: u32) -> Vec3 {
    let nf = facing(b, wo);
    // A Lambertian BSDF has one value for every photon: sum the irradiance, apply it once.
    if bsdf_estimate_is_constant(b) {
        return bsdf_eval(b, wo, nf) * photon_irradiance(s, map, h.p, nf, exclude);
    }
    let g = &s.maps.grids[map];
    if g.photon_count == 0 {
        return Vec3::ZERO;
    }
    let (photons, starts) = map_arrays(s, map);
    let r2 = g.radius * g.radius;
    let thickness = PHOTON_DISC_THICKNESS * g.radius;
    // Photons arriving from behind count only where the BSDF transmits.
    let both_sides = bsdf_flags(b) & BSDF_TRANSMISSION != 0;
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
    sum * (2.0 / (PI * r2))
}

/// Indirect radiance toward `wo` at `h`, read from the global map at `h` without the direct and
/// caustic photons (the fast preview when `gather_rays` is 0).
pub fn indirect_preview(s: &SceneView, h: &Hit, b: &Bsdf, wo: Vec3) -> Vec3 {
    photon_radiance(s, MAP_GLOBAL, h, b, wo, PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC)
}

/// One final-gather ray's share of the indirect radiance toward `wo` at `h`: ray `j`, sampled
/// from the estimate lobes of `b`, follows path lobes to a surface with estimate lobes and reads
/// the global map there, weighted 1/gather_rays. Emission met on the way is not counted: direct
/// light and caustics cover it.
#[allow(clippy::too_many_arguments)] // the kernel's signature, kept identical
pub fn gather_ray(
    s: &SceneView,
    h: &Hit,
    b: &Bsdf,
    wo: Vec3,
    stream: u32,
    sample: u32,
    j: u32,
    rays: &mut u32,
) -> Vec3 {
    let f = s.frame;
    let gdim = RNG_GATHER_DOMAIN + j * RNG_GATHER_DIMS_PER_RAY;
    let u0 = rand4(stream, sample, f.seed, gdim);
    let first = bsdf_sample(b, wo, [u0[2], u0[0], u0[1]], LOBES_ESTIMATE);
    if first.flags == 0 {
        return Vec3::ZERO;
    }
    let mut d = first.wi;
    let mut o = offset_origin(h, wo, first.flags);
    let mut throughput = Vec3::ONE;
    for bounce in 0..f.max_depth {
        *rays += 1;
        let (prim, t) = trace_ray(s, o, d, f32::INFINITY, false);
        if prim == NO_LIGHT {
            break;
        }
        let y = shape_hit(s, prim, o, d, t);
        let wo_y = -d;
        let by = material_bsdf(s, &s.materials[y.material as usize], &y);
        let u = rand4(stream, sample, f.seed, gdim + 1 + bounce);
        let q = bsdf_path_probability(&by, wo_y);
        if u[3] < q {
            let smp = bsdf_sample(&by, wo_y, [u[0], u[1], u[2]], LOBES_PATH);
            if smp.flags == 0 {
                break;
            }
            throughput *= smp.weight / q;
            o = offset_origin(&y, wo_y, smp.flags);
            d = smp.wi;
            continue;
        }
        if bsdf_flags(&by) & BSDF_ESTIMATE == 0 {
            break;
        }
        let radiance = photon_radiance(s, MAP_GLOBAL, &y, &by, wo_y, 0);
        return first.weight * (throughput / (1.0 - q)) * radiance / f.gather_rays as f32;
    }
    Vec3::ZERO
}

/// Caustic radiance toward `wo` at `h` from the caustic map.
pub fn caustic_light(s: &SceneView, h: &Hit, b: &Bsdf, wo: Vec3) -> Vec3 {
    photon_radiance(s, MAP_CAUSTIC, h, b, wo, 0)
}
