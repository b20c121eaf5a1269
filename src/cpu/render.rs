//! The four terms of each pixel, accumulated over rows and samples; twin of
//! `shaders/render.comp` (with participating media: its `media` variant).

use glam::Vec3;

use super::bsdf::Bsdf;
use super::bsdf::{bsdf_flags, bsdf_path_probability, bsdf_sample, facing, material_bsdf, material_emission};
use super::gather::{
    edge_mass, edge_probe_ray, open_edge_reach, photon_radiance, Gathered, MAP_CAUSTIC, MAP_GLOBAL, MAP_VOLUME,
};
use super::light::{distant_discs_radiance, emitter_cosine, environment_radiance, pick_light, spot_falloff};
use super::medium::{
    equiangular_sample, medium_after, medium_hit, medium_sample, medium_sigma_t_at, medium_transmittance, phase_bsdf,
    spot_span,
};
use super::phase::phase_hg;
use super::rng::{bsdf_numbers, qmc2, rand1, rand2, rand4};
use super::shading::{camera_ray, direct_light_sample, film_offset, lens_sample, offset_origin, ray_skip, NO_RAY};
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
    /// The shadow ray of an equiangular sample of a camera segment (media).
    Shaft,
    /// No ray (`NO_RAY`): the photon lookups at the estimate vertex.
    Lookup,
    /// An edge probe of the lookups' discs (`edge_probe_ray`).
    Probe,
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

/// Flags of the photons that every lookup of each map (`MAP_*` order) excludes in a render with
/// `gather_rays` final-gather rays, which the CPU's lookup layout may leave out (see the
/// `Lookup`s of `radiance`): reading the global map directly skips its direct and caustic
/// photons (the light sample and the caustic map count them) and a scattering point skips
/// the volume map's single scattering; a gather path's end reads both maps whole.
pub fn excluded_by_every_lookup(gather_rays: u32) -> [u32; 3] {
    if gather_rays == 0 {
        [PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC, 0, PHOTON_FLAG_DIRECT]
    } else {
        [0, 0, 0]
    }
}

/// Adds part `part` of the terms of the camera path of `sample` through pixel (`px`, `py`) to
/// `terms` (indexed by `LAYER_*`) and the rays it casts to `rays`; part 0 is everything but the
/// final gather, part k >= 1 is gather ray k - 1 (see `DispatchRange`). The camera path, its
/// shadow ray and its gather path are one loop, as in the kernel (which has one call site of
/// each traversal and material evaluation for lavapipe's sake), so both add the same terms in
/// the same order. `penumbra_since`: the sample at which the pixel's earlier shadow rays toward
/// adaptive lights were first found some blocked, some not (`NO_SAMPLE`: not yet); this sample's
/// rays toward them are counted into `visibility` (blocked, lit).
#[allow(clippy::too_many_arguments)]
pub fn radiance(
    s: &SceneView,
    px: u32,
    py: u32,
    sample: u32,
    part: u32,
    penumbra_since: u32,
    terms: &mut [Vec3; 4],
    rays: &mut u32,
    visibility: &mut [u32; 2],
) {
    let f = s.frame;
    let stream = py * f.width + px;
    // The film position, then the lens.
    let film = film_offset(f, qmc2(stream, sample, f.seed, RNG_PIXEL_X));
    let sx = 2.0 * (px as f32 + film[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + film[1]) / f.height as f32;
    let (mut o, mut d) = camera_ray(s, sx, sy, lens_sample(s, stream, sample));
    let mut t_max = f32::INFINITY;
    let mut ray = Ray::Camera;
    // Path-lobe bounces of the current path so far.
    let mut depth = 0;
    let mut throughput = Vec3::ONE;
    // The medium the current ray runs through, and the path's free flights so far (their
    // random dimensions).
    let mut medium = f.camera_medium;
    let mut segment = 0;
    // The camera segment an equiangular sample interrupted, resumed after its shadow ray.
    let mut shaft_done = false;
    let (mut shaft_o, mut shaft_d, mut shaft_medium, mut shaft_layer) =
        (Vec3::ZERO, Vec3::ZERO, NO_MEDIUM, LAYER_DIRECT);
    // The estimate vertex (the camera path's, then the gather path's last vertex) and what the
    // shadow ray and the gather path carry from it.
    let mut estimate: Option<(Hit, Bsdf, Vec3)> = None;
    let mut weight = Vec3::ZERO;
    let mut via_specular = false;
    // The estimate vertex is a scattering point in a medium, and 1/sigma_t there.
    let mut volume_e = false;
    let mut inv_sigma_t_e = Vec3::ZERO;
    let mut unoccluded = Vec3::ZERO;
    // The estimate vertex's shadow rays: this one, how many, toward an adaptive light, and the
    // medium they start in.
    let (mut shadow_ray, mut shadow_rays, mut shadow_adaptive, mut medium_e) = (0, 1, false, NO_MEDIUM);
    let mut gather_weight = Vec3::ZERO;
    let mut gdim = 0;
    let mut lookups: [Option<Lookup>; 2] = [None; 2];
    let mut found = [Gathered::default(); 2];
    // The lookups are the camera path's own, on a surface: their discs are probed for edges
    // where they find photons of another surface in reach. The probes' frame (facing normal,
    // largest radius, turn), the next probe, and how far the surface reaches in each direction.
    let mut probe_edges = false;
    let (mut probe_n, mut probe_reach, mut probe_turn) = (Vec3::ZERO, 0.0, 0.0);
    let mut probe = 0u32;
    let mut surface_reach = [0.0; EDGE_PROBES as usize];

    // The smooth triangle the current ray leaves, which it must not meet again (see trace_ray).
    let mut skip = NO_LIGHT;
    // Steps of the loop: a path of max_depth bounces and its crossings of medium boundaries;
    // with media each camera segment may take three (its equiangular shadow ray, then its retrace).
    // And the extra shadow rays of an adaptive light (each with its crossings).
    // Then the lookups and their edge probes.
    let steps = if s.media.is_empty() {
        2 * f.max_depth + 1 + ADAPTIVE_MAX_RAYS - 1
    } else {
        3 * (2 * f.max_depth + 1 + MEDIUM_CROSSINGS) + (ADAPTIVE_MAX_RAYS - 1) * (1 + MEDIUM_CROSSINGS)
    } + 1
        + 2 * EDGE_PROBES;
    for step in 0..steps {
        // A shadow ray of length NO_RAY was not needed: trace_ray returns at once, uncounted.
        if t_max != NO_RAY {
            *rays += 1;
        }
        // Shadow rays take the closest hit where there are media: they pass null boundaries and
        // sum the media between (the kernel's `media` variant).
        let any_hit = (ray == Ray::Shadow || ray == Ray::Shaft) && s.media.is_empty();
        // A shaft ray leaves a point in a medium, which has no triangle to skip; a probe leaves
        // the surface's plane.
        let ignore = if ray == Ray::Shaft || ray == Ray::Probe { NO_LIGHT } else { skip };
        let (prim, mut t) = trace_ray(s, o, d, t_max, any_hit, ignore);
        let mut scattered = false;
        // The medium up to the hit (or to the light, or to infinity): shadow rays take its
        // transmittance, camera and gather rays sample a free flight through it.
        // A probe looks for the surface's edges, not through the medium.
        if medium != NO_MEDIUM && t_max != NO_RAY && ray != Ray::Probe {
            if ray == Ray::Shadow || ray == Ray::Shaft {
                unoccluded *= medium_transmittance(
                    s,
                    medium,
                    o,
                    d,
                    t,
                    rand2(stream, sample, f.seed, RNG_TRANSMITTANCE_DOMAIN + step),
                );
            } else {
                // Single scattering from point and spot lights along the whole camera segment,
                // by equiangular sampling (the light shafts; the free flight's scattering point
                // leaves these lights out): the sample's shadow ray runs first, then the segment
                // is traced again and goes on. Not in heterogeneous media, where the free
                // flight's scattering point samples these lights (see the kernel).
                // (A scene of no lights, or whose lights all give no power, has nothing to pick.)
                if ray == Ray::Camera
                    && part == 0
                    && !shaft_done
                    && f.light_count > 0
                    && s.media[medium as usize].density == NO_TEXTURE
                {
                    let ue = rand4(stream, sample, f.seed, RNG_EQUIANGULAR_DOMAIN + segment);
                    let l = &s.lights[pick_light(s, ue[0], false) as usize];
                    // A spot's samples stay in its cone, where its light is.
                    let (t0, t1) = if l.kind == LIGHT_SPOT {
                        spot_span(o, d, t, Vec3::from(l.position), Vec3::from(l.direction), l.cos_outer)
                    } else {
                        (0.0, t)
                    };
                    if (l.kind == LIGHT_POINT || l.kind == LIGHT_SPOT) && l.pick_probability > 0.0 && t0 < t1 {
                        let (te, pdf) = equiangular_sample(o + d * t0, d, t1 - t0, Vec3::from(l.position), ue[1]);
                        let te = t0 + te;
                        let x = o + d * te;
                        let to_light = Vec3::from(l.position) - x;
                        let r2 = to_light.dot(to_light);
                        let r = r2.sqrt();
                        let wi = to_light / r;
                        let md = &s.media[medium as usize];
                        let c = throughput
                            * medium_transmittance(s, medium, o, d, te, [ue[2], ue[3]])
                            * Vec3::from(md.sigma_s)
                            * (phase_hg((-d).dot(wi), md.g) * spot_falloff(l, -wi) / (r2 * pdf * l.pick_probability))
                            * Vec3::from(l.intensity);
                        if pdf > 0.0 && r > 0.0 && c != Vec3::ZERO {
                            (shaft_o, shaft_d, shaft_medium) = (o, d, medium);
                            shaft_layer = if depth > 0 { LAYER_SPECULAR } else { LAYER_DIRECT };
                            unoccluded = c;
                            o = x;
                            d = wi;
                            t_max = (r - f.ray_epsilon).max(0.0);
                            ray = Ray::Shaft;
                            continue;
                        }
                    }
                }
                shaft_done = false;
                let key =
                    RNG_MEDIUM_DOMAIN + if ray == Ray::Gather { part } else { 0 } * RNG_MEDIUM_DIMS_PER_PART + segment;
                segment += 1;
                let e = medium_sample(s, medium, o, d, t, qmc2(stream, sample, f.seed, key));
                if ray == Ray::Camera && part == 0 {
                    terms[(if depth > 0 { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] += throughput * e.emission;
                }
                throughput *= e.weight;
                scattered = e.scattered;
                t = e.t;
                if throughput == Vec3::ZERO {
                    break;
                }
            }
        }
        if ray == Ray::Lookup {
            let (h, b, wo) = estimate.as_ref().expect("lookups read at an estimate vertex");
            for (k, l) in lookups.iter().enumerate() {
                if let Some(l) = l {
                    found[k] = photon_radiance(s, l.map, h, b, *wo, l.exclude);
                }
            }
            if !probe_edges {
                break;
            }
            probe_n = facing(b, *wo);
            probe_reach = lookups.iter().flatten().map(|l| s.maps.grids[l.map].radius).fold(0.0, f32::max);
            probe_turn = rand1(stream, sample, f.seed, RNG_EDGE_PROBE);
            // An instance's triangle (a hit name past the primitives) carries no open-edge flags.
            surface_reach = if h.prim < f.primitive_count {
                open_edge_reach(&s.primitives[h.prim as usize], h.p, probe_n, probe_reach, probe_turn)
            } else {
                [probe_reach; EDGE_PROBES as usize]
            };
            // No probes in scenes with instances: probes through many overlapping instances can
            // take the kernel past lavapipe's 65535 loop iterations an invocation, which ends them
            // early there and not here (tests/hardening3.rs's frames scene; docs/integrators.md).
            if f.instance_count > 0 || !found.iter().any(|g| g.off_disc) {
                break;
            }
            (o, d) = edge_probe_ray(h.p, probe_n, probe_reach, probe_turn, 0);
            t_max = probe_reach;
            ray = Ray::Probe;
            continue;
        }
        let h = if scattered {
            Some(medium_hit(o + d * t, -d))
        } else if prim != NO_LIGHT && (ray != Ray::Shadow || !s.media.is_empty()) {
            Some(shape_hit(s, prim, o, d, t))
        } else {
            None
        };
        if ray == Ray::Probe {
            // A wall across the probe's way (an invisible boundary is none) ends the surface there.
            let wall = h.filter(|h| s.materials[h.material as usize].kind != MATERIAL_NULL);
            if wall.is_some_and(|h| h.ng.dot(probe_n).abs() < EDGE_PROBE_COS) {
                let to_edge = if probe.is_multiple_of(2) { t } else { probe_reach - t };
                let i = (probe / 2) as usize;
                surface_reach[i] = surface_reach[i].min(to_edge);
            }
            probe += 1;
            if probe == 2 * EDGE_PROBES {
                break;
            }
            let (x, _, _) = estimate.as_ref().expect("probes leave an estimate vertex");
            (o, d) = edge_probe_ray(x.p, probe_n, probe_reach, probe_turn, probe);
            t_max = probe_reach;
            continue;
        }
        if let Some(h) = h.filter(|h| !scattered && s.materials[h.material as usize].kind == MATERIAL_NULL) {
            // An invisible boundary: straight through into the medium beyond, not a bounce.
            medium = medium_after(s, prim, h.ng, d, medium);
            if ray != Ray::Shaft {
                skip = ray_skip(s, prim);
            }
            let next = offset_origin(&h, -d, BSDF_TRANSMISSION);
            if ray == Ray::Shadow || ray == Ray::Shaft {
                t_max = (t_max - (next - o).dot(d)).max(0.0);
            }
            o = next;
            continue;
        }
        if ray == Ray::Shaft {
            // The equiangular sample's shadow ray: its light if nothing blocked it; then back to
            // the camera segment it interrupted.
            if prim == NO_LIGHT {
                terms[shaft_layer as usize] += unoccluded;
            }
            (o, d, medium) = (shaft_o, shaft_d, shaft_medium);
            t_max = f32::INFINITY;
            ray = Ray::Camera;
            shaft_done = true;
            continue;
        }
        if ray == Ray::Shadow {
            if prim == NO_LIGHT {
                terms[(if via_specular { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] += weight * unoccluded;
            }
            if shadow_adaptive && t_max != NO_RAY {
                visibility[(prim == NO_LIGHT) as usize] += 1;
            }
            shadow_ray += 1;
            if shadow_ray < shadow_rays {
                let (he, be, wo_e) = estimate.as_ref().expect("a shadow ray leaves an estimate vertex");
                let dim = depth * RNG_DIMS_PER_BOUNCE;
                let sr = direct_light_sample(s, he, be, *wo_e, stream, sample, dim, penumbra_since, shadow_ray);
                (unoccluded, o, d, t_max, medium) = (sr.unoccluded, sr.origin, sr.direction, sr.t_max, medium_e);
                continue;
            }
            if f.photon_mapping == 0 {
                break;
            }
            let layer = |own: u32| if via_specular { LAYER_SPECULAR } else { own };
            if volume_e {
                // A scattering point: the volume map without the single scattering, which the
                // light sample gave; sigma_t-weighted collisions become radiance over sigma_t.
                let w = weight * inv_sigma_t_e;
                lookups[0] = Some(Lookup {
                    map: MAP_VOLUME,
                    exclude: PHOTON_FLAG_DIRECT,
                    layer: layer(LAYER_INDIRECT),
                    weight: w,
                });
                (ray, t_max) = (Ray::Lookup, NO_RAY);
                continue;
            }
            lookups[0] = Some(Lookup { map: MAP_CAUSTIC, exclude: 0, layer: layer(LAYER_CAUSTICS), weight });
            if f.gather_rays == 0 {
                let exclude = PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC;
                lookups[1] = Some(Lookup { map: MAP_GLOBAL, exclude, layer: layer(LAYER_INDIRECT), weight });
            }
            probe_edges = true;
            (ray, t_max) = (Ray::Lookup, NO_RAY);
            continue;
        }
        let Some(h) = h else {
            // A camera path that leaves the scene sees the environment and the discs of distant
            // lights (a path lobe's view of a light); a gather path counts none of it, as it
            // counts no emission.
            if ray == Ray::Camera && part == 0 {
                let mut seen = distant_discs_radiance(s, d);
                if f.environment != NO_LIGHT {
                    seen += environment_radiance(s, &s.lights[f.environment as usize], d);
                }
                terms[(if depth > 0 { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] += throughput * seen;
            }
            break;
        };
        skip = if scattered { NO_LIGHT } else { ray_skip(s, prim) };
        let wo = -d;
        let camera = ray == Ray::Camera;
        let mut inv_sigma_t = Vec3::ONE;
        let b = if scattered {
            let st = medium_sigma_t_at(s, medium, h.p);
            inv_sigma_t = Vec3::select(st.cmpgt(Vec3::ZERO), st.recip(), Vec3::ZERO);
            phase_bsdf(s, medium, wo)
        } else {
            let m = &s.materials[h.material as usize];
            // Everything a mirror or glass shows is the specular term. Emission leaves the emitting
            // faces only; it counts wherever a camera path meets it, since estimate lobes end the
            // path and light sampling covers them. A gather path counts none: direct light and
            // caustics do.
            if camera && emitter_cosine(m.flags, h.ng, wo) > 0.0 && part == 0 {
                terms[(if depth > 0 { LAYER_SPECULAR } else { LAYER_DIRECT }) as usize] +=
                    throughput * material_emission(s, m, &h);
            }
            material_bsdf(s, m, &h)
        };
        let dim = depth * RNG_DIMS_PER_BOUNCE;
        let key = if camera { dim + RNG_FRESNEL } else { gdim + 1 + depth };
        let u = bsdf_numbers(stream, sample, (stream, sample), f.seed, key);
        // Follow the path lobes (mirrors, glass) with their probability; else end here.
        let q = bsdf_path_probability(&b, wo);
        if u[3] < q {
            let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], LOBES_PATH);
            if smp.flags == 0 {
                break;
            }
            throughput *= smp.weight / q;
            if smp.flags & BSDF_TRANSMISSION != 0 {
                medium = medium_after(s, prim, h.ng, smp.wi, medium);
            }
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
            // The gather path's end: the global map there (the volume map at a scattering
            // point), weighted 1/gather_rays.
            let layer = if via_specular { LAYER_SPECULAR } else { LAYER_INDIRECT };
            let w = weight * (gather_weight * (throughput / (1.0 - q)) / f.gather_rays as f32) * inv_sigma_t;
            let map = if scattered { MAP_VOLUME } else { MAP_GLOBAL };
            lookups[0] = Some(Lookup { map, exclude: 0, layer, weight: w });
            estimate = Some((h, b, wo));
            (ray, t_max) = (Ray::Lookup, NO_RAY);
            continue;
        }
        weight = throughput / (1.0 - q);
        via_specular = depth > 0;
        volume_e = scattered;
        inv_sigma_t_e = inv_sigma_t;
        if part == 0 {
            let sr = direct_light_sample(s, &h, &b, wo, stream, sample, dim, penumbra_since, 0);
            (shadow_rays, shadow_adaptive, medium_e) = (sr.rays, sr.adaptive, medium);
            unoccluded = sr.unoccluded;
            o = sr.origin;
            d = sr.direction;
            t_max = sr.t_max;
            ray = Ray::Shadow;
            estimate = Some((h, b, wo));
            continue;
        }
        // A scattering point reads the volume map in part 0 and has no final gather.
        if f.photon_mapping == 0 || scattered {
            break;
        }
        // Final-gather ray part - 1, sampled from the estimate lobes.
        gdim = RNG_GATHER_DOMAIN + (part - 1) * RNG_GATHER_DIMS_PER_RAY;
        // A pixel's gather rays are one sequence: ray j of sample i is its point i x rays + j.
        let u0 = rand4(stream, sample, f.seed, gdim);
        let ug = qmc2(stream, sample.wrapping_mul(f.gather_rays).wrapping_add(part - 1), f.seed, RNG_GATHER_DOMAIN);
        let first = bsdf_sample(&b, wo, [u0[2], ug[0], ug[1]], LOBES_ESTIMATE);
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
    // Where the probes found an edge, the thin core's photons over the kernel's share on the
    // surface; elsewhere the disc's.
    for (l, g) in lookups.iter().zip(found) {
        if let Some(l) = l {
            // Without probes the surface's reach is its open edges' alone, and the disc's
            // photons are all the surface's.
            let probed = probe == 2 * EDGE_PROBES;
            let mass = if probe_edges { edge_mass(&surface_reach, s.maps.grids[l.map].radius) } else { 1.0 };
            let v = if mass < 1.0 { (if probed { g.thin } else { g.disc }) / mass.max(EDGE_MIN_MASS) } else { g.disc };
            terms[l.layer as usize] += l.weight * v;
        }
    }
}

/// Adds the sample part of `range` to `accumulation` (`LAYER_COUNT` `[r, g, b, w]` per pixel of
/// the band; w of the direct layer counts rays, w of the indirect and caustic layers the pixel's
/// shadow rays toward adaptive lights in this pass, blocked and not, w of the specular layer 1 +
/// the sample at which both were first seen), exactly as one dispatch of the kernel does.
pub fn render(s: &SceneView, range: &DispatchRange, accumulation: &mut [[f32; 4]]) {
    super::pixel_list::for_each_pixel(s.frame.width, range, s.pixel_list, accumulation, |px, py, acc| {
        let mut terms = [Vec3::ZERO; 4];
        let mut rays = 0;
        let mut visibility = [0; 2];
        let (blocked, lit, since) = (LAYER_INDIRECT as usize, LAYER_CAUSTICS as usize, LAYER_SPECULAR as usize);
        let mut penumbra_since = if acc[since][3] > 0.0 { acc[since][3] as u32 - 1 } else { NO_SAMPLE };
        if range.part == 0 && penumbra_since == NO_SAMPLE && acc[blocked][3] > 0.0 && acc[lit][3] > 0.0 {
            penumbra_since = range.sample_index;
            acc[since][3] = (range.sample_index + 1) as f32;
        }
        let sample = range.sample_index;
        radiance(s, px, py, sample, range.part, penumbra_since, &mut terms, &mut rays, &mut visibility);
        acc[blocked][3] += visibility[0] as f32;
        acc[lit][3] += visibility[1] as f32;
        for (layer, term) in acc.iter_mut().zip(terms) {
            layer[0] += term.x;
            layer[1] += term.y;
            layer[2] += term.z;
        }
        acc[LAYER_DIRECT as usize][3] += rays as f32;
    });
}
