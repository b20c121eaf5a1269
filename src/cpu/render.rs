//! The four terms of each pixel, accumulated over rows and samples; twin of
//! `shaders/render.comp`.

use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::Bsdf;
use super::bsdf::{bsdf_flags, bsdf_path_probability, bsdf_sample, material_bsdf, material_emission};
use super::gather::{photon_radiance, MAP_CAUSTIC, MAP_GLOBAL};
use super::light::environment_radiance;
use super::rng::rand4;
use super::shading::{camera_ray, direct_light_sample, offset_origin, ray_skip, NO_RAY};
use super::shape::{shape_hit, Hit};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::DispatchRange;

/// What the ray of the current step is (see `radiance`).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Ray {
    /// Camera path: through path lobes to the first estimate lobe.
    Camera,
    /// The shadow ray of the direct light at the estimate vertex.
    Shadow,
    /// A final-gather ray: through path lobes to an estimate lobe.
    Gather,
}

/// A photon-map lookup at the estimate vertex: which map, which photons skipped, into which
/// layer, with what weight.
#[derive(Clone, Copy)]
struct Lookup {
    map: usize,
    exclude: u32,
    layer: u32,
    weight: Vec3,
}

/// Adds part `part` of the terms of the camera path of `sample` through pixel (`px`, `py`) to
/// `terms` (indexed by `LAYER_*`) and the rays it casts to `rays`; part 0 is everything but the
/// final gather, part k >= 1 is gather ray k - 1 (see `DispatchRange`). The camera path, its
/// shadow ray and its gather path are one loop, as in the kernel (which has one call site of
/// each traversal and material evaluation for lavapipe's sake), so both add the same terms in
/// the same order.
pub fn radiance(s: &SceneView, px: u32, py: u32, sample: u32, part: u32, terms: &mut [Vec3; 4], rays: &mut u32) {
    let f = s.frame;
    let stream = py * f.width + px;
    // xy jitter the film position, zw sample the lens.
    let film = rand4(stream, sample, f.seed, RNG_PIXEL_X);
    let sx = 2.0 * (px as f32 + film[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + film[1]) / f.height as f32;
    let (mut o, mut d) = camera_ray(s, sx, sy, [film[2], film[3]]);
    let mut t_max = f32::INFINITY;
    let mut ray = Ray::Camera;
    // Path-lobe bounces of the current path so far.
    let mut depth = 0;
    let mut throughput = Vec3::ONE;
    // The estimate vertex (the camera path's, then the gather path's last vertex) and what the
    // shadow ray and the gather path carry from it.
    let mut estimate: Option<(Hit, Bsdf, Vec3)> = None;
    let mut weight = Vec3::ZERO;
    let mut via_specular = false;
    let mut unoccluded = Vec3::ZERO;
    let mut gather_weight = Vec3::ZERO;
    let mut gdim = 0;
    let mut lookups: [Option<Lookup>; 2] = [None; 2];

    // The smooth triangle the current ray leaves, which it must not meet again (see trace_ray).
    let mut skip = NO_LIGHT;
    for _ in 0..2 * f.max_depth + 1 {
        // A shadow ray of length NO_RAY was not needed: trace_ray returns at once, uncounted.
        if t_max != NO_RAY {
            *rays += 1;
        }
        let (prim, t) = trace_ray(s, o, d, t_max, ray == Ray::Shadow, skip);
        if ray == Ray::Shadow {
            if prim == NO_LIGHT {
                terms[(if via_specular { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] += weight * unoccluded;
            }
            if f.photon_mapping == 0 {
                break;
            }
            let layer = |own: u32| if via_specular { LAYER_SPECULAR } else { own };
            lookups[0] = Some(Lookup { map: MAP_CAUSTIC, exclude: 0, layer: layer(LAYER_CAUSTICS), weight });
            if f.gather_rays == 0 {
                let exclude = PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC;
                lookups[1] = Some(Lookup { map: MAP_GLOBAL, exclude, layer: layer(LAYER_INDIRECT), weight });
            }
            break;
        }
        if prim == NO_LIGHT {
            // A camera path that leaves the scene sees the environment (a path lobe's view of a
            // light); a gather path counts none of it, as it counts no emission.
            if f.environment != NO_LIGHT && ray == Ray::Camera && part == 0 {
                terms[(if depth > 0 { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] +=
                    throughput * environment_radiance(s, &s.lights[f.environment as usize], d);
            }
            break;
        }
        let h = shape_hit(s, prim, o, d, t);
        skip = ray_skip(s, prim);
        let m = &s.materials[h.material as usize];
        let wo = -d;
        let camera = ray == Ray::Camera;
        // Everything a mirror or glass shows is the specular term. Emission leaves the front face
        // only; it counts wherever a camera path meets it, since estimate lobes end the path and
        // light sampling covers them. A gather path counts none: direct light and caustics do.
        if camera && wo.dot(h.ng) > 0.0 && part == 0 {
            terms[(if depth > 0 { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] +=
                throughput * material_emission(s, m, &h);
        }
        let b = material_bsdf(s, m, &h);
        let dim = depth * RNG_DIMS_PER_BOUNCE;
        let u = rand4(stream, sample, f.seed, if camera { dim + RNG_FRESNEL } else { gdim + 1 + depth });
        // Follow the path lobes (mirrors, glass) with their probability; else end here.
        let q = bsdf_path_probability(&b, wo);
        if u[3] < q {
            let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_PATH);
            if smp.flags == 0 {
                break;
            }
            throughput *= smp.weight / q;
            o = offset_origin(&h, wo, smp.flags);
            d = smp.wi;
            depth += 1;
            if depth >= f.max_depth {
                break;
            }
            continue;
        }
        if bsdf_flags(&b) & BSDF_ESTIMATE == 0 {
            break;
        }
        if !camera {
            // The gather path's end: the global map there, weighted 1/gather_rays.
            let layer = if via_specular { LAYER_SPECULAR } else { LAYER_INDIRECT };
            let w = weight * (gather_weight * (throughput / (1.0 - q)) / f.gather_rays as f32);
            lookups[0] = Some(Lookup { map: MAP_GLOBAL, exclude: 0, layer, weight: w });
            estimate = Some((h, b, wo));
            break;
        }
        weight = throughput / (1.0 - q);
        via_specular = depth > 0;
        if part == 0 {
            let sr = direct_light_sample(s, &h, &b, wo, stream, sample, dim);
            unoccluded = sr.unoccluded;
            o = sr.origin;
            d = sr.direction;
            t_max = sr.t_max;
            ray = Ray::Shadow;
            estimate = Some((h, b, wo));
            continue;
        }
        if f.photon_mapping == 0 {
            break;
        }
        // Final-gather ray part - 1, sampled from the estimate lobes.
        gdim = RNG_GATHER_DOMAIN + (part - 1) * RNG_GATHER_DIMS_PER_RAY;
        let u0 = rand4(stream, sample, f.seed, gdim);
        let first = bsdf_sample(&b, wo, [u0[2], u0[0], u0[1]], LOBES_ESTIMATE);
        if first.flags == 0 {
            break;
        }
        gather_weight = first.weight;
        o = offset_origin(&h, wo, first.flags);
        d = first.wi;
        throughput = Vec3::ONE;
        depth = 0;
        ray = Ray::Gather;
    }
    if let Some((h, b, wo)) = &estimate {
        for l in lookups.iter().flatten() {
            terms[l.layer as usize] += l.weight * photon_radiance(s, l.map, h, b, *wo, l.exclude);
        }
    }
}

/// Adds the sample part of `range` to `accumulation` (`LAYER_COUNT` `[r, g, b, w]` per pixel of
/// the band; w of the direct layer counts rays), exactly as one dispatch of the kernel does.
pub fn render(s: &SceneView, range: &DispatchRange, accumulation: &mut [[f32; 4]]) {
    let row_len = (s.frame.width * LAYER_COUNT) as usize;
    accumulation.par_chunks_mut(row_len).take(range.row_count as usize).enumerate().for_each(|(row, pixels)| {
        let py = range.row_begin + row as u32;
        for (px, acc) in pixels.chunks_exact_mut(LAYER_COUNT as usize).enumerate() {
            let mut terms = [Vec3::ZERO; 4];
            let mut rays = 0;
            radiance(s, px as u32, py, range.sample_index, range.part, &mut terms, &mut rays);
            for (layer, term) in acc.iter_mut().zip(terms) {
                layer[0] += term.x;
                layer[1] += term.y;
                layer[2] += term.z;
            }
            acc[LAYER_DIRECT as usize][3] += rays as f32;
        }
    });
}
