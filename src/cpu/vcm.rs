//! Vertex connection and merging (`integrator = "vcm"`) and bidirectional path tracing (`"bpt"`,
//! the same algorithm without merging), after SmallVCM (Georgiev, Křivánek, Davidovič and
//! Slusallek, "Light transport simulation with vertex connection and merging", 2012, and the
//! "Implementing VCM" report); twin of `shaders/vcm_light.comp` and `shaders/render_vcm.comp`.
//!
//! Each sample is two stages. The light stage traces `VcmParams::light_paths` light sub-paths,
//! stores their non-delta vertices (`LightVertex`, a fixed run of slots per path) and connects
//! each to the camera (light tracing), splatting into an image of fixed-point sums. The camera
//! stage traces one camera sub-path per pixel; at each non-delta vertex it samples a light,
//! connects to every vertex of the light path of its own index, and merges with the light
//! vertices within the radius (a photon density estimate over the hashed grid the photon maps
//! use), adding the pixel's splats at the end. Every contribution is weighed by the power
//! heuristic over all techniques that could have made its path, computed by SmallVCM's recursion
//! (dVCM, dVC, dVM per sub-path, updated at each vertex) without visiting the path again.
//!
//! Directions follow the BSDF convention: `wo` toward the camera side, `wi` toward the light side;
//! at a light vertex the camera side is where the connection goes, so a light sub-path evaluates
//! `bsdf_eval(b, w_out, w_in)`, the same function of the same path a camera path evaluates (the
//! adjoint, for our BSDFs, where the shading normal is the geometric one; where a bump or normal
//! map bends it, `shading_adjoint` makes light paths' scattering the adjoint, as photon tracing).
//!
//! Densities of light sampling and emission use each light's uniform density by area (as `pt`'s
//! weights do): multiple importance sampling needs only that every technique weighs a path by the
//! same functions. Russian roulette stays out of the weights (as in pbrt's BDPT).
//!
//! In participating media both sub-paths sample free flights (`next_vertex`), pass null
//! boundaries without a vertex, and scatter at collisions by the phase function; light vertices
//! in media are stored (`VERTEX_MEDIUM`) and connected to, never merged, so merging's terms leave
//! the weights at those vertices (`SubPath::scatter`, `merge_weight`). Connections carry the
//! transmittance of the media they cross (`transmittance`). The weights leave the free-flight
//! densities out (docs/integrators.md, "Media").

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::bsdf::{
    bsdf_eval, bsdf_flags, bsdf_path_probability, bsdf_pdf, bsdf_sample, material_bsdf, material_emission,
    shading_adjoint, Bsdf,
};
use super::grid::for_each_photon_near;
use super::grid_build::{build_grid, grid_params};
use super::instance::hit_primitive;
use super::light::{
    direct_light_pmf, emitter_cosine, environment_pdf, environment_radiance, light_emission, light_sample,
    pick_direct_light, pick_light, receiver_normal,
};
use super::medium::{medium_after, medium_hit, medium_sample, medium_transmittance, phase_bsdf};
use super::render_pt::path_layer;
use super::rng::{bsdf_numbers, qmc2, rand1, rand2, rand4, sequence_point};
use super::shading::{
    camera_ray, film_offset, filter_is_pixel, filter_radius, filter_weight, grid_sample, lens_offset, lens_sample,
    offset_origin, ray_skip,
};
use super::shape::{shape_hit, Hit};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::{DispatchRange, FrameParams, GridParams, Light, LightVertex, Photon, VcmParams};

/// The heuristic's power of a density (Veach's beta = 2; SmallVCM's `Mis`).
pub fn mis(x: f32) -> f32 {
    x * x
}

/// `a * b` for the weights' products, zero when either is zero: a technique whose density is zero
/// (or underflows to zero) weighs nothing, even against a partial weight that overflowed to
/// infinity (a camera vertex on an infinite plane near the horizon, ten million units away and
/// met at a grazing angle: 0 x inf would be NaN, and one NaN sample blackens its pixel for good).
pub fn wmul(a: f32, b: f32) -> f32 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        a * b
    }
}

/// `a / c` for the partial weights, zero when `a` is (0 / 0 at a grazing cosine of 0).
pub fn wdiv(a: f32, c: f32) -> f32 {
    if a == 0.0 {
        0.0
    } else {
        a / c
    }
}

/// Whether light sub-paths can reach the camera: a perspective camera (pinhole or thin lens), an
/// orthographic one without a lens, a latlong one. An orthographic camera's lens would make
/// every aperture point see a point along its own tilted ray, which light tracing leaves out
/// (and the weights with it).
pub fn camera_connectable(f: &FrameParams) -> bool {
    f.camera_kind != CAMERA_ORTHOGRAPHIC || f.lens_radius <= 0.0
}

/// The point of the aperture that lens sample `u` picks (the eye of a pinhole camera), as
/// `camera_ray` places it.
pub fn lens_point(f: &FrameParams, u: [f32; 2]) -> Vec3 {
    let eye = Vec3::from(f.camera_position);
    if f.lens_radius > 0.0 {
        eye + lens_offset(f, u)
    } else {
        eye
    }
}

/// The camera point a light vertex at `x` connects to: the aperture point of lens sample `u`
/// (perspective), the eye (latlong), or the film point whose parallel ray meets `x`
/// (orthographic).
pub fn camera_point(f: &FrameParams, x: Vec3, u: [f32; 2]) -> Vec3 {
    match f.camera_kind {
        CAMERA_ORTHOGRAPHIC => {
            let fw = Vec3::from(f.camera_forward).normalize();
            x - fw * (x - Vec3::from(f.camera_position)).dot(fw)
        }
        CAMERA_LATLONG => Vec3::from(f.camera_position),
        _ => lens_point(f, u),
    }
}

/// Film area of one pixel on the plane `camera_forward` away (`camera_right` and `camera_up`
/// span half the film).
pub fn camera_pixel_area(f: &FrameParams) -> f32 {
    4.0 * Vec3::from(f.camera_right).length() * Vec3::from(f.camera_up).length() / (f.width * f.height) as f32
}

/// Solid-angle density, per pixel, of the camera's rays along unit direction `d` (from the
/// camera): for a perspective camera a point uniform on one pixel of the film seen from the eye
/// (SmallVCM's imageToSolidAngleFactor), for a latlong one the inverse of a pixel's solid angle
/// at `d`'s latitude. An orthographic camera's rays are parallel: see `camera_area_pdf`.
pub fn camera_pdf_w(f: &FrameParams, d: Vec3) -> f32 {
    if f.camera_kind == CAMERA_LATLONG {
        let up = Vec3::from(f.camera_up);
        let cos_latitude = (1.0 - d.dot(up) * d.dot(up)).max(0.0).sqrt();
        let pi = std::f32::consts::PI;
        return (f.width * f.height) as f32 / (2.0 * pi * pi * cos_latitude);
    }
    let fw = Vec3::from(f.camera_forward);
    let cos = d.dot(fw.normalize());
    fw.length_squared() / (cos * cos * cos * camera_pixel_area(f))
}

/// Density by area, per pixel, of the camera's rays along `d` at a point `dist2` (squared) away
/// that they meet at cosine `cos_y` (SmallVCM's imageToSurfaceFactor). An orthographic camera's
/// parallel rays spread over a pixel's film area whatever the distance.
pub fn camera_area_pdf(f: &FrameParams, d: Vec3, dist2: f32, cos_y: f32) -> f32 {
    if f.camera_kind == CAMERA_ORTHOGRAPHIC {
        cos_y / camera_pixel_area(f)
    } else {
        camera_pdf_w(f, d) * cos_y / dist2
    }
}

/// A camera sub-path's first dVCM along its first ray `d`: the light tracing technique's
/// density relative to the camera's. An orthographic camera's is by area already, and its first
/// `SubPath::arrive` leaves the distance out.
pub fn camera_d_vcm(f: &FrameParams, light_paths: u32, d: Vec3) -> f32 {
    if !camera_connectable(f) {
        0.0
    } else if f.camera_kind == CAMERA_ORTHOGRAPHIC {
        mis(light_paths as f32 * camera_pixel_area(f))
    } else {
        mis(light_paths as f32 / camera_pdf_w(f, d))
    }
}

/// The film point (in pixels, (0, 0) the image's top-left corner) of world point `x` seen from
/// `lens` (a point of the aperture), if it is in front of the camera. Through a thin lens that
/// is the film point of where the ray from `lens` to `x` crosses the plane in focus (every
/// camera ray aims its pixel's pinhole ray there).
pub fn camera_film(f: &FrameParams, x: Vec3, lens: Vec3) -> Option<Vec2> {
    let (fw, r, u) = (Vec3::from(f.camera_forward), Vec3::from(f.camera_right), Vec3::from(f.camera_up));
    let v = x - Vec3::from(f.camera_position);
    let (sx, sy) = match f.camera_kind {
        // Inverting `camera_ray`: longitude from straight ahead, latitude from the horizon.
        CAMERA_LATLONG => {
            let d = v.normalize();
            let pi = std::f32::consts::PI;
            (d.dot(r).atan2(d.dot(fw)) / pi, d.dot(u).clamp(-1.0, 1.0).asin() / (0.5 * pi))
        }
        CAMERA_ORTHOGRAPHIC => {
            if v.dot(fw) <= 0.0 {
                return None;
            }
            (v.dot(r) / r.length_squared(), v.dot(u) / u.length_squared())
        }
        _ => {
            let x = if f.lens_radius > 0.0 {
                let d = (x - lens).normalize();
                let along = d.dot(fw);
                if along <= 0.0 {
                    return None;
                }
                lens + d * (f.focal_distance / along)
            } else {
                x
            };
            let v = x - Vec3::from(f.camera_position);
            let k = v.dot(fw) / fw.length_squared();
            if k <= 0.0 {
                return None;
            }
            (v.dot(r) / (k * r.length_squared()), v.dot(u) / (k * u.length_squared()))
        }
    };
    Some(Vec2::new(0.5 * (sx + 1.0) * f.width as f32, 0.5 * (1.0 - sy) * f.height as f32))
}

/// Whether some pixel's filter reaches film point `film`: a box's only inside the image, a wider
/// filter's up to its radius beyond the outer pixels' centres.
pub fn film_reaches_image(f: &FrameParams, film: Vec2) -> bool {
    let size = Vec2::new(f.width as f32, f.height as f32);
    if filter_is_pixel(f) {
        return film.x >= 0.0 && film.y >= 0.0 && film.x < size.x && film.y < size.y;
    }
    let r = filter_radius(f) - 0.5;
    film.x > -r && film.y > -r && film.x < size.x + r && film.y < size.y + r
}

/// The pixels whose filter reaches `film` (a box's: the one it lies in) and the filter's weight
/// at each, the splat's share there: with the film point of a camera sample drawn from the filter
/// around its pixel (`shading::film_offset`), a light-tracing splat must reach the pixels whose
/// samples could have landed on it, weighted by the same density, so both estimate the same
/// filtered image. Film points may lie outside the image (up to the radius).
pub fn film_footprint(f: &FrameParams, film: Vec2) -> Vec<(u32, f32)> {
    if filter_is_pixel(f) {
        return vec![((film.y as u32).min(f.height - 1) * f.width + (film.x as u32).min(f.width - 1), 1.0)];
    }
    let r = filter_radius(f);
    let (lo_x, lo_y) = (((film.x - 0.5 - r).ceil() as i32).max(0), ((film.y - 0.5 - r).ceil() as i32).max(0));
    let hi_x = ((film.x - 0.5 + r).floor() as i32).min(f.width as i32 - 1);
    let hi_y = ((film.y - 0.5 + r).floor() as i32).min(f.height as i32 - 1);
    let mut out = Vec::new();
    for py in lo_y..=hi_y {
        for px in lo_x..=hi_x {
            let w = filter_weight(f, film.x - (px as f32 + 0.5)) * filter_weight(f, film.y - (py as f32 + 0.5));
            if w > 0.0 {
                out.push((py as u32 * f.width + px as u32, w));
            }
        }
    }
    out
}

/// Splat value `v` >= 0 as the (low, high) words of its 64-bit fixed-point sum: 32 bits of
/// fraction. Both words follow from exact f32 operations, so both twins add the same integers.
pub fn splat_words(v: f32) -> (u32, u32) {
    if v.is_nan() || v <= 0.0 {
        return (0, 0);
    }
    let v = v.min(SPLAT_MAX);
    let whole = v.floor();
    (((v - whole) * 4_294_967_296.0) as u32, whole as u32)
}

/// The f32 a fixed-point sum reads back as.
pub fn splat_value(low: u32, high: u32) -> f32 {
    high as f32 + low as f32 * (1.0 / 4_294_967_296.0)
}

/// Density, before the pick probability, of a light sub-path leaving light `l` along -`w` (`w`
/// points from the scene toward the light; SmallVCM's emissionPdfW): for area lights by area
/// times the cosine lobe at cosine `cos_l`, for infinite lights by solid angle times the area of
/// the scene's disc they start from, for point and spot lights uniform in their cone. The one
/// place every technique takes it from (light sub-paths, light sampling, emission met).
pub fn emission_pdf(s: &SceneView, l: &Light, w: Vec3, cos_l: f32) -> f32 {
    let disc = std::f32::consts::PI * l.radius * l.radius;
    match l.kind {
        // Over the emitter's hemisphere, or both (a two-sided one's cos_outer is -1).
        LIGHT_AREA => cos_l.max(0.0) / (std::f32::consts::PI * l.area * (1.0 - l.cos_outer)),
        LIGHT_ENVIRONMENT => environment_pdf(s, l, w) / disc,
        LIGHT_DISTANT if l.area > 0.0 => 1.0 / (l.area * disc),
        LIGHT_DISTANT => 1.0 / disc,
        _ => 1.0 / (2.0 * std::f32::consts::PI * (1.0 - l.cos_outer)),
    }
}

/// Whether a sub-path of the infinite light `l` can reach point `at` arriving from direction `w`
/// (toward the light). Its sub-paths start on the disc of the scene's bounding sphere that faces
/// the light's travel (`light_emission`: `l.radius` upstream of `l.position`), so the point of
/// that disc behind `at` along `w` must lie on it. Geometry the bounding sphere leaves out (an
/// infinite plane) is met by no light sub-path outside the disc's shadow: there the light-side
/// techniques must weigh nothing and the camera's take the whole path, or that ground is dark.
pub fn disc_reaches(l: &Light, w: Vec3, at: Vec3) -> bool {
    let axis = if l.kind == LIGHT_ENVIRONMENT { -w } else { Vec3::from(l.direction) };
    let centre = Vec3::from(l.position) - axis * l.radius;
    let s = (at - centre).dot(axis) / -w.dot(axis);
    let q = at - centre + w * s;
    s >= -DISC_SLACK * l.radius && q.length_squared() <= l.radius * l.radius * (1.0 + DISC_SLACK)
}

/// `emission_pdf` of a sub-path that meets point `at` first: zero for an infinite light whose
/// disc does not reach it (`disc_reaches`).
pub fn emission_pdf_at(s: &SceneView, l: &Light, w: Vec3, cos_l: f32, at: Vec3) -> f32 {
    let infinite = matches!(l.kind, LIGHT_DISTANT | LIGHT_ENVIRONMENT);
    if infinite && !disc_reaches(l, w, at) {
        0.0
    } else {
        emission_pdf(s, l, w, cos_l)
    }
}

/// The light sample's densities that the weights need, before the pick probability: the
/// solid-angle density of drawing it from the shading point `dist` away (SmallVCM's directPdfW;
/// `pdf` is the sample's own, 0 for delta lights), `emission_pdf_at` the shading point `at`, and
/// the cosine at the light.
fn illumination_pdfs(s: &SceneView, l: &Light, at: Vec3, wi: Vec3, dist: f32, pdf: f32, cos_l: f32) -> (f32, f32, f32) {
    let direct = match l.kind {
        LIGHT_AREA | LIGHT_ENVIRONMENT => pdf,
        LIGHT_DISTANT if l.area > 0.0 => pdf,
        LIGHT_DISTANT => 1.0,
        // Point and spot lights: by area at the shading point, as SmallVCM's.
        _ => dist * dist,
    };
    let cos_at_light = if l.kind == LIGHT_AREA { cos_l } else { 1.0 };
    (direct, emission_pdf_at(s, l, wi, cos_l, at), cos_at_light)
}

/// Whether light `l` is a delta light (no ray meets it: point, spot, distant without a disc).
fn light_is_delta(l: &Light) -> bool {
    match l.kind {
        LIGHT_AREA | LIGHT_ENVIRONMENT => false,
        LIGHT_DISTANT => l.area <= 0.0,
        _ => true,
    }
}

/// Densities of a non-delta lobe choice at a vertex: the solid-angle density of sampling `wi`
/// from `wo` (with the probability of taking the non-delta lobes) and the reverse.
fn lobe_pdfs(b: &Bsdf, wo: Vec3, wi: Vec3) -> (f32, f32) {
    let forward = (1.0 - bsdf_path_probability(b, wo)) * bsdf_pdf(b, wo, wi);
    let reverse = (1.0 - bsdf_path_probability(b, wi)) * bsdf_pdf(b, wi, wo);
    (forward, reverse)
}

/// |cos| to the shading normal, or 1 at a medium's scattering point.
fn abs_cos(b: &Bsdf, w: Vec3) -> f32 {
    if b.kind == MATERIAL_PHASE {
        1.0
    } else {
        b.ns.dot(w).abs()
    }
}

/// Whether merging can happen at a vertex with BSDF `b`: not at a medium's scattering points
/// (they are connected to, never merged; docs/integrators.md, "Media").
fn mergeable(b: &Bsdf) -> bool {
    b.kind != MATERIAL_PHASE
}

/// Whether camera paths merge at their first vertex. Not where light tracing reaches the
/// camera: with a radius of about a pixel, merging there is light tracing again with a box
/// filter, so the two halved each other's weight while the lookups cost a tenth of a vcm render
/// (at equal samples the error moved by 1%, the time fell 10-24%; BENCHMARKS.md). The check
/// technique `VCM_MERGE_ONLY` merges there, as SmallVCM's ppm mode.
fn merges_at_first_vertex(p: &VcmParams, f: &FrameParams) -> bool {
    !has(p, VCM_CONNECT) || !camera_connectable(f)
}

/// SmallVCM's misVmWeightFactor for merging at a vertex with BSDF `b`: 0 where it cannot merge.
fn merge_weight(p: &VcmParams, b: &Bsdf) -> f32 {
    if mergeable(b) {
        p.vm_weight
    } else {
        0.0
    }
}

/// A sub-path's state: its throughput and SmallVCM's partial weights.
#[derive(Clone, Copy, Debug)]
struct SubPath {
    throughput: Vec3,
    d_vcm: f32,
    d_vc: f32,
    d_vm: f32,
}

impl SubPath {
    /// Arriving at a vertex `dist` away at cosine `cos_in` (`far` false: the first segment of an
    /// infinite light's path, whose density is by area of the scene's disc already).
    fn arrive(&mut self, dist: f32, cos_in: f32, far: bool) {
        if far {
            self.d_vcm = wmul(self.d_vcm, mis(dist * dist));
        }
        let c = mis(cos_in);
        self.d_vcm = wdiv(self.d_vcm, c);
        self.d_vc = wdiv(self.d_vc, c);
        self.d_vm = wdiv(self.d_vm, c);
    }

    /// Leaving a vertex along a sampled direction of cosine `cos_out`: through a delta lobe, or a
    /// non-delta one with densities `pdf` (forward, including the lobe choice) and `reverse`.
    /// `merge` says whether merging is a technique at this vertex: the terms of merging there
    /// (misVmWeightFactor in dVC, the 1 in dVM) are left out at a medium's scattering points.
    fn scatter(&mut self, p: &VcmParams, delta: bool, cos_out: f32, pdf: f32, reverse: f32, merge: bool) {
        if delta {
            self.d_vcm = 0.0;
            self.d_vc = wmul(self.d_vc, mis(cos_out));
            self.d_vm = wmul(self.d_vm, mis(cos_out));
        } else {
            let g = mis(cos_out / pdf);
            let (vm, one) = if merge { (p.vm_weight, 1.0) } else { (0.0, 0.0) };
            self.d_vc = wmul(g, wmul(self.d_vc, mis(reverse)) + self.d_vcm + vm);
            self.d_vm = wmul(g, wmul(self.d_vm, mis(reverse)) + wmul(self.d_vcm, p.vc_weight) + one);
            self.d_vcm = mis(1.0 / pdf);
        }
    }
}

/// Whether a technique is on.
fn has(p: &VcmParams, t: u32) -> bool {
    p.techniques & t != 0
}

/// Light sub-paths per sample: one per `VCM_PIXELS_PER_LIGHT_PATH` pixels, as many as the vertex
/// budget allows.
pub fn light_path_count(f: &FrameParams) -> u32 {
    (f.width * f.height).div_ceil(VCM_PIXELS_PER_LIGHT_PATH).min(VCM_MAX_LIGHT_VERTICES / f.max_depth.max(1)).max(1)
}

/// How far the camera sees: the median distance of the first hits of nine camera rays spread over
/// the film (lens centre), or `fallback` when none hits.
pub fn view_distance(s: &SceneView, fallback: f32) -> f32 {
    let mut hits: Vec<f32> = Vec::new();
    for (sx, sy) in [
        (0.0, 0.0),
        (-0.5, -0.5),
        (0.5, -0.5),
        (-0.5, 0.5),
        (0.5, 0.5),
        (0.0, 0.5),
        (0.0, -0.5),
        (0.5, 0.0),
        (-0.5, 0.0),
    ] {
        let (o, d) = camera_ray(s, sx, sy, [0.5, 0.5]);
        let (prim, t) = trace_ray(s, o, d, f32::INFINITY, false, NO_LIGHT);
        if prim != NO_LIGHT && t.is_finite() {
            hits.push(t);
        }
    }
    hits.sort_by(f32::total_cmp);
    hits.get(hits.len() / 2).copied().unwrap_or(fallback)
}

/// The merging radius of the first sample: the smaller of `VCM_RADIUS_PIXELS` pixels' footprint
/// at the distance the camera sees (`view_distance`) and the radius holding
/// `VCM_RADIUS_VERTICES` light vertices were one vertex per light path spread evenly over the
/// scene's `surface_area` (a large open scene, most of it unlit or unseen, would blur the seen part
/// with the second alone).
pub fn vcm_base_radius(f: &FrameParams, surface_area: f32, view_distance: f32) -> f32 {
    let paths = light_path_count(f) as f32;
    let by_area = (VCM_RADIUS_VERTICES * surface_area / (std::f32::consts::PI * paths)).sqrt();
    let film = match f.camera_kind {
        CAMERA_ORTHOGRAPHIC => 2.0 * Vec3::from(f.camera_right).length(),
        CAMERA_LATLONG => 2.0 * std::f32::consts::PI * view_distance,
        _ => 2.0 * Vec3::from(f.camera_right).length() * view_distance / Vec3::from(f.camera_forward).length(),
    };
    let by_pixel = VCM_RADIUS_PIXELS * film / f.width as f32;
    let r = if by_pixel > 0.0 && by_pixel.is_finite() { by_area.min(by_pixel) } else { by_area };
    r.max(f32::MIN_POSITIVE)
}

/// The sample's parameters: the light path count, the merging radius of sample `sample_index`
/// (from the first sample's, `base_radius`) and the weights' factors, for an integrator
/// (`INTEGRATOR_BPT` or `_VCM`) and the frame's techniques (`TECHNIQUES_ALL`, or one
/// `VCM_*_ONLY` check).
pub fn vcm_params(f: &FrameParams, base_radius: f32, sample_index: u32) -> VcmParams {
    let slots = f.max_depth.max(1);
    let light_paths = light_path_count(f);
    let techniques = match f.techniques {
        VCM_LIGHT_TRACE_ONLY => VCM_LIGHT_TRACE_ONLY,
        VCM_MERGE_ONLY => VCM_MERGE_ONLY,
        _ if f.integrator == INTEGRATOR_VCM => VCM_CONNECT | VCM_MERGE,
        _ => VCM_CONNECT,
    };
    let radius = base_radius * ((sample_index as f64 + 1.0).powf((VCM_ALPHA as f64 - 1.0) / 2.0)) as f32;
    let eta = std::f32::consts::PI * radius * radius * light_paths as f32;
    VcmParams {
        sample_index,
        light_paths,
        vertex_slots: slots,
        techniques,
        radius,
        vm_weight: if techniques & VCM_MERGE != 0 { mis(eta) } else { 0.0 },
        vc_weight: if techniques & VCM_CONNECT != 0 { mis(1.0 / eta) } else { 0.0 },
        vm_normalization: 1.0 / eta,
        path_begin: 0,
        path_count: light_paths,
        paths_per_invocation: 1,
        connections: VCM_CONNECTIONS,
        steps_per_dispatch: 0,
        resume: 0,
    }
}

/// The light stage's results on the CPU: vertex slots (`vertex_slots` per path, unused ones with
/// `path_length` 0), their grid for merging, and the light-tracing image (per pixel and layer,
/// r g b, each a 64-bit fixed-point sum). A render keeps one across its samples: reallocating
/// and clearing its tens of megabytes every sample was a serial fifth of a bpt render on two
/// cores (BENCHMARKS.md, "The light stage's buffers").
#[derive(Default)]
pub struct LightStage {
    pub vertices: Vec<LightVertex>,
    positions: Vec<Vec3>,
    /// Each path's count of vertices (in its first slots): what connections draw by
    /// (`pick_light_vertex`).
    path_counts: Vec<u32>,
    pub grid: GridParams,
    /// Light vertices as grid points: position, then (path, slot) in the two other words.
    pub points: Vec<Photon>,
    pub starts: Vec<u32>,
    splats: Vec<AtomicU64>,
}

impl LightStage {
    /// The pixel's light-tracing terms, as the kernel reads them.
    pub fn splat_terms(&self, pixel: u32) -> [Vec3; 4] {
        let mut terms = [Vec3::ZERO; 4];
        let base = (pixel * LAYER_COUNT * 3) as usize;
        for (layer, t) in terms.iter_mut().enumerate() {
            let c = |k: usize| {
                let v = self.splats[base + layer * 3 + k].load(Ordering::Relaxed);
                splat_value(v as u32, (v >> 32) as u32)
            };
            *t = Vec3::new(c(0), c(1), c(2));
        }
        terms
    }
}

/// The grid a sample's light vertices merge through. Its cells are twice the radius wide, as
/// SmallVCM's: a lookup then reads at most 8 buckets (about 7 on average) instead of about 21,
/// and with a radius of about a pixel most lookups find no vertex at all, so the buckets' cache
/// misses were the cost (vcm's camera stage 10% faster on cornell-glossy, BENCHMARKS.md).
pub fn vertex_grid(p: &VcmParams, points: u32) -> GridParams {
    GridParams { cell_size: 2.0 * p.radius, ..grid_params(p.radius, points, 1.0) }
}

/// Runs the light stage of a sample into `stage`: every light path, its vertices, its splats.
pub fn light_stage(s: &SceneView, p: &VcmParams, stage: &mut LightStage) {
    let f = s.frame;
    let slots = p.vertex_slots as usize;
    let slot_count = p.light_paths as usize * slots;
    let splat_count = (f.width * f.height * LAYER_COUNT * 3) as usize;
    stage.vertices.resize(slot_count, LightVertex::default());
    stage.positions.resize(slot_count, Vec3::ZERO);
    stage.path_counts.resize(p.light_paths as usize, 0);
    stage.splats.resize_with(splat_count, || AtomicU64::new(0));
    stage.splats.par_iter().with_min_len(4096).for_each(|a| a.store(0, Ordering::Relaxed));
    let splats = &stage.splats;
    let runs = stage.vertices.par_chunks_mut(slots).zip(stage.positions.par_chunks_mut(slots));
    let runs = runs.zip(stage.path_counts.par_iter_mut());
    // A path's slots beyond its count keep an earlier sample's vertices: nothing reads them.
    runs.enumerate().for_each(|(path, ((out, at), count))| {
        (_, *count) = trace_light_path(s, p, path as u32, out, at, &mut |pixel, layer, v| {
            let base = ((pixel * LAYER_COUNT + layer) * 3) as usize;
            for (k, c) in [v.x, v.y, v.z].into_iter().enumerate() {
                let (low, high) = splat_words(c);
                splats[base + k].fetch_add(((high as u64) << 32) | low as u64, Ordering::Relaxed);
            }
        });
    });
    let mut points = Vec::new();
    if has(p, VCM_MERGE | VCM_MERGE_ONLY) {
        for (path, &count) in stage.path_counts.iter().enumerate() {
            for j in 0..count as usize {
                let i = path * slots + j;
                if stage.vertices[i].flags & VERTEX_MEDIUM == 0 {
                    let position = stage.positions[i].into();
                    points.push(Photon { position, flux_rg: path as u32, flux_b_dir: j as u32 });
                }
            }
        }
    }
    stage.grid = vertex_grid(p, points.len() as u32);
    (stage.points, stage.starts) = build_grid(&points, &stage.grid);
}

/// The light vertex a connection draws with numbers `u`: a block of `VCM_PICK_BLOCK` light
/// paths uniformly (`u[0]`), then one of the block's vertices uniformly (`u[1]`; a path's are
/// its first `counts[path]` slots). Returns the slot and the weight that makes the draw's mean
/// the sum over all the sample's vertices over the light paths (1 / (the vertex's probability x
/// light paths)), or `None` for a block without vertices. Nearly a uniform draw from all the
/// sample's vertices (the weight stays near their mean count), which at equal samples gave
/// lower error than one light path's every vertex (SmallVCM) or one path's one vertex; a block
/// rather than the whole sample keeps a light path the device traces otherwise under rounding
/// (haze, bump maps) out of all but its block's draws, so the GPU = CPU checks stay tight.
pub fn pick_light_vertex(counts: &[u32], slots: u32, u: [f32; 2]) -> Option<(usize, f32)> {
    let paths = counts.len() as u32;
    let blocks = paths.div_ceil(VCM_PICK_BLOCK);
    let block = ((u[0] * blocks as f32) as u32).min(blocks - 1);
    let first = (block * VCM_PICK_BLOCK) as usize;
    let counts = &counts[first..(first + VCM_PICK_BLOCK as usize).min(paths as usize)];
    let total: u32 = counts.iter().sum();
    if total == 0 {
        return None;
    }
    let mut j = ((u[1] * total as f32) as u32).min(total - 1);
    let mut path = first;
    for &c in &counts[..counts.len() - 1] {
        if j < c {
            break;
        }
        j -= c;
        path += 1;
    }
    Some((path * slots as usize + j as usize, total as f32 * blocks as f32 / paths as f32))
}

/// The point, ray offset and BSDF of a stored light vertex, rebuilt from the ray that met it: a
/// surface point, or a medium's scattering point (`VERTEX_MEDIUM`) with its phase function.
fn light_surface<'a>(s: &SceneView<'a>, v: &LightVertex) -> LightSurface<'a> {
    let (o, d) = (Vec3::from(v.origin), Vec3::from(v.direction));
    if v.flags & VERTEX_MEDIUM != 0 {
        let h = medium_hit(o + d * v.t, -d);
        return LightSurface { p: h.p, eps: h.eps, bsdf: phase_bsdf(s, v.hit, -d) };
    }
    let h = shape_hit(s, v.hit, o, d, v.t);
    LightSurface { p: h.p, eps: h.eps, bsdf: material_bsdf(s, &s.materials[h.material as usize], &h) }
}

/// What a connection needs of a light vertex: its point, ray offset and BSDF.
#[derive(Clone, Copy)]
struct LightSurface<'a> {
    p: Vec3,
    eps: f32,
    bsdf: Bsdf<'a>,
}

/// The medium a segment leaving vertex `h` (at `at`) along `dir` starts in, where the path met
/// it from `wo`: the medium beyond the surface when `dir` crosses it.
fn medium_toward(s: &SceneView, h: &Hit, at: VertexMedium, wo: Vec3, dir: Vec3) -> u32 {
    if at.prim == NO_LIGHT || dir.dot(h.ng) * wo.dot(h.ng) >= 0.0 {
        at.medium
    } else {
        medium_after(s, at.prim, h.ng, dir, at.medium)
    }
}

/// Where a sub-path's vertex is: its primitive (`NO_LIGHT` at a medium's scattering point) and
/// the medium the path reached it in.
#[derive(Clone, Copy, Debug)]
struct VertexMedium {
    prim: u32,
    medium: u32,
}

/// Where a connection segment's transmittance draws its random numbers (ratio tracking through
/// heterogeneous media): stream and sample, and the first dimension of the segment's crossings.
#[derive(Clone, Copy, Debug)]
struct SegmentNumbers {
    stream: u32,
    sample: u32,
    dim: u32,
}

/// Transmittance of the ray from `o` along unit `d` up to `t_max`, starting in `medium` and
/// leaving `skip` aside: 0 when a surface other than a null boundary blocks it, else 1 times
/// the transmittance of every medium on the way (through at most `MEDIUM_CROSSINGS` null
/// boundaries, as `pt`'s shadow rays). Without media in the scene, one any-hit ray. Counts the
/// rays.
#[allow(clippy::too_many_arguments)]
fn transmittance(
    s: &SceneView,
    mut o: Vec3,
    d: Vec3,
    mut t_max: f32,
    mut medium: u32,
    mut skip: u32,
    n: SegmentNumbers,
    rays: &mut u32,
) -> Vec3 {
    if s.media.is_empty() {
        *rays += 1;
        let (prim, _) = trace_ray(s, o, d, t_max, true, skip);
        return if prim == NO_LIGHT { Vec3::ONE } else { Vec3::ZERO };
    }
    let mut tr = Vec3::ONE;
    for crossing in 0..=MEDIUM_CROSSINGS {
        *rays += 1;
        let (prim, t) = trace_ray(s, o, d, t_max, false, skip);
        if medium != NO_MEDIUM {
            let seg = if prim == NO_LIGHT { t_max } else { t };
            tr *= medium_transmittance(s, medium, o, d, seg, rand2(n.stream, n.sample, s.frame.seed, n.dim + crossing));
        }
        if prim == NO_LIGHT {
            return tr;
        }
        let h = shape_hit(s, prim, o, d, t);
        if s.materials[h.material as usize].kind != MATERIAL_NULL || tr == Vec3::ZERO {
            return Vec3::ZERO;
        }
        medium = medium_after(s, prim, h.ng, d, medium);
        skip = ray_skip(s, prim);
        let next = offset_origin(&h, -d, BSDF_TRANSMISSION);
        t_max = (t_max - (next - o).dot(d)).max(0.0);
        o = next;
    }
    Vec3::ZERO
}

/// Transmittance of the segment from the point `ha` (its ray leaving from the offset origin on
/// the target's side, in `medium`) to `target`: 0 when blocked (see `transmittance`).
fn visibility(
    s: &SceneView,
    ha: &Hit,
    skip: u32,
    target: Vec3,
    medium: u32,
    n: SegmentNumbers,
    rays: &mut u32,
) -> Vec3 {
    let origin = offset_origin(ha, target - ha.p, BSDF_REFLECTION);
    let to = target - origin;
    let dist = to.length();
    transmittance(s, origin, to / dist, dist * (1.0 - 1e-4) - s.frame.ray_epsilon, medium, skip, n, rays)
}

/// Where a sub-path's ray ends (`next_vertex`).
struct NextVertex {
    /// The primitive met (`NO_LIGHT`: none, or a scattering point in the medium, `scattered`).
    prim: u32,
    scattered: bool,
    /// The last ray's origin and distance (the vertex is `o + t d`), and the whole distance from
    /// the ray's first origin.
    o: Vec3,
    t: f32,
    dist: f32,
    /// The medium the vertex is in (the one the ray ended in).
    medium: u32,
}

/// The next scattering vertex of a sub-path whose ray leaves `o` along `d` in `medium`: free
/// flights through the media on the way (numbers from `domain + segment`, stream and sample
/// `seq`, `segment` counting the flights, as `pt`'s), straight through null boundaries (at most
/// `MEDIUM_CROSSINGS`; `None` past them). Multiplies `throughput` by the flights' weights and
/// adds the media's emission on the way (`throughput` times it) to `emitted`.
#[allow(clippy::too_many_arguments)]
fn next_vertex(
    s: &SceneView,
    mut o: Vec3,
    d: Vec3,
    mut medium: u32,
    mut skip: u32,
    seq: (u32, u32),
    domain: u32,
    segment: &mut u32,
    throughput: &mut Vec3,
    emitted: &mut Vec3,
    rays: &mut u32,
) -> Option<NextVertex> {
    let media = !s.media.is_empty();
    let mut travelled = 0.0f32;
    for _ in 0..=(if media { MEDIUM_CROSSINGS } else { 0 }) {
        *rays += 1;
        let (prim, mut t) = trace_ray(s, o, d, f32::INFINITY, false, skip);
        let mut scattered = false;
        if medium != NO_MEDIUM {
            let e = medium_sample(s, medium, o, d, t, qmc2(seq.0, seq.1, s.frame.seed, domain + *segment));
            *segment += 1;
            *emitted += *throughput * e.emission;
            *throughput *= e.weight;
            scattered = e.scattered;
            t = e.t;
        }
        if !scattered && prim != NO_LIGHT && media {
            let h = shape_hit(s, prim, o, d, t);
            if s.materials[h.material as usize].kind == MATERIAL_NULL {
                // An invisible boundary: straight through into the medium beyond, not a vertex.
                medium = medium_after(s, prim, h.ng, d, medium);
                skip = ray_skip(s, prim);
                let next = offset_origin(&h, -d, BSDF_TRANSMISSION);
                travelled += (next - o).dot(d);
                o = next;
                continue;
            }
        }
        return Some(NextVertex {
            prim: if scattered { NO_LIGHT } else { prim },
            scattered,
            o,
            t,
            dist: travelled + t,
            medium,
        });
    }
    None
}

/// Traces light path `path` of the sample into `out` (its vertex slots, one after another, with
/// their points in `positions`) and hands each light-tracing splat to `splat(pixel, layer,
/// value)`. Returns the rays cast and the count of vertices stored.
pub fn trace_light_path(
    s: &SceneView,
    p: &VcmParams,
    path: u32,
    out: &mut [LightVertex],
    positions: &mut [Vec3],
    splat: &mut dyn FnMut(u32, u32, Vec3),
) -> (u32, u32) {
    let f = s.frame;
    let mut rays = 0;
    let mut stored = 0;
    if f.light_count == 0 {
        return (rays, stored);
    }
    let sample = p.sample_index;
    let dim0 = RNG_VCM_LIGHT_DOMAIN;
    let light = pick_light(s, rand1(path, sample, f.seed, dim0 + RNG_LIGHT_PICK), false);
    let l = &s.lights[light as usize];
    if l.pick_probability <= 0.0 {
        return (rays, stored);
    }
    // The render's light paths are one low-discrepancy sequence (sample k's paths are its points
    // k x light_paths + path) in the numbers that spread them: start, direction, bounces.
    let seq = sequence_point(0, sample, p.light_paths, path);
    let e = light_emission(
        s,
        l,
        qmc2(seq.0, seq.1, f.seed, dim0 + RNG_LIGHT_U),
        qmc2(seq.0, seq.1, f.seed, dim0 + RNG_LIGHT_V),
    );
    // Light sampling's density of the start point: by area for area lights, by solid angle for
    // infinite ones, 1 for delta lights (SmallVCM's directPdfA).
    let direct_pdf = match l.kind {
        LIGHT_AREA => 1.0 / l.area,
        LIGHT_ENVIRONMENT => environment_pdf(s, l, -e.direction),
        LIGHT_DISTANT if l.area > 0.0 => 1.0 / l.area,
        _ => 1.0,
    };
    let emission = emission_pdf(s, l, -e.direction, e.cos_l);
    if emission <= 0.0 || e.power == Vec3::ZERO {
        return (rays, stored);
    }
    let finite = !matches!(l.kind, LIGHT_DISTANT | LIGHT_ENVIRONMENT);
    let mut sub = SubPath {
        throughput: e.power / l.pick_probability,
        d_vcm: mis(direct_pdf / emission),
        d_vc: if light_is_delta(l) {
            0.0
        } else {
            mis((if finite { e.cos_l } else { 1.0 }) / (emission * l.pick_probability))
        },
        d_vm: 0.0,
    };
    sub.d_vm = sub.d_vc * p.vc_weight;
    let (mut o, mut d) = (e.origin, e.direction);
    let mut skip = NO_LIGHT;
    let mut medium = l.medium;
    let mut segment = 0u32;
    // The sub-path's signature so far: non-delta vertices, and whether a delta vertex came first.
    let (mut diffuse, mut specular_first) = (0u32, false);
    for k in 1..=p.vertex_slots {
        let mut unused = Vec3::ZERO;
        let Some(next) = next_vertex(
            s,
            o,
            d,
            medium,
            skip,
            seq,
            RNG_VCM_LIGHT_MEDIUM_DOMAIN,
            &mut segment,
            &mut sub.throughput,
            &mut unused,
            &mut rays,
        ) else {
            break;
        };
        if next.prim == NO_LIGHT && !next.scattered || sub.throughput == Vec3::ZERO {
            break;
        }
        let prim = next.prim;
        (o, medium) = (next.o, next.medium);
        let t = next.t;
        let wo = -d;
        let (h, b) = vertex_at(s, next.scattered, prim, medium, o, d, t);
        let flags = bsdf_flags(&b);
        if flags == 0 {
            break;
        }
        sub.arrive(next.dist, abs_cos(&b, wo), k > 1 || finite);
        if k == 1 {
            // d_vcm holds light sampling's density of the start over emission's, each with its
            // own choice of light: by power for emission, by the light tree at this vertex for
            // light sampling from it.
            let pmf = direct_light_pmf(s, light, h.p, receiver_normal(&b));
            sub.d_vcm = wmul(sub.d_vcm, mis(pmf / l.pick_probability));
        }
        if flags & BSDF_ESTIMATE != 0 {
            positions[stored as usize] = h.p;
            let in_medium = if next.scattered { VERTEX_MEDIUM } else { 0 };
            out[stored as usize] = LightVertex {
                origin: o.into(),
                hit: if next.scattered { medium } else { prim },
                direction: d.into(),
                t,
                throughput: sub.throughput.into(),
                path_length: k,
                d_vcm: sub.d_vcm,
                d_vc: sub.d_vc,
                d_vm: sub.d_vm,
                flags: diffuse | in_medium | if specular_first { VERTEX_SPECULAR_FIRST } else { 0 },
            };
            stored += 1;
            if has(p, VCM_CONNECT | VCM_LIGHT_TRACE_ONLY) && camera_connectable(f) {
                // The lens sample: dimensions of the vertex that sampling its BSDF leaves free.
                let lens_u = rand2(path, sample, f.seed, dim0 + k * RNG_DIMS_PER_BOUNCE + RNG_PIXEL_X);
                let skip = if next.scattered { NO_LIGHT } else { ray_skip(s, prim) };
                let numbers = SegmentNumbers {
                    stream: path,
                    sample,
                    dim: RNG_VCM_LIGHT_TRANSMITTANCE_DOMAIN + k * (MEDIUM_CROSSINGS + 1),
                };
                let at = VertexMedium { prim, medium };
                if let Some((film, v)) = connect_to_camera(s, p, &h, &b, wo, &sub, skip, at, lens_u, numbers, &mut rays)
                {
                    let layer = path_layer(false, diffuse + 1, specular_first);
                    for (pixel, w) in film_footprint(f, film) {
                        // A box's weight is 1: the splat's value unchanged, bit for bit.
                        splat(pixel, layer, if filter_is_pixel(f) { v } else { w * v });
                    }
                }
            }
        }
        if k >= p.vertex_slots {
            break;
        }
        let dim = dim0 + k * RNG_DIMS_PER_BOUNCE;
        let q = bsdf_path_probability(&b, wo);
        let u = bsdf_numbers(path, sample, seq, f.seed, dim + RNG_FRESNEL);
        let delta = u[3] < q;
        let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], if delta { LOBES_PATH } else { LOBES_ESTIMATE });
        if smp.flags == 0 {
            break;
        }
        let cos_out = abs_cos(&b, smp.wi);
        let adjoint = shading_adjoint(&b, wo, smp.wi);
        let factor = if smp.flags & BSDF_SPECULAR != 0 {
            sub.scatter(p, true, cos_out, 0.0, 0.0, false);
            specular_first |= diffuse == 0;
            smp.weight * (adjoint / q)
        } else {
            let (pdf, reverse) = lobe_pdfs(&b, wo, smp.wi);
            if pdf <= 0.0 {
                break;
            }
            sub.scatter(p, false, cos_out, pdf, reverse, mergeable(&b));
            diffuse += 1;
            // The camera's form of the BSDF: wo toward the camera side.
            bsdf_eval(&b, smp.wi, wo) * (cos_out * adjoint / pdf)
        };
        sub.throughput *= factor;
        // Russian roulette on this vertex's own factor (the throughput holds flux, whose scale
        // says nothing about the path's odds).
        if k >= BPT_ROULETTE_DEPTH {
            let survive = factor.max_element().min(PT_ROULETTE_MAX);
            if rand1(path, sample, f.seed, dim + RNG_ROULETTE) >= survive {
                break;
            }
            sub.throughput /= survive;
        }
        if sub.throughput == Vec3::ZERO {
            break;
        }
        if next.scattered {
            skip = NO_LIGHT;
        } else {
            skip = ray_skip(s, prim);
            if smp.flags & BSDF_TRANSMISSION != 0 {
                medium = medium_after(s, prim, h.ng, smp.wi, medium);
            }
        }
        o = offset_origin(&h, wo, smp.flags);
        d = smp.wi;
    }
    (rays, stored)
}

/// The scattering vertex a ray (`o`, `d`) reached at distance `t`, with its BSDF: a collision
/// in `medium` (`scattered`, the phase function) or the surface of hit name `prim`.
fn vertex_at<'a>(
    s: &SceneView<'a>,
    scattered: bool,
    prim: u32,
    medium: u32,
    o: Vec3,
    d: Vec3,
    t: f32,
) -> (Hit, Bsdf<'a>) {
    if scattered {
        (medium_hit(o + d * t, -d), phase_bsdf(s, medium, -d))
    } else {
        let h = shape_hit(s, prim, o, d, t);
        let b = material_bsdf(s, &s.materials[h.material as usize], &h);
        (h, b)
    }
}

/// Light tracing: the light vertex at `h` seen by the camera, as (film point, value) when nothing
/// is in the way (SmallVCM's ConnectToCamera); `film_footprint` spreads it.
#[allow(clippy::too_many_arguments)]
fn connect_to_camera(
    s: &SceneView,
    p: &VcmParams,
    h: &Hit,
    b: &Bsdf,
    wo: Vec3,
    sub: &SubPath,
    skip: u32,
    at: VertexMedium,
    lens_u: [f32; 2],
    numbers: SegmentNumbers,
    rays: &mut u32,
) -> Option<(Vec2, Vec3)> {
    let f = s.frame;
    let eye = camera_point(f, h.p, lens_u);
    let film = camera_film(f, h.p, eye).filter(|&film| film_reaches_image(f, film))?;
    let to_eye = eye - h.p;
    let dist2 = to_eye.length_squared();
    let dist = dist2.sqrt();
    let dir = to_eye / dist;
    let fr = bsdf_eval(b, dir, wo);
    if fr == Vec3::ZERO {
        return None;
    }
    let image_to_surface = camera_area_pdf(f, -dir, dist2, abs_cos(b, dir));
    let w_light = if has(p, VCM_LIGHT_TRACE_ONLY) {
        0.0
    } else {
        // The density of a camera path arriving from the camera continuing toward the light.
        let (toward_light, _) = lobe_pdfs(b, dir, wo);
        wmul(
            mis(image_to_surface / p.light_paths as f32),
            (if merges_at_first_vertex(p, f) { merge_weight(p, b) } else { 0.0 })
                + sub.d_vcm
                + wmul(sub.d_vc, mis(toward_light)),
        )
    };
    let adjoint = shading_adjoint(b, wo, dir);
    let value = sub.throughput * fr * (image_to_surface * adjoint / (p.light_paths as f32 * (1.0 + w_light)));
    if value == Vec3::ZERO {
        return None;
    }
    let value = value * visibility(s, h, skip, eye, medium_toward(s, h, at, wo, dir), numbers, rays);
    if value == Vec3::ZERO {
        return None;
    }
    Some((film, value))
}

/// Adds the terms of the camera path of pixel (`px`, `py`) in the sample to `terms` and the rays
/// it casts to `rays`.
#[allow(clippy::too_many_arguments)]
pub fn radiance_vcm(
    s: &SceneView,
    p: &VcmParams,
    stage: &LightStage,
    px: u32,
    py: u32,
    terms: &mut [Vec3; 4],
    rays: &mut u32,
) {
    let f = s.frame;
    let stream = py * f.width + px;
    let sample = p.sample_index;
    let film = film_offset(f, qmc2(stream, sample, f.seed, RNG_PIXEL_X));
    let sx = 2.0 * (px as f32 + film[0]) / f.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * (py as f32 + film[1]) / f.height as f32;
    let (mut o, mut d) = camera_ray(s, sx, sy, lens_sample(s, stream, sample));
    let light_only = has(p, VCM_LIGHT_TRACE_ONLY);
    let merge_only = has(p, VCM_MERGE_ONLY);
    let connect = has(p, VCM_CONNECT);
    let mut sub = SubPath { throughput: Vec3::ONE, d_vcm: camera_d_vcm(f, p.light_paths, d), d_vc: 0.0, d_vm: 0.0 };
    let slots = p.vertex_slots as usize;
    let mut skip = NO_LIGHT;
    let (mut first_specular, mut diffuse, mut specular_after) = (false, 0u32, false);
    let mut specular_path = true;
    let mut medium = f.camera_medium;
    let mut segment = 0u32;
    // The last vertex and the normal light sampling chose its light with there (zero in a
    // medium): emission met is weighed with that choice's probability.
    let (mut prev_x, mut prev_n) = (o, Vec3::ZERO);
    for m in 1..=f.max_depth + 1 {
        let mut medium_emission = Vec3::ZERO;
        let next = next_vertex(
            s,
            o,
            d,
            medium,
            skip,
            (stream, sample),
            RNG_MEDIUM_DOMAIN,
            &mut segment,
            &mut sub.throughput,
            &mut medium_emission,
            rays,
        );
        let layer = path_layer(first_specular, diffuse, specular_after) as usize;
        // Emission the path meets is taken whole when the camera sees it directly; the check
        // techniques take only what they cannot make themselves (emission through delta lobes).
        let single = light_only || merge_only;
        let emission_allowed = !single || specular_path;
        let take_whole = m == 1 || single;
        // The media's own emission: only camera paths gather it (no other technique samples it).
        if emission_allowed {
            terms[layer] += medium_emission;
        }
        let Some(next) = next else {
            break;
        };
        if sub.throughput == Vec3::ZERO {
            break;
        }
        let (prim, t) = (next.prim, next.t);
        (o, medium) = (next.o, next.medium);
        if prim == NO_LIGHT && !next.scattered {
            if !emission_allowed {
                break;
            }
            for (i, l) in s.lights.iter().enumerate().take_while(|(_, l)| l.kind == LIGHT_DISTANT && l.area > 0.0) {
                if d.dot(Vec3::from(l.direction)) <= -l.cos_outer {
                    let w = if take_whole {
                        1.0
                    } else {
                        let emission = l.pick_probability * emission_pdf_at(s, l, d, 1.0, o);
                        emission_weight(&sub, direct_light_pmf(s, i as u32, prev_x, prev_n) / l.area, emission)
                    };
                    terms[layer] += sub.throughput * Vec3::from(l.intensity) * (w / l.area);
                }
            }
            if f.environment != NO_LIGHT {
                let l = &s.lights[f.environment as usize];
                let w = if take_whole {
                    1.0
                } else {
                    let emission = l.pick_probability * emission_pdf_at(s, l, d, 1.0, o);
                    let pmf = direct_light_pmf(s, f.environment, prev_x, prev_n);
                    emission_weight(&sub, pmf * environment_pdf(s, l, d), emission)
                };
                terms[layer] += sub.throughput * environment_radiance(s, l, d) * w;
            }
            break;
        }
        let wo = -d;
        let (h, b) = vertex_at(s, next.scattered, prim, medium, o, d, t);
        // An orthographic camera's first density is by area (`camera_d_vcm`).
        sub.arrive(next.dist, abs_cos(&b, wo), m > 1 || f.camera_kind != CAMERA_ORTHOGRAPHIC);
        // A medium's scattering point has no material (its hit names the medium).
        let cos_l = if next.scattered { 0.0 } else { emitter_cosine(s.materials[h.material as usize].flags, h.ng, wo) };
        if cos_l > 0.0 && emission_allowed {
            let emitted = material_emission(s, &s.materials[h.material as usize], &h);
            if emitted != Vec3::ZERO {
                let hp = hit_primitive(s, prim);
                let light = s.primitives[hp as usize].light;
                let w = if take_whole || light == NO_LIGHT || hp != prim {
                    1.0
                } else {
                    let l = &s.lights[light as usize];
                    let emission = l.pick_probability * emission_pdf(s, l, d, cos_l);
                    emission_weight(&sub, direct_light_pmf(s, light, prev_x, prev_n) / l.area, emission)
                };
                terms[layer] += sub.throughput * emitted * w;
            }
        }
        if m > f.max_depth {
            break;
        }
        let flags = bsdf_flags(&b);
        if flags == 0 {
            break;
        }
        skip = if next.scattered { NO_LIGHT } else { ray_skip(s, prim) };
        let at = VertexMedium { prim, medium };
        let merges = mergeable(&b) && (m > 1 || merges_at_first_vertex(p, f));
        let vm = if merges { p.vm_weight } else { 0.0 };
        let dim = (m - 1) * RNG_DIMS_PER_BOUNCE;
        // The transmittance numbers of this vertex's connections: light sampling, then a slot each.
        let connection = |c: u32| SegmentNumbers {
            stream,
            sample,
            dim: RNG_VCM_TRANSMITTANCE_DOMAIN + ((m - 1) * (slots as u32 + 1) + c) * (MEDIUM_CROSSINGS + 1),
        };
        if flags & BSDF_ESTIMATE != 0 {
            let cam_diffuse = diffuse + 1;
            if connect {
                let (v, layer) = (
                    light_sampling(s, p, &h, &b, wo, &sub, skip, at, stream, dim, connection(0), vm, rays),
                    path_layer(first_specular, cam_diffuse, false),
                );
                terms[layer as usize] += sub.throughput * v;
                // Light vertices drawn by block of light paths (VCM_CONNECTIONS, `pick_light_vertex`).
                let picks = p.connections.min(2);
                let pick = rand4(stream, sample, f.seed, dim + RNG_CONNECT_PICK);
                for k in 0..picks as usize {
                    let u = [pick[2 * k], pick[2 * k + 1]];
                    let Some((slot, weight)) = pick_light_vertex(&stage.path_counts, p.vertex_slots, u) else {
                        continue;
                    };
                    let share = weight / picks as f32;
                    let lv = &stage.vertices[slot];
                    if lv.path_length + m > f.max_depth {
                        continue;
                    }
                    let light = light_surface(s, lv);
                    let v = connect_vertices(
                        s,
                        p,
                        &h,
                        &b,
                        wo,
                        &sub,
                        skip,
                        at,
                        (lv, &light),
                        connection(k as u32 + 1),
                        vm,
                        rays,
                    );
                    let layer = path_layer(
                        first_specular,
                        cam_diffuse + (lv.flags & VERTEX_DIFFUSE_MASK) + 1,
                        lv.flags & VERTEX_SPECULAR_FIRST != 0,
                    );
                    terms[layer as usize] += sub.throughput * v * share;
                }
            }
            if has(p, VCM_MERGE | VCM_MERGE_ONLY) && merges {
                let mut merged = [Vec3::ZERO; 4];
                for_each_photon_near(h.p, &stage.grid, &stage.points, &stage.starts, |pt, _| {
                    let lv = &stage.vertices[(pt.flux_rg as usize) * slots + pt.flux_b_dir as usize];
                    if lv.path_length + m - 1 > f.max_depth {
                        return;
                    }
                    let light_dir = -Vec3::from(lv.direction);
                    let fr = bsdf_eval(&b, wo, light_dir);
                    if fr == Vec3::ZERO {
                        return;
                    }
                    let w = if merge_only {
                        1.0
                    } else {
                        let (forward, reverse) = lobe_pdfs(&b, wo, light_dir);
                        let w_light = wmul(lv.d_vcm, p.vc_weight) + wmul(lv.d_vm, mis(forward));
                        let w_camera = wmul(sub.d_vcm, p.vc_weight) + wmul(sub.d_vm, mis(reverse));
                        1.0 / (w_light + 1.0 + w_camera)
                    };
                    let layer = path_layer(
                        first_specular,
                        cam_diffuse + (lv.flags & VERTEX_DIFFUSE_MASK),
                        lv.flags & VERTEX_SPECULAR_FIRST != 0,
                    );
                    merged[layer as usize] += fr * Vec3::from(lv.throughput) * w;
                });
                for (t, m) in terms.iter_mut().zip(merged) {
                    *t += sub.throughput * m * p.vm_normalization;
                }
                if merge_only {
                    break;
                }
            }
        }
        if light_only && flags & BSDF_ESTIMATE != 0 {
            break;
        }
        // The next path ray.
        let q = bsdf_path_probability(&b, wo);
        let u = bsdf_numbers(stream, sample, (stream, sample), f.seed, dim + RNG_FRESNEL);
        let delta = u[3] < q;
        let smp = bsdf_sample(&b, wo, [u[0], u[1], u[2]], if delta { LOBES_PATH } else { LOBES_ESTIMATE });
        if smp.flags == 0 {
            break;
        }
        let cos_out = abs_cos(&b, smp.wi);
        if smp.flags & BSDF_SPECULAR != 0 {
            sub.scatter(p, true, cos_out, 0.0, 0.0, false);
            first_specular |= m == 1;
            specular_after = diffuse > 0;
            sub.throughput *= smp.weight / q;
        } else {
            let (pdf, reverse) = lobe_pdfs(&b, wo, smp.wi);
            if pdf <= 0.0 {
                break;
            }
            sub.scatter(p, false, cos_out, pdf, reverse, merges);
            diffuse += 1;
            specular_after = false;
            specular_path = false;
            sub.throughput *= smp.weight / (1.0 - q);
        }
        if m >= BPT_ROULETTE_DEPTH {
            let survive = sub.throughput.max_element().min(PT_ROULETTE_MAX);
            if rand1(stream, sample, f.seed, dim + RNG_ROULETTE) >= survive {
                break;
            }
            sub.throughput /= survive;
        }
        if sub.throughput == Vec3::ZERO {
            break;
        }
        if !next.scattered && smp.flags & BSDF_TRANSMISSION != 0 {
            medium = medium_after(s, prim, h.ng, smp.wi, medium);
        }
        (prev_x, prev_n) = (h.p, receiver_normal(&b));
        o = offset_origin(&h, wo, smp.flags);
        d = smp.wi;
    }
    // The light tracing that landed on this pixel.
    for (t, v) in terms.iter_mut().zip(stage.splat_terms(stream)) {
        *t += v;
    }
}

/// The weight of emission met by a camera sub-path, from the light's densities `direct` (light
/// sampling: by area for finite lights, by solid angle for infinite ones) and `emission` (a
/// light sub-path leaving it the same way), pick probability included.
fn emission_weight(sub: &SubPath, direct: f32, emission: f32) -> f32 {
    1.0 / (1.0 + wmul(mis(direct), sub.d_vcm) + wmul(mis(emission), sub.d_vc))
}

/// Light sampling at a camera vertex (SmallVCM's DirectIllumination): the weighed contribution
/// (before the camera throughput) when nothing blocks the light.
#[allow(clippy::too_many_arguments)]
fn light_sampling(
    s: &SceneView,
    p: &VcmParams,
    h: &Hit,
    b: &Bsdf,
    wo: Vec3,
    sub: &SubPath,
    skip: u32,
    at: VertexMedium,
    stream: u32,
    dim: u32,
    numbers: SegmentNumbers,
    vm: f32,
    rays: &mut u32,
) -> Vec3 {
    let f = s.frame;
    if f.light_count == 0 {
        return Vec3::ZERO;
    }
    let sample = p.sample_index;
    let u_pick = rand1(stream, sample, f.seed, dim + RNG_LIGHT_PICK);
    let (light, pmf) = pick_direct_light(s, u_pick, h.p, receiver_normal(b));
    if pmf <= 0.0 {
        return Vec3::ZERO;
    }
    let l = &s.lights[light as usize];
    let ul = qmc2(stream, sample, f.seed, dim + RNG_LIGHT_U);
    let ls = light_sample(s, l, h.p, grid_sample(l.grid, ul, stream, sample));
    let cos_to_light = abs_cos(b, ls.wi);
    let fr = bsdf_eval(b, wo, ls.wi) * ls.weight * cos_to_light;
    if fr == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let dist = (ls.p - h.p).length();
    let (direct, emission, cos_at_light) = illumination_pdfs(s, l, h.p, ls.wi, dist, ls.pdf, ls.cos_l);
    if direct <= 0.0 {
        // A direction the light's own sampling gives no density (an environment texel of zero
        // weight met under rounding): light sampling did not make it, and 0 / 0 would be NaN.
        return Vec3::ZERO;
    }
    let (forward, reverse) = lobe_pdfs(b, wo, ls.wi);
    let forward = if light_is_delta(l) { 0.0 } else { forward };
    let w_light = mis(forward / (pmf * direct));
    // Emission chooses its light by power, light sampling by the tree.
    let emission = emission * l.pick_probability;
    let w_camera = wmul(
        mis(emission * cos_to_light / (pmf * direct * cos_at_light)),
        vm + sub.d_vcm + wmul(sub.d_vc, mis(reverse)),
    );
    let w = 1.0 / (w_light + 1.0 + w_camera);
    // The shadow ray runs to the sampled point itself, stopping short by the sample's own offset.
    let origin = offset_origin(h, ls.wi, BSDF_REFLECTION);
    let to_target = ls.p - origin;
    let length = to_target.length();
    let medium = medium_toward(s, h, at, wo, ls.wi);
    let tr = transmittance(s, origin, to_target / length, (length - ls.eps).max(0.0), medium, skip, numbers, rays);
    if tr == Vec3::ZERO {
        return Vec3::ZERO;
    }
    fr * (w / pmf) * tr
}

/// A camera vertex joined to light vertex `lv` (SmallVCM's ConnectVertices): the weighed
/// contribution (before the camera throughput) when nothing is in the way.
#[allow(clippy::too_many_arguments)]
fn connect_vertices(
    s: &SceneView,
    p: &VcmParams,
    h: &Hit,
    b: &Bsdf,
    wo: Vec3,
    sub: &SubPath,
    skip: u32,
    at: VertexMedium,
    (lv, light): (&LightVertex, &LightSurface),
    numbers: SegmentNumbers,
    vm: f32,
    rays: &mut u32,
) -> Vec3 {
    let lb = light.bsdf;
    let to_light = light.p - h.p;
    let dist2 = to_light.length_squared();
    if dist2 <= 0.0 {
        return Vec3::ZERO;
    }
    let dist = dist2.sqrt();
    let dir = to_light / dist;
    let fc = bsdf_eval(b, wo, dir);
    if fc == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let l_wo = -Vec3::from(lv.direction);
    let fl = bsdf_eval(&lb, -dir, l_wo);
    if fl == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let (cos_cam, cos_light) = (abs_cos(b, dir), abs_cos(&lb, dir));
    let g = cos_cam * cos_light / dist2;
    let (cam_forward, cam_reverse) = lobe_pdfs(b, wo, dir);
    let (light_forward, light_reverse) = lobe_pdfs(&lb, l_wo, -dir);
    // Densities by area at the other end.
    let cam_to_area = cam_forward * cos_light / dist2;
    let light_to_area = light_forward * cos_cam / dist2;
    let w_light = wmul(mis(cam_to_area), merge_weight(p, &lb) + lv.d_vcm + wmul(lv.d_vc, mis(light_reverse)));
    let w_camera = wmul(mis(light_to_area), vm + sub.d_vcm + wmul(sub.d_vc, mis(cam_reverse)));
    let w = 1.0 / (w_light + 1.0 + w_camera);
    let value = fc * fl * Vec3::from(lv.throughput) * (g * w * shading_adjoint(&lb, l_wo, -dir));
    if value == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let target = light.p + (h.p - light.p).normalize() * light.eps;
    value * visibility(s, h, skip, target, medium_toward(s, h, at, wo, dir), numbers, rays)
}

/// Adds the camera stage of `range` (one sample) to `accumulation`, as one dispatch of the
/// kernel does.
pub fn render_vcm(
    s: &SceneView,
    p: &VcmParams,
    stage: &LightStage,
    range: &DispatchRange,
    accumulation: &mut [[f32; 4]],
) {
    super::pixel_list::for_each_pixel(s.frame.width, range, s.pixel_list, accumulation, |px, py, acc| {
        let mut terms = [Vec3::ZERO; 4];
        let mut rays = 0;
        radiance_vcm(s, p, stage, px, py, &mut terms, &mut rays);
        for (layer, term) in acc.iter_mut().zip(terms) {
            layer[0] += term.x;
            layer[1] += term.y;
            layer[2] += term.z;
        }
        acc[LAYER_DIRECT as usize][3] += rays as f32;
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::shading::film_offset;

    fn frame(filter: u32, scale: f32) -> FrameParams {
        FrameParams { width: 16, height: 12, pixel_filter: filter, filter_scale: scale, ..FrameParams::default() }
    }

    #[test]
    fn film_footprint_shares_a_splat_out_exactly() {
        // Inside the image a box's and a tent's shares sum to 1 at every film point (their pixel
        // centres tile the plane), so light tracing neither gains nor loses energy. A Gaussian
        // of 0.5 pixel sampled at whole pixels sums to 1 + 2 exp(-2 pi^2 sigma^2) cos(2 pi x)
        // per axis (Poisson summation: within 1.5%), 1 on average over the pixel: each pixel is
        // still the filtered image at its centre, as camera samples drawn from the filter make it.
        // Stretched filters (`filter_radius`) need not sum to 1 pointwise, but still do on average.
        for (filter, scale) in [FILTER_BOX, FILTER_TENT, FILTER_GAUSSIAN]
            .into_iter()
            .flat_map(|filter| [(filter, 1.0), (filter, 0.75), (filter, 2.5)])
        {
            let f = frame(filter, scale);
            let (mut total, mut n) = (0.0f64, 0);
            for i in 0..16 {
                for j in 0..16 {
                    let (x, y) = (5.0 + (i as f32 + 0.5) / 16.0, 4.0 + (j as f32 + 0.5) / 16.0);
                    let sum: f32 = film_footprint(&f, Vec2::new(x, y)).iter().map(|&(_, w)| w).sum();
                    let bound = if filter == FILTER_GAUSSIAN { 0.03 } else { 1e-5 };
                    if scale == 1.0 {
                        assert!((sum - 1.0).abs() < bound, "filter {filter} at ({x}, {y}): shares sum to {sum}");
                    }
                    total += sum as f64;
                    n += 1;
                }
            }
            let mean = total / n as f64;
            let bound = if scale == 1.0 { 1e-3 } else { 3e-3 };
            assert!((mean - 1.0).abs() < bound, "filter {filter} x {scale}: shares average {mean} over a pixel");
        }
    }

    #[test]
    fn camera_samples_land_where_splats_spread() {
        // The camera's film points of pixel P, drawn by film_offset, must have the density that
        // film_footprint gives P at each point: histograms of 2^20 samples in cells of 1/8 pixel
        // against the filter's weight integrated over each cell.
        for (filter, scale) in
            [(FILTER_TENT, 1.0), (FILTER_GAUSSIAN, 1.0), (FILTER_BOX, 1.5), (FILTER_TENT, 0.6), (FILTER_GAUSSIAN, 1.75)]
        {
            let f = frame(filter, scale);
            let r = crate::cpu::shading::filter_radius(&f);
            let cells = (2.0 * r * 8.0) as usize;
            let mut hist = vec![0u32; cells];
            let n = 1u32 << 20;
            for i in 0..n {
                let u = crate::cpu::rng::pcg4d([i, 7, 11, 13]).map(crate::cpu::rng::rand_unit);
                let x = film_offset(&f, [u[0], u[1]])[0] - 0.5;
                let c = ((x + r) * 8.0).floor();
                if c >= 0.0 && (c as usize) < cells {
                    hist[c as usize] += 1;
                }
            }
            for (c, &count) in hist.iter().enumerate() {
                let x0 = c as f32 / 8.0 - r;
                let want: f32 =
                    (0..64).map(|k| crate::cpu::shading::filter_weight(&f, x0 + (k as f32 + 0.5) / 512.0)).sum::<f32>()
                        / 512.0;
                let got = count as f32 / n as f32;
                assert!(
                    (got - want).abs() < 4.0 * (want / n as f32).sqrt() + 1e-5,
                    "filter {filter}, cell at {x0}: sampled {got} against {want}"
                );
            }
        }
    }
}
