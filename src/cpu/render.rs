//! Radiance of camera paths, accumulated per pixel; twin of `shaders/render.comp`.

use glam::Vec3;
use rayon::prelude::*;

use super::rng::{rand1, rand2};
use super::shading::{camera_direction, direct_light, fresnel_dielectric, primitive_normal, reflect};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::DispatchRange;

/// Radiance carried by the camera path of `sample` through pixel (`px`, `py`); adds the rays it
/// casts (closest-hit and shadow) to `rays`.
pub fn radiance(s: &SceneView, px: u32, py: u32, sample: u32, rays: &mut u32) -> Vec3 {
    let f = s.frame;
    let stream = py * f.width + px;
    let jitter = rand2(stream, sample, f.seed, RNG_PIXEL_X);
    let sx = 2.0 * (px as f32 + jitter[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + jitter[1]) / f.height as f32;
    let mut o = Vec3::from(f.camera_position);
    let mut d = camera_direction(s, sx, sy);
    let mut throughput = Vec3::ONE;
    let mut result = Vec3::ZERO;
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
        // Emission leaves the front face only; diffuse vertices end the path and light
        // sampling covers them, so emission met by a camera path is always counted.
        if front {
            result += throughput * Vec3::from(m.emission);
        }
        let nf = if front { n } else { -n };
        let dim = depth * RNG_DIMS_PER_BOUNCE;
        if m.kind == MATERIAL_DIFFUSE {
            let albedo = Vec3::from(m.reflectance);
            if albedo != Vec3::ZERO && f.light_count > 0 {
                result += throughput * direct_light(s, x, nf, albedo, stream, sample, dim, rays);
            }
            break;
        }
        if m.kind == MATERIAL_MIRROR {
            throughput *= Vec3::from(m.reflectance);
            d = reflect(d, nf);
            o = x + nf * f.ray_epsilon;
            continue;
        }
        // Dielectric: choose reflection or refraction with the Fresnel probability, weight 1.
        let (eta_i, eta_t) = if front { (1.0, m.ior) } else { (m.ior, 1.0) };
        let cos_i = -d.dot(nf);
        let (fr, cos_t) = fresnel_dielectric(cos_i, eta_i, eta_t);
        if rand1(stream, sample, f.seed, dim + RNG_FRESNEL) < fr {
            d = reflect(d, nf);
            o = x + nf * f.ray_epsilon;
        } else {
            let eta = eta_i / eta_t;
            d = (eta * d + (eta * cos_i - cos_t) * nf).normalize();
            o = x - nf * f.ray_epsilon;
        }
    }
    result
}

/// Adds the samples of `range` to `accumulation` (one `[r, g, b, rays]` per pixel of the band),
/// exactly as one dispatch of the `render` kernel does.
pub fn render(s: &SceneView, range: &DispatchRange, accumulation: &mut [[f32; 4]]) {
    let width = s.frame.width as usize;
    accumulation.par_chunks_mut(width).take(range.row_count as usize).enumerate().for_each(|(row, pixels)| {
        let py = range.row_begin + row as u32;
        for (px, acc) in pixels.iter_mut().enumerate() {
            let mut sum = Vec3::ZERO;
            let mut rays = 0;
            for sample in range.sample_begin..range.sample_begin + range.sample_count {
                sum += radiance(s, px as u32, py, sample, &mut rays);
            }
            acc[0] += sum.x;
            acc[1] += sum.y;
            acc[2] += sum.z;
            acc[3] += rays as f32;
        }
    });
}
