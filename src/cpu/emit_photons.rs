//! Photon paths from the lights and the photons they leave at diffuse surfaces; twin of
//! `shaders/emit_photons.comp` and `shaders/photon_path.glsl`.

use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::{bsdf_flags, bsdf_sample, facing, material_bsdf, shading_adjoint};
use super::light::{light_emit, pick_light};
use super::medium::{medium_after, medium_hit, medium_sample, phase_bsdf};
use super::photon::pack_photon;
use super::rng::{bsdf_numbers, qmc2, rand1, rand2, sequence_point};
use super::shading::{offset_origin, ray_skip};
use super::shape::shape_hit;
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::{EmitParams, Photon};

/// The `qmc2` stream and index of photon path `path`: global and caustic passes (`pass` even
/// and odd) are two sequences, and pass k's paths are their points k x paths + path.
pub fn photon_sequence(path: u32, params: &EmitParams) -> (u32, u32) {
    sequence_point(params.pass & 1, params.pass >> 1, params.total_paths, path)
}

/// Traces photon path `path` and calls `store(x, flux, wi, side, flags, volume)` at every surface
/// with estimate lobes it meets (`side`: its normal facing the photon) and (`volume` true, `side`
/// zero) every collision in a medium, exactly as the kernel does.
pub fn trace_photon_path(
    s: &SceneView,
    path: u32,
    params: &EmitParams,
    mut store: impl FnMut(Vec3, Vec3, Vec3, Vec3, u32, bool),
) {
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
    // The render's photon paths of one kind (global or caustic) are one low-discrepancy
    // sequence in the numbers that spread photons evenly: where they leave the light, where to,
    // where they bounce.
    let seq = photon_sequence(path, params);
    let (mut o, mut d, mut flux) = light_emit(
        s,
        l,
        qmc2(seq.0, seq.1, seed, dim + RNG_PHOTON_POSITION),
        qmc2(seq.0, seq.1, seed, dim + RNG_PHOTON_DIRECTION),
    );
    // Each path carries 1/N of the picked light's power, divided by the pick probability.
    flux /= l.photon_probability * params.total_paths as f32;
    let mut specular_only = true;
    let mut medium = l.medium;
    // The smooth triangle the current ray leaves, which it must not meet again (see trace_ray).
    let mut skip = NO_LIGHT;
    // Scattering events so far (surfaces and media; null boundaries are none).
    let mut depth = 0;
    let mut step = 0;
    while step < params.max_depth + MEDIUM_CROSSINGS && depth < params.max_depth {
        let (prim, mut t) = trace_ray(s, o, d, f32::INFINITY, false, skip);
        let mut scattered = false;
        let mut collision = Vec3::ZERO;
        let mut medium_weight = Vec3::ONE;
        // A free flight through the medium: a collision before the surface scatters the photon
        // (or absorbs it, by roulette on the albedo below); passing it, the flux keeps its mean.
        if medium != NO_MEDIUM {
            let e = medium_sample(s, medium, o, d, t, rand2(path, params.pass, seed, dim + RNG_PHOTON_MEDIUM + step));
            scattered = e.scattered;
            t = e.t;
            if scattered {
                collision = e.collision;
                medium_weight = e.weight;
            } else {
                flux *= e.weight;
            }
        }
        step += 1;
        if !scattered && prim == NO_LIGHT {
            return;
        }
        skip = if scattered { NO_LIGHT } else { ray_skip(s, prim) };
        let wo = -d;
        let (h, b) = if scattered {
            (medium_hit(o + d * t, wo), phase_bsdf(s, medium, wo))
        } else {
            let h = shape_hit(s, prim, o, d, t);
            let m = &s.materials[h.material as usize];
            if m.kind == MATERIAL_NULL {
                // An invisible boundary: straight through into the medium beyond, not a bounce.
                medium = medium_after(s, prim, h.ng, d, medium);
                o = offset_origin(&h, wo, BSDF_TRANSMISSION);
                continue;
            }
            let b = material_bsdf(s, m, &h);
            (h, b)
        };
        let lobes = bsdf_flags(&b);
        let bdim = dim + (depth + 1) * RNG_DIMS_PER_BOUNCE;
        // A black surface reflects nothing but keeps the photons that reach it: no lookup of its
        // own reads them (its BSDF is zero), but a neighbour's disc that reaches over it does,
        // where the neighbour's surface lies hidden behind it (the box's light, 0.1 mm below the
        // ceiling: without them the ceiling around the light reads a third too dark).
        if lobes == 0 || lobes & BSDF_ESTIMATE != 0 {
            let flags = if depth == 0 {
                PHOTON_FLAG_DIRECT
            } else if specular_only {
                PHOTON_FLAG_CAUSTIC
            } else {
                0
            };
            // A collision in a medium stores a volume photon carrying its sigma_t-weighted flux,
            // in the global pass only: the caustic map is of surfaces.
            if scattered {
                if params.caustics_only == 0 {
                    store(h.p, flux * collision, wo, Vec3::ZERO, flags, true);
                }
            } else if params.caustics_only == 0 || flags == PHOTON_FLAG_CAUSTIC {
                store(h.p, flux, wo, facing(&b, wo), flags, false);
            }
            // A caustic-only pass has no use for the path once it has met an estimate lobe.
            if params.caustics_only != 0 || lobes == 0 {
                return;
            }
        }
        let u = bsdf_numbers(path, params.pass, seq, seed, bdim + RNG_PHOTON_BOUNCE);
        let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_ALL);
        if smp.flags == 0 {
            return;
        }
        // Russian roulette on the sample's weight (with a collision's albedo and the adjoint's
        // factor on a bumped surface): survivors keep their flux up to its colour.
        let w = smp.weight * medium_weight * shading_adjoint(&b, wo, smp.wi);
        let survive = w.max_element().min(1.0);
        if rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive {
            return;
        }
        flux *= w / survive;
        if smp.flags & BSDF_ESTIMATE != 0 {
            specular_only = false;
        }
        if !scattered && smp.flags & BSDF_TRANSMISSION != 0 {
            medium = medium_after(s, prim, h.ng, smp.wi, medium);
        }
        o = offset_origin(&h, wo, smp.flags);
        d = smp.wi;
        depth += 1;
    }
}

/// The photon maps of one emission, unsorted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonMaps {
    pub global: Vec<Photon>,
    pub caustic: Vec<Photon>,
    /// Collisions in media (global pass only).
    pub volume: Vec<Photon>,
}

/// Traces paths `params.path_begin ..+ path_count` (in parallel) and returns their photons in
/// path order; the kernel stores the same photons in an order set by its atomics.
pub fn emit_photons(s: &SceneView, params: &EmitParams) -> PhotonMaps {
    let inv_scale = params.total_paths as f32 / s.frame.total_light_power;
    // One vector per run of paths a thread takes (not per path: 200k small allocations cost
    // more than the flatten), still in path order.
    let per_run: Vec<Vec<(Photon, u32, bool)>> = (params.path_begin..params.path_begin + params.path_count)
        .into_par_iter()
        .fold(Vec::new, |mut stored, path| {
            trace_photon_path(s, path, params, |x, flux, wi, side, flags, volume| {
                stored.push((pack_photon(x, flux, inv_scale, wi, side, flags), flags, volume));
            });
            stored
        })
        .collect();
    let mut maps = PhotonMaps::default();
    for (photon, flags, volume) in per_run.into_iter().flatten() {
        if volume {
            maps.volume.push(photon);
            continue;
        }
        if params.caustics_only == 0 {
            maps.global.push(photon);
        }
        if flags == PHOTON_FLAG_CAUSTIC {
            maps.caustic.push(photon);
        }
    }
    maps
}
