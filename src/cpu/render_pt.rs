//! The path-tracing integrator (`integrator = "pt"`): camera paths through every lobe, with
//! light sampling at each vertex that has non-delta lobes and the emission that paths meet,
//! both weighed by multiple importance sampling (the power heuristic); twin of
//! `shaders/render_pt.comp`. No photon maps: the estimator is unbiased, its error falls as
//! 1/samples, and it is the baseline the other integrators are checked against.
//!
//! Each contribution goes into the layer of its path's signature (light-path expressions, with
//! D any non-delta vertex, a medium's scattering points included, and S a delta one):
//! `E S ...` specular, `E L` and `E D L` direct, `E D S+ L` caustics, the rest (more than one D)
//! indirect; the four sum to the image.

use glam::Vec3;

use super::bsdf::{
    bsdf_eval, bsdf_flags, bsdf_path_probability, bsdf_pdf, bsdf_sample, material_bsdf, material_emission,
};
use super::instance::hit_primitive;
use super::light::{
    direct_light_pmf, emitter_cosine, environment_radiance, light_pdf, light_sample, pick_direct_light, receiver_normal,
};
use super::medium::{medium_after, medium_hit, medium_sample, medium_transmittance, phase_bsdf};
use super::rng::{bsdf_numbers, qmc2, rand1, rand2};
use super::shading::{camera_ray, film_offset, grid_sample, lens_sample, offset_origin, ray_skip, NO_RAY};
use super::shape::shape_hit;
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::DispatchRange;

/// The power heuristic (Veach's beta = 2) for a sample of density `a` against another
/// strategy's density `b` for the same path.
pub fn mis_power(a: f32, b: f32) -> f32 {
    if a <= 0.0 {
        return 0.0;
    }
    if b <= 0.0 || b.is_infinite() {
        return 1.0;
    }
    let r = b / a;
    1.0 / (1.0 + r * r)
}

/// The weight of a path made by technique `own` (`TECHNIQUE_*`) with density `p_own` where the
/// other technique would have made it with density `p_other` (0: it cannot), for the techniques
/// switched on in `techniques`.
pub fn mis_weight(techniques: u32, own: u32, p_own: f32, p_other: f32) -> f32 {
    if p_other <= 0.0 || techniques == own {
        return 1.0;
    }
    if techniques & own == 0 {
        return 0.0;
    }
    mis_power(p_own, p_other)
}

/// The layer of a path that ends at a light after its vertices so far: whether its first vertex
/// was delta (`first_specular`), how many non-delta vertices it has (`diffuse`, the last vertex
/// included), and whether a delta vertex follows the last non-delta one (`specular_after`).
pub fn path_layer(first_specular: bool, diffuse: u32, specular_after: bool) -> u32 {
    if first_specular {
        LAYER_SPECULAR
    } else if diffuse <= 1 && !specular_after {
        LAYER_DIRECT
    } else if diffuse == 1 {
        LAYER_CAUSTICS
    } else {
        LAYER_INDIRECT
    }
}

/// Loop steps of one camera path: a path ray and a shadow ray per vertex of `max_depth`, plus
/// crossings of null boundaries (each ray may cross `MEDIUM_CROSSINGS`) where there are media.
pub fn pt_steps(max_depth: u32, media: bool) -> u32 {
    if media {
        2 * (max_depth + 1) * (1 + MEDIUM_CROSSINGS)
    } else {
        2 * (max_depth + 1)
    }
}

/// Adds the terms of the camera path of `sample` through pixel (`px`, `py`) to `terms`
/// (indexed by `LAYER_*`) and the rays it casts to `rays`. The path ray and its shadow rays are
/// one loop with one `trace_ray`, as in the kernel.
pub fn radiance_pt(s: &SceneView, px: u32, py: u32, sample: u32, terms: &mut [Vec3; 4], rays: &mut u32) {
    let f = s.frame;
    let stream = py * f.width + px;
    let film = film_offset(f, qmc2(stream, sample, f.seed, RNG_PIXEL_X));
    let sx = 2.0 * (px as f32 + film[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + film[1]) / f.height as f32;
    let (mut o, mut d) = camera_ray(s, sx, sy, lens_sample(s, stream, sample));
    let mut t_max = f32::INFINITY;
    let mut shadow = false;
    let mut throughput = Vec3::ONE;
    let mut medium = f.camera_medium;
    // Scattering vertices so far (surfaces and points in media), and free flights so far.
    let mut vertex = 0u32;
    let mut segment = 0u32;
    let mut skip = NO_LIGHT;
    // The last scattering vertex and the solid-angle density its lobes drew the path ray with
    // (0: a delta lobe or the camera, whose emission seen is taken whole).
    let mut prev_p = o;
    // The normal light selection used at prev_p (zero in a medium), for the pick probability
    // that weighs emission met against light sampling there.
    let mut prev_n = Vec3::ZERO;
    let mut prev_pdf = 0.0f32;
    // The path's signature so far (see `path_layer`).
    let (mut first_specular, mut diffuse, mut specular_after) = (false, 0u32, false);
    // The shadow ray's contribution and layer, and the path ray to go on with after it.
    let (mut unoccluded, mut shadow_layer) = (Vec3::ZERO, LAYER_DIRECT);
    let (mut next_o, mut next_d, mut next_medium, mut next_skip, mut next_end) =
        (Vec3::ZERO, Vec3::ZERO, NO_MEDIUM, NO_LIGHT, false);
    let mut shadow_medium = NO_MEDIUM;

    for step in 0..pt_steps(f.max_depth, !s.media.is_empty()) {
        if t_max != NO_RAY {
            *rays += 1;
        }
        // Shadow rays pass null boundaries and sum the media between where there are media.
        let any_hit = shadow && s.media.is_empty();
        let (prim, mut t) = trace_ray(s, o, d, t_max, any_hit, skip);
        let mut scattered = false;
        let cur_medium = if shadow { shadow_medium } else { medium };
        if cur_medium != NO_MEDIUM && t_max != NO_RAY {
            if shadow {
                let u = rand2(stream, sample, f.seed, RNG_TRANSMITTANCE_DOMAIN + step);
                unoccluded *= medium_transmittance(s, cur_medium, o, d, t, u);
            } else {
                let e =
                    medium_sample(s, cur_medium, o, d, t, qmc2(stream, sample, f.seed, RNG_MEDIUM_DOMAIN + segment));
                segment += 1;
                terms[path_layer(first_specular, diffuse, specular_after) as usize] += throughput * e.emission;
                throughput *= e.weight;
                scattered = e.scattered;
                t = e.t;
                if throughput == Vec3::ZERO {
                    break;
                }
            }
        }
        let h = if scattered {
            Some(medium_hit(o + d * t, -d))
        } else if prim != NO_LIGHT && (!shadow || !s.media.is_empty()) {
            Some(shape_hit(s, prim, o, d, t))
        } else {
            None
        };
        if let Some(h) = h.filter(|h| !scattered && s.materials[h.material as usize].kind == MATERIAL_NULL) {
            // An invisible boundary: straight through into the medium beyond, not a vertex.
            if shadow {
                shadow_medium = medium_after(s, prim, h.ng, d, shadow_medium);
            } else {
                medium = medium_after(s, prim, h.ng, d, medium);
            }
            skip = ray_skip(s, prim);
            let next = offset_origin(&h, -d, BSDF_TRANSMISSION);
            if shadow {
                t_max = (t_max - (next - o).dot(d)).max(0.0);
            }
            o = next;
            continue;
        }
        if shadow {
            if prim == NO_LIGHT {
                terms[shadow_layer as usize] += unoccluded;
            }
            if next_end {
                break;
            }
            (o, d, medium, skip) = (next_o, next_d, next_medium, next_skip);
            t_max = f32::INFINITY;
            shadow = false;
            continue;
        }
        let Some(h) = h else {
            // The path leaves the scene: the environment and the discs of distant lights, each
            // weighed against its own light sampling.
            let layer = path_layer(first_specular, diffuse, specular_after) as usize;
            for (i, l) in s.lights.iter().enumerate().take_while(|(_, l)| l.kind == LIGHT_DISTANT && l.area > 0.0) {
                if d.dot(Vec3::from(l.direction)) <= -l.cos_outer {
                    let w = if prev_pdf > 0.0 {
                        let pmf = direct_light_pmf(s, i as u32, prev_p, prev_n);
                        mis_weight(f.techniques, TECHNIQUE_BSDF, prev_pdf, pmf / l.area)
                    } else {
                        1.0
                    };
                    terms[layer] += throughput * Vec3::from(l.intensity) * (w / l.area);
                }
            }
            if f.environment != NO_LIGHT {
                let l = &s.lights[f.environment as usize];
                let w = if prev_pdf > 0.0 {
                    mis_weight(
                        f.techniques,
                        TECHNIQUE_BSDF,
                        prev_pdf,
                        direct_light_pmf(s, f.environment, prev_p, prev_n) * light_pdf(s, l, d, 0.0, 0.0),
                    )
                } else {
                    1.0
                };
                terms[layer] += throughput * environment_radiance(s, l, d) * w;
            }
            break;
        };
        let wo = -d;
        let b = if scattered {
            phase_bsdf(s, medium, wo)
        } else {
            let m = &s.materials[h.material as usize];
            // Emission leaves the emitting faces only (emitter_cosine); a light that light sampling could have drawn
            // is weighed against it.
            let cos_l = emitter_cosine(m.flags, h.ng, wo);
            if cos_l > 0.0 {
                let emitted = material_emission(s, m, &h);
                if emitted != Vec3::ZERO {
                    // An instance's hit names its object's primitive, which is no light.
                    let hp = hit_primitive(s, prim);
                    let light = s.primitives[hp as usize].light;
                    let w = if prev_pdf > 0.0 && light != NO_LIGHT && hp == prim {
                        let l = &s.lights[light as usize];
                        let pmf = direct_light_pmf(s, light, prev_p, prev_n);
                        let p_light = pmf * light_pdf(s, l, d, (h.p - prev_p).length(), cos_l);
                        mis_weight(f.techniques, TECHNIQUE_BSDF, prev_pdf, p_light)
                    } else {
                        1.0
                    };
                    terms[path_layer(first_specular, diffuse, specular_after) as usize] += throughput * emitted * w;
                }
            }
            material_bsdf(s, m, &h)
        };
        let flags = bsdf_flags(&b);
        if flags == 0 {
            break;
        }
        let receiver = receiver_normal(&b);
        skip = if scattered { NO_LIGHT } else { ray_skip(s, prim) };
        let dim = vertex * RNG_DIMS_PER_BOUNCE;
        let q = bsdf_path_probability(&b, wo);

        // The next path ray: the delta lobes with probability q, else the others.
        let u = bsdf_numbers(stream, sample, (stream, sample), f.seed, dim + RNG_FRESNEL);
        let delta = u[3] < q;
        let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], if delta { LOBES_PATH } else { LOBES_ESTIMATE });
        let choice = if delta { q } else { 1.0 - q };
        next_end = smp.flags == 0 || vertex + 1 >= f.max_depth;
        if !next_end {
            next_d = smp.wi;
            next_o = offset_origin(&h, wo, smp.flags);
            next_medium = if smp.flags & BSDF_TRANSMISSION != 0 && !scattered {
                medium_after(s, prim, h.ng, smp.wi, medium)
            } else {
                medium
            };
            next_skip = skip;
        }

        // Light sampling, where the lobes are not all delta.
        let mut light_ray = false;
        if flags & BSDF_ESTIMATE != 0 && f.light_count > 0 {
            let u_pick = rand1(stream, sample, f.seed, dim + RNG_LIGHT_PICK);
            let (light, pmf) = pick_direct_light(s, u_pick, h.p, receiver);
            if pmf > 0.0 {
                let l = &s.lights[light as usize];
                let ul = qmc2(stream, sample, f.seed, dim + RNG_LIGHT_U);
                let ls = light_sample(s, l, h.p, grid_sample(l.grid, ul, stream, sample));
                let cos = if scattered { 1.0 } else { b.ns.dot(ls.wi).abs() };
                let fr = bsdf_eval(&b, wo, ls.wi) * ls.weight * cos;
                if fr != Vec3::ZERO {
                    let p_bsdf = if ls.pdf > 0.0 { (1.0 - q) * bsdf_pdf(&b, wo, ls.wi) } else { 0.0 };
                    let w = mis_weight(f.techniques, TECHNIQUE_LIGHT, pmf * ls.pdf, p_bsdf);
                    let origin = offset_origin(&h, ls.wi, BSDF_REFLECTION);
                    let to_target = ls.p - origin;
                    let length = to_target.length();
                    unoccluded = throughput * fr * (w / pmf);
                    shadow_layer = path_layer(first_specular, diffuse + 1, false);
                    shadow_medium = medium;
                    o = origin;
                    d = to_target / length;
                    t_max = (length - ls.eps).max(0.0);
                    light_ray = true;
                }
            }
        }

        // The path's signature and throughput after this vertex.
        if smp.flags & BSDF_SPECULAR != 0 {
            first_specular |= vertex == 0;
            specular_after = diffuse > 0;
            prev_pdf = 0.0;
        } else {
            diffuse += 1;
            specular_after = false;
            prev_pdf = choice * bsdf_pdf(&b, wo, smp.wi);
        }
        prev_p = h.p;
        prev_n = receiver;
        throughput *= smp.weight / choice;
        vertex += 1;
        // Russian roulette, on the throughput's largest channel.
        if !next_end && vertex >= PT_ROULETTE_DEPTH {
            let survive = throughput.max_element().min(PT_ROULETTE_MAX);
            if rand1(stream, sample, f.seed, dim + RNG_ROULETTE) >= survive {
                next_end = true;
            } else {
                throughput /= survive;
            }
        }
        if light_ray {
            shadow = true;
            continue;
        }
        if next_end {
            break;
        }
        (o, d, medium) = (next_o, next_d, next_medium);
    }
}

/// Adds the sample of `range` to `accumulation` (`LAYER_COUNT` `[r, g, b, w]` per pixel of the
/// band; w of the direct layer counts rays), exactly as one dispatch of the kernel does.
pub fn render_pt(s: &SceneView, range: &DispatchRange, accumulation: &mut [[f32; 4]]) {
    super::pixel_list::for_each_pixel(s.frame.width, range, s.pixel_list, accumulation, |px, py, acc| {
        let mut terms = [Vec3::ZERO; 4];
        let mut rays = 0;
        radiance_pt(s, px, py, range.sample_index, &mut terms, &mut rays);
        for (layer, term) in acc.iter_mut().zip(terms) {
            layer[0] += term.x;
            layer[1] += term.y;
            layer[2] += term.z;
        }
        acc[LAYER_DIRECT as usize][3] += rays as f32;
    });
}
