//! The feature layers a denoiser is guided by, per camera sample; twin of
//! `shaders/render_features.comp`. Open Image Denoise asks for the albedo and the shading normal
//! of the first surface that is not a perfect mirror or glass, seen through those (its
//! documentation, "RT" filter: "for perfect specular surfaces ... the albedo and normal of the
//! first diffuse or glossy surface seen through them"); pipelines also ask for the position and
//! depth of the first surface seen. The camera ray of each sample is the integrators' own (same
//! film and lens numbers), so the layers line up with the image sample for sample; specular
//! lobes are followed with the path's own numbers (`RNG_FRESNEL` of each vertex).
//!
//! Only where features are asked for (`--layers`, `--denoise`): the integrators' kernels are
//! untouched, so an image without features is the same bits as before.
//!
//! Conventions (each a choice OIDN's documentation allows):
//! - albedo: a sample of the BSDF over all its lobes, f |cos| / pdf, clamped to [0, 1] per
//!   channel: the directional albedo on average (exactly the colour for a Lambertian surface),
//!   times the tint of the mirrors and glass on the way; a surface that only emits gives its
//!   emission clamped to [0, 1]; a ray that leaves the scene the environment's, likewise, or 0;
//! - normal: the shading normal turned toward the viewer, world space; 0 where the ray leaves;
//! - position (world space) and depth (distance from the camera) of the first surface: 0 where
//!   the ray leaves the scene. Participating media are looked through (surfaces only).

use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::{bsdf_flags, bsdf_sample, facing, material_bsdf, material_emission};
use super::light::environment_radiance;
use super::rng::{bsdf_numbers, qmc2};
use super::shading::{camera_ray, film_offset, lens_sample, offset_origin, ray_skip};
use super::shape::shape_hit;
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::DispatchRange;

/// Loop steps of one sample: a ray per vertex (at most `max_depth`) plus the crossings of null
/// boundaries (at most `MEDIUM_CROSSINGS`), so an invocation's work stays bounded.
pub fn feature_steps(max_depth: u32) -> u32 {
    max_depth + MEDIUM_CROSSINGS
}

/// The features of one camera sample of pixel (px, py): `FEATURE_COUNT` vec4 in `FEATURE_*`
/// order (albedo rgb, normal xyz, position xyz with depth in w).
pub fn sample_features(s: &SceneView, px: u32, py: u32, sample: u32) -> [[f32; 4]; FEATURE_COUNT as usize] {
    let f = s.frame;
    let stream = py * f.width + px;
    let film = film_offset(f, qmc2(stream, sample, f.seed, RNG_PIXEL_X));
    let sx = 2.0 * (px as f32 + film[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + film[1]) / f.height as f32;
    let (mut o, mut d) = camera_ray(s, sx, sy, lens_sample(s, stream, sample));
    let eye = o;
    let mut tint = Vec3::ONE;
    let mut skip = NO_LIGHT;
    let mut vertex = 0u32;
    let (mut albedo, mut normal, mut position, mut depth) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0f32);
    let mut seen = false;
    for _ in 0..feature_steps(f.max_depth) {
        let (prim, t) = trace_ray(s, o, d, f32::INFINITY, false, skip);
        if prim == NO_LIGHT {
            if f.environment != NO_LIGHT {
                let l = &s.lights[f.environment as usize];
                albedo = tint * environment_radiance(s, l, d).min(Vec3::ONE);
            }
            break;
        }
        let h = shape_hit(s, prim, o, d, t);
        let m = &s.materials[h.material as usize];
        if m.kind == MATERIAL_NULL {
            // An invisible boundary of a medium: straight through.
            skip = ray_skip(s, prim);
            o = offset_origin(&h, -d, BSDF_TRANSMISSION);
            continue;
        }
        if !seen {
            (position, depth, seen) = (h.p, (h.p - eye).length(), true);
        }
        let wo = -d;
        let b = material_bsdf(s, m, &h);
        normal = facing(&b, wo);
        let flags = bsdf_flags(&b);
        if flags == 0 {
            albedo = tint * material_emission(s, m, &h).min(Vec3::ONE);
            break;
        }
        let u = bsdf_numbers(stream, sample, (stream, sample), f.seed, vertex * RNG_DIMS_PER_BOUNCE + RNG_FRESNEL);
        let last = vertex + 1 >= f.max_depth;
        if flags & BSDF_ESTIMATE != 0 || last {
            // The first non-specular vertex (or the last the integrators reach).
            let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_ALL);
            albedo = tint * smp.weight.clamp(Vec3::ZERO, Vec3::ONE);
            break;
        }
        let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_PATH);
        if smp.flags == 0 {
            break;
        }
        tint *= smp.weight.clamp(Vec3::ZERO, Vec3::ONE);
        skip = ray_skip(s, prim);
        o = offset_origin(&h, wo, smp.flags);
        d = smp.wi;
        vertex += 1;
    }
    [
        [albedo.x, albedo.y, albedo.z, 0.0],
        [normal.x, normal.y, normal.z, 0.0],
        [position.x, position.y, position.z, depth],
    ]
}

/// Adds the sample of `range` to `features` (`FEATURE_COUNT` vec4 per pixel of the band),
/// exactly as one dispatch of the kernel does.
pub fn render_features(s: &SceneView, range: &DispatchRange, features: &mut [[f32; 4]]) {
    let row_len = (s.frame.width * FEATURE_COUNT) as usize;
    features.par_chunks_mut(row_len).take(range.row_count as usize).enumerate().for_each(|(row, pixels)| {
        let py = range.row_begin + row as u32;
        for (px, acc) in pixels.chunks_exact_mut(FEATURE_COUNT as usize).enumerate() {
            let sample = sample_features(s, px as u32, py, range.sample_index);
            for (a, v) in acc.iter_mut().zip(sample) {
                for c in 0..4 {
                    a[c] += v[c];
                }
            }
        }
    });
}
