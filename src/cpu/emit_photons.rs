//! Photon paths from the lights and the photons they leave at diffuse surfaces; twin of
//! `shaders/emit_photons.comp` and `shaders/photon_path.glsl`.

use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::{bsdf_flags, bsdf_sample, material_bsdf};
use super::light::{light_emit, pick_light};
use super::photon::pack_photon;
use super::rng::{rand1, rand2, rand4};
use super::shading::{offset_origin, ray_skip};
use super::shape::shape_hit;
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::{EmitParams, Photon};

/// Traces photon path `path` and calls `store(x, flux, wi, flags)` at every surface with
/// estimate lobes it meets, exactly as the kernel does.
pub fn trace_photon_path(s: &SceneView, path: u32, params: &EmitParams, mut store: impl FnMut(Vec3, Vec3, Vec3, u32)) {
    let f = s.frame;
    if f.light_count == 0 {
        return;
    }
    let seed = f.seed;
    let dim = RNG_PHOTON_DOMAIN;
    let l = &s.lights[pick_light(s, rand1(path, params.pass, seed, dim + RNG_PHOTON_LIGHT_PICK), true) as usize];
    // A scene whose lights all give direct light only picks one with probability 0.
    if l.photon_probability <= 0.0 {
        return;
    }
    let (mut o, mut d, mut flux) = light_emit(
        s,
        l,
        rand2(path, params.pass, seed, dim + RNG_PHOTON_POSITION),
        rand2(path, params.pass, seed, dim + RNG_PHOTON_DIRECTION),
    );
    // Each path carries 1/N of the picked light's power, divided by the pick probability.
    flux /= l.photon_probability * params.total_paths as f32;
    let mut specular_only = true;
    let mut skip = NO_LIGHT;
    for depth in 0..params.max_depth {
        let (prim, t) = trace_ray(s, o, d, f32::INFINITY, false, skip);
        if prim == NO_LIGHT {
            return;
        }
        let h = shape_hit(s, prim, o, d, t);
        skip = ray_skip(s, prim);
        let wo = -d;
        let b = material_bsdf(s, &s.materials[h.material as usize], &h);
        let lobes = bsdf_flags(&b);
        if lobes == 0 {
            return; // a black surface keeps nothing and reflects nothing
        }
        let bdim = dim + (depth + 1) * RNG_DIMS_PER_BOUNCE;
        if lobes & BSDF_ESTIMATE != 0 {
            let flags = if depth == 0 {
                PHOTON_FLAG_DIRECT
            } else if specular_only {
                PHOTON_FLAG_CAUSTIC
            } else {
                0
            };
            if params.caustics_only == 0 || flags == PHOTON_FLAG_CAUSTIC {
                store(h.p, flux, wo, flags);
            }
            // A caustic-only pass has no use for the path once it has met an estimate lobe.
            if params.caustics_only != 0 {
                return;
            }
        }
        let u = rand4(path, params.pass, seed, bdim + RNG_PHOTON_BOUNCE);
        let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_ALL);
        if smp.flags == 0 {
            return;
        }
        // Russian roulette on the sample's weight: survivors keep their flux up to its colour.
        let survive = smp.weight.max_element();
        if rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive {
            return;
        }
        flux *= smp.weight / survive;
        if smp.flags & BSDF_ESTIMATE != 0 {
            specular_only = false;
        }
        o = offset_origin(&h, wo, smp.flags);
        d = smp.wi;
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
