//! The four terms of each pixel, accumulated over rows and samples; twin of
//! `shaders/render.comp`.

use glam::Vec3;
use rayon::prelude::*;

use super::gather::{caustic_light, gather_ray, indirect_preview};
use super::rng::{rand1, rand2};
use super::shading::{camera_direction, dielectric_scatter, direct_light, primitive_normal, reflect};
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
    let jitter = rand2(stream, sample, f.seed, RNG_PIXEL_X);
    let sx = 2.0 * (px as f32 + jitter[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + jitter[1]) / f.height as f32;
    let mut o = Vec3::from(f.camera_position);
    let mut d = camera_direction(s, sx, sy);
    let mut throughput = Vec3::ONE;
    for depth in 0..f.max_depth {
        *rays += 1;
        let (prim, t) = trace_ray(s.nodes, s.primitives, o, d, f32::INFINITY, false);
        if prim == NO_LIGHT {
            break;
        }
        let x = o + t * d;
        let n = primitive_normal(s, prim, x);
        let m = &s.materials[s.primitives[prim as usize].material as usize];
        let front = n.dot(d) < 0.0;
        // Everything a mirror or glass shows is the specular term.
        let layer = |own: u32| (if depth > 0 { LAYER_SPECULAR } else { own }) as usize;
        // Emission leaves the front face only; it counts wherever a camera path meets it, since
        // diffuse vertices end the path and light sampling covers them.
        if front && part == 0 {
            terms[layer(LAYER_DIRECT)] += throughput * Vec3::from(m.emission);
        }
        let nf = if front { n } else { -n };
        let dim = depth * RNG_DIMS_PER_BOUNCE;
        if m.kind == MATERIAL_DIFFUSE {
            let albedo = Vec3::from(m.reflectance);
            if albedo == Vec3::ZERO {
                break;
            }
            if part == 0 {
                let direct = direct_light(s, x, nf, albedo, stream, sample, dim, rays);
                terms[layer(LAYER_DIRECT)] += throughput * direct;
            }
            if f.photon_mapping == 0 {
                break;
            }
            if part == 0 {
                terms[layer(LAYER_CAUSTICS)] += throughput * caustic_light(s, x, nf, albedo);
                if f.gather_rays == 0 {
                    terms[layer(LAYER_INDIRECT)] += throughput * indirect_preview(s, x, nf, albedo);
                }
            } else {
                let indirect = gather_ray(s, x, nf, albedo, stream, sample, part - 1, rays);
                terms[layer(LAYER_INDIRECT)] += throughput * indirect;
            }
            break;
        }
        if m.kind == MATERIAL_MIRROR {
            throughput *= Vec3::from(m.reflectance);
            d = reflect(d, nf);
            o = x + nf * f.ray_epsilon;
            continue;
        }
        // Dielectric: reflection or refraction with the Fresnel probability, weight 1.
        (o, d) = dielectric_scatter(s, x, nf, front, m.ior, rand1(stream, sample, f.seed, dim + RNG_FRESNEL), d);
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
