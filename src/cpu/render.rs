//! The four terms of each pixel, accumulated over rows and samples; twin of
//! `shaders/render.comp`.

use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::{bsdf_flags, bsdf_path_probability, bsdf_sample, material_bsdf, material_emission};
use super::gather::{caustic_light, gather_ray, indirect_preview};
use super::light::environment_radiance;
use super::rng::rand4;
use super::shading::{camera_ray, direct_light, offset_origin};
use super::shape::shape_hit;
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::DispatchRange;

/// Adds part `part` of the terms of the camera path of `sample` through pixel (`px`, `py`) to
/// `terms` (indexed by `LAYER_*`) and the rays it casts to `rays`; part 0 is everything but the
/// final gather, part k >= 1 is gather ray k - 1 (see `DispatchRange`).
pub fn radiance(s: &SceneView, px: u32, py: u32, sample: u32, part: u32, terms: &mut [Vec3; 4], rays: &mut u32) {
    let f = s.frame;
    let stream = py * f.width + px;
    // xy jitter the film position, zw sample the lens.
    let film = rand4(stream, sample, f.seed, RNG_PIXEL_X);
    let sx = 2.0 * (px as f32 + film[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + film[1]) / f.height as f32;
    let (mut o, mut d) = camera_ray(s, sx, sy, [film[2], film[3]]);
    let mut throughput = Vec3::ONE;
    for depth in 0..f.max_depth {
        *rays += 1;
        let (prim, t) = trace_ray(s, o, d, f32::INFINITY, false);
        // Everything a mirror or glass shows is the specular term.
        let layer = |own: u32| (if depth > 0 { LAYER_SPECULAR } else { own }) as usize;
        if prim == NO_LIGHT {
            // A ray that leaves the scene sees the environment (a path lobe's view of a light).
            if f.environment != NO_LIGHT && part == 0 {
                terms[layer(LAYER_DIRECT)] +=
                    throughput * environment_radiance(s, &s.lights[f.environment as usize], d);
            }
            break;
        }
        let h = shape_hit(s, prim, o, d, t);
        let m = &s.materials[h.material as usize];
        let wo = -d;
        // Emission leaves the front face only; it counts wherever a camera path meets it, since
        // estimate lobes end the path and light sampling covers them.
        if wo.dot(h.ng) > 0.0 && part == 0 {
            terms[layer(LAYER_DIRECT)] += throughput * material_emission(s, m, &h);
        }
        let b = material_bsdf(s, m, &h);
        let dim = depth * RNG_DIMS_PER_BOUNCE;
        let u = rand4(stream, sample, f.seed, dim + RNG_FRESNEL);
        // Follow the path lobes (mirrors, glass) with their probability; else end here.
        let q = bsdf_path_probability(&b, wo);
        if u[3] < q {
            let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_PATH);
            if smp.flags == 0 {
                break;
            }
            throughput *= smp.weight / q;
            o = offset_origin(s, &h, wo, smp.flags);
            d = smp.wi;
            continue;
        }
        if bsdf_flags(&b) & BSDF_ESTIMATE == 0 {
            break;
        }
        let weight = throughput / (1.0 - q);
        if part == 0 {
            terms[layer(LAYER_DIRECT)] += weight * direct_light(s, &h, &b, wo, stream, sample, dim, rays);
        }
        if f.photon_mapping == 0 {
            break;
        }
        if part == 0 {
            terms[layer(LAYER_CAUSTICS)] += weight * caustic_light(s, &h, &b, wo);
            if f.gather_rays == 0 {
                terms[layer(LAYER_INDIRECT)] += weight * indirect_preview(s, &h, &b, wo);
            }
        } else {
            terms[layer(LAYER_INDIRECT)] += weight * gather_ray(s, &h, &b, wo, stream, sample, part - 1, rays);
        }
        break;
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
