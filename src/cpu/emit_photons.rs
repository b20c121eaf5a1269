//! Photon paths from the lights and the photons they leave at diffuse surfaces; twin of
//! `shaders/emit_photons.comp` and `shaders/photon_path.glsl`.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::photon::pack_photon;
use super::rng::{rand1, rand2};
use super::shading::{
    cosine_direction, dielectric_scatter, pick_light, primitive_normal, reflect, sample_light_point, sphere_direction,
};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::{EmitParams, Photon};

/// Traces photon path `path` and calls `store(x, flux, wi, flags)` at every diffuse surface it
/// meets, exactly as the kernel does.
pub fn trace_photon_path(s: &SceneView, path: u32, params: &EmitParams, mut store: impl FnMut(Vec3, Vec3, Vec3, u32)) {
    let f = s.frame;
    if f.light_count == 0 {
        return;
    }
    let seed = f.seed;
    let dim = RNG_PHOTON_DOMAIN;
    let l = &s.lights[pick_light(s, rand1(path, params.pass, seed, dim + RNG_PHOTON_LIGHT_PICK)) as usize];
    let u_pos = rand2(path, params.pass, seed, dim + RNG_PHOTON_POSITION);
    let u_dir = rand2(path, params.pass, seed, dim + RNG_PHOTON_DIRECTION);
    let (mut o, ln) = sample_light_point(l, u_pos);
    // Each path carries 1/N of the picked light's power, divided by the pick probability.
    let (mut d, mut flux);
    if l.kind == LIGHT_POINT {
        d = sphere_direction(u_dir);
        flux = 4.0 * PI * Vec3::from(l.radiance);
    } else {
        d = cosine_direction(ln, u_dir);
        o += ln * f.ray_epsilon;
        flux = PI * l.area * Vec3::from(l.radiance);
    }
    flux /= l.pick_probability * params.total_paths as f32;
    let mut specular_only = true;
    for depth in 0..params.max_depth {
        let (prim, t) = trace_ray(s.nodes, s.primitives, o, d, f32::INFINITY, false);
        if prim == NO_LIGHT {
            return;
        }
        let x = o + t * d;
        let n = primitive_normal(s, prim, x);
        let m = &s.materials[s.primitives[prim as usize].material as usize];
        let nf = if n.dot(d) < 0.0 { n } else { -n };
        let bdim = dim + (depth + 1) * RNG_DIMS_PER_BOUNCE;
        if m.kind == MATERIAL_DIFFUSE {
            let albedo = Vec3::from(m.reflectance);
            let survive = albedo.max_element();
            if survive <= 0.0 {
                return; // a black surface keeps nothing and reflects nothing
            }
            let flags = if depth == 0 {
                PHOTON_FLAG_DIRECT
            } else if specular_only {
                PHOTON_FLAG_CAUSTIC
            } else {
                0
            };
            if params.caustics_only == 0 || flags == PHOTON_FLAG_CAUSTIC {
                store(x, flux, -d, flags);
            }
            // A caustic-only pass has no use for the path once it has met a diffuse surface.
            if params.caustics_only != 0 {
                return;
            }
            // Russian roulette on the albedo: survivors keep their flux up to the colour filter.
            if rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive {
                return;
            }
            flux *= albedo / survive;
            d = cosine_direction(nf, rand2(path, params.pass, seed, bdim + RNG_PHOTON_BOUNCE));
            o = x + nf * f.ray_epsilon;
            specular_only = false;
        } else if m.kind == MATERIAL_MIRROR {
            let tint = Vec3::from(m.reflectance);
            let survive = tint.max_element();
            if rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive {
                return;
            }
            flux *= tint / survive;
            d = reflect(d, nf);
            o = x + nf * f.ray_epsilon;
        } else {
            let front = n.dot(d) < 0.0;
            // Dielectric: reflection or refraction with the Fresnel probability, weight 1.
            (o, d) =
                dielectric_scatter(s, x, nf, front, m.ior, rand1(path, params.pass, seed, bdim + RNG_PHOTON_BOUNCE), d);
        }
    }
}

/// The two photon maps of one emission, unsorted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonMaps {
    pub global: Vec<Photon>,
    pub caustic: Vec<Photon>,
}

/// Traces paths `params.path_begin ..+ path_count` (in parallel) and returns their photons in
/// path order; the kernel stores the same photons in an order set by its atomics.
pub fn emit_photons(s: &SceneView, params: &EmitParams) -> PhotonMaps {
    let inv_scale = params.total_paths as f32 / s.frame.total_light_power;
    let per_path: Vec<Vec<(Photon, u32)>> = (params.path_begin..params.path_begin + params.path_count)
        .into_par_iter()
        .map(|path| {
            let mut stored = Vec::new();
            trace_photon_path(s, path, params, |x, flux, wi, flags| {
                stored.push((pack_photon(x, flux, inv_scale, wi, flags), flags));
            });
            stored
        })
        .collect();
    let mut maps = PhotonMaps::default();
    for (photon, flags) in per_path.into_iter().flatten() {
        if params.caustics_only == 0 {
            maps.global.push(photon);
        }
        if flags == PHOTON_FLAG_CAUSTIC {
            maps.caustic.push(photon);
        }
    }
    maps
}
