//! Radiance estimates from the photon maps and the final gather; twin of `shaders/gather.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::grid::for_each_photon_near;
use super::photon::{photon_flags, photon_flux, photon_wi};
use super::rng::{rand1, rand2};
use super::shading::{cosine_direction, dielectric_scatter, primitive_normal, reflect};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;

pub const MAP_GLOBAL: usize = 0;
pub const MAP_CAUSTIC: usize = 1;

/// Irradiance at `x` (normal `n`, facing the side photons must arrive from) from the photons of
/// `map` within the map's radius, with the 2D Epanechnikov kernel K = 2/(pi r^2) (1 - d^2/r^2),
/// whose integral over the disc is 1. Photons whose flags intersect `exclude` are skipped, as are
/// photons that arrived from behind the surface or lie off its tangent plane.
pub fn photon_irradiance(s: &SceneView, map: usize, x: Vec3, n: Vec3, exclude: u32) -> Vec3 {
    let g = &s.maps.grids[map];
    if g.photon_count == 0 {
        return Vec3::ZERO;
    }
    let (photons, starts) = if map == MAP_GLOBAL {
        (s.maps.global_photons, s.maps.global_starts)
    } else {
        (s.maps.caustic_photons, s.maps.caustic_starts)
    };
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

/// Indirect radiance toward the viewer at a diffuse point `x` (normal `n` facing the viewer) of
/// albedo `albedo`, read from the global map at `x` without the direct and caustic photons (the
/// fast preview when `gather_rays` is 0).
pub fn indirect_preview(s: &SceneView, x: Vec3, n: Vec3, albedo: Vec3) -> Vec3 {
    albedo * (1.0 / PI) * photon_irradiance(s, MAP_GLOBAL, x, n, PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC)
}

/// One final-gather ray's share of the indirect radiance at `x`: cosine-distributed ray `j`
/// whose first diffuse hit reads the global map (mirrors and glass on the way are followed),
/// weighted 1/gather_rays. Emission met on the way is not counted: direct light and caustics
/// cover it.
#[allow(clippy::too_many_arguments)] // the kernel's signature, kept identical
pub fn gather_ray(
    s: &SceneView,
    x: Vec3,
    n: Vec3,
    albedo: Vec3,
    stream: u32,
    sample: u32,
    j: u32,
    rays: &mut u32,
) -> Vec3 {
    let f = s.frame;
    let gdim = RNG_GATHER_DOMAIN + j * RNG_GATHER_DIMS_PER_RAY;
    let mut d = cosine_direction(n, rand2(stream, sample, f.seed, gdim));
    let mut o = x + n * f.ray_epsilon;
    let mut throughput = Vec3::ONE;
    for bounce in 0..f.max_depth {
        *rays += 1;
        let (prim, t) = trace_ray(s.nodes, s.primitives, o, d, f32::INFINITY, false);
        if prim == NO_LIGHT {
            break;
        }
        let y = o + t * d;
        let ny = primitive_normal(s, prim, y);
        let m = &s.materials[s.primitives[prim as usize].material as usize];
        let front = ny.dot(d) < 0.0;
        let nf = if front { ny } else { -ny };
        if m.kind == MATERIAL_DIFFUSE {
            // Cosine sampling cancels the cosine and the 1/pi of the BRDF at x: weight = albedo.
            let radiance = Vec3::from(m.reflectance) * (1.0 / PI) * photon_irradiance(s, MAP_GLOBAL, y, nf, 0);
            return albedo * throughput * radiance / f.gather_rays as f32;
        }
        if m.kind == MATERIAL_MIRROR {
            throughput *= Vec3::from(m.reflectance);
            d = reflect(d, nf);
            o = y + nf * f.ray_epsilon;
            continue;
        }
        // Dielectric: reflection or refraction with the Fresnel probability, weight 1.
        (o, d) = dielectric_scatter(s, y, nf, front, m.ior, rand1(stream, sample, f.seed, gdim + 1 + bounce), d);
    }
    Vec3::ZERO
}

/// Caustic radiance toward the viewer at `x` from the caustic map.
pub fn caustic_light(s: &SceneView, x: Vec3, n: Vec3, albedo: Vec3) -> Vec3 {
    albedo * (1.0 / PI) * photon_irradiance(s, MAP_CAUSTIC, x, n, 0)
}
