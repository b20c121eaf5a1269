//! Materials as BSDFs: every material kind, one match per operation; twin of `shaders/bsdf.glsl`.
//! Directions point away from the surface: `wo` toward the previous vertex (the viewer), `wi`
//! toward the next one. The path loops never ask which kind they hold, only what its lobes are:
//! `BSDF_ESTIMATE` lobes end a camera path (light sampling, photon lookups, final gather) and
//! store photons; `BSDF_PATH` lobes are followed.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::microfacet::{
    conductor_eval, conductor_pdf, conductor_sample, dielectric_eval, dielectric_pdf, dielectric_sample,
    mf_cosine_direction, mf_fresnel_dielectric, mf_is_smooth, mf_plastic_coat_probability, plastic_eval, plastic_pdf,
    plastic_sample, MfSample, PlasticCoat, MF_TRANSMISSION,
};
use super::phase::{phase_hg, phase_hg_sample};
use super::rng::{pcg4d, rand_unit};
use super::sampling::{cosine_direction, onb, reflect};
use super::shape::Hit;
use super::texture::{bump_normal, normal_map_normal, param_color, param_scalar, texture_eval};
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Material;

/// A material evaluated at one surface point: its textures looked up, its frame set.
#[derive(Clone, Copy, Debug, Default)]
pub struct Bsdf<'a> {
    pub kind: u32,
    /// The material's `MATERIAL_FLAG_*`.
    pub flags: u32,
    /// The material's `data` (a rough nonlinear plastic's coat table) in `words`, the scene's
    /// texture data (the GLSL reads it from its binding).
    pub data: u32,
    pub words: &'a [u32],
    pub color0: Vec3,
    pub color1: Vec3,
    /// A conductor's tint.
    pub color2: Vec3,
    pub alpha: Vec2,
    pub ior: f32,
    /// The normal that decides sides (reflection or transmission, leaks, the dielectric's inside):
    /// the geometric normal (a triangle's winding side, a sphere's outside), or on a smooth
    /// triangle its interpolated normal, so its BSDF sees the curved surface the vertex normals
    /// describe (no flat terminator band where the light is below the facet but above the
    /// shading normal's horizon, and glass refracts smoothly).
    pub ng: Vec3,
    /// Shading normal, on the side of `ng`.
    pub ns: Vec3,
    /// Direction of the first GGX width (dpdu; zero without uv: any tangent).
    pub ts: Vec3,
    /// Glossy lobes are path lobes (GGX width <= `frame.glossy_threshold`).
    pub glossy_path: bool,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f |cos| / pdf of the lobes sampled from.
    pub weight: Vec3,
    /// 0 for a specular (delta) lobe.
    pub pdf: f32,
    /// `BSDF_*` flags of the lobe sampled; 0 when no direction was sampled.
    pub flags: u32,
}

/// Radiance the material emits at `h` toward its front side.
pub fn material_emission(s: &SceneView, m: &Material, h: &Hit) -> Vec3 {
    param_color(s, m.emission, m.emission_tex, h)
}

/// A number in [0, 1) fixed for each point of space and key: a hash of the point's cell in a
/// grid of 4 ray offsets. Stochastic alpha and mixes decide by it, so camera rays, shadow rays
/// and photons see the same surface at the same point; the cell, not the point's bits, is
/// hashed, since the GPU and the CPU round a hit point differently in its last bits.
pub fn hash_point(s: &SceneView, p: Vec3, key: u32) -> f32 {
    let c = (p / (4.0 * s.frame.ray_epsilon)).floor().as_ivec3();
    rand_unit(pcg4d([c.x as u32, c.y as u32, c.z as u32, key])[0])
}

pub fn material_bsdf<'a>(s: &SceneView<'a>, m: &Material, h: &Hit) -> Bsdf<'a> {
    let mut m = m;
    let mut level = 0;
    while level < MIX_MAX_DEPTH && m.kind == MATERIAL_MIX {
        let pick =
            if hash_point(s, h.p, level) < param_scalar(s, m.weight, m.weight_tex, h) { m.mix_b } else { m.mix_a };
        m = &s.materials[pick as usize];
        level += 1;
    }
    let mut alpha = Vec2::from(m.roughness);
    if m.roughness_tex != NO_TEXTURE {
        alpha *= texture_eval(s, m.roughness_tex, h).x;
    }
    Bsdf {
        kind: m.kind,
        flags: m.flags,
        data: m.data,
        words: s.texture_data,
        color0: param_color(s, m.color0, m.color0_tex, h),
        color1: param_color(s, m.color1, m.color1_tex, h),
        color2: param_color(s, m.color2, m.color2_tex, h),
        alpha,
        ior: m.ior,
        ng: h.ns,
        // Bump and normal maps change the shading normal only: `ng` keeps deciding sides and
        // leaks, and the hit's own `ng` the ray offsets.
        ns: if m.bump_tex != NO_TEXTURE {
            bump_normal(s, m.bump_tex, m.bump_strength, h)
        } else if m.normal_tex != NO_TEXTURE {
            normal_map_normal(s, m.normal_tex, h)
        } else {
            h.ns
        },
        ts: h.dpdu,
        glossy_path: alpha.max_element() <= s.frame.glossy_threshold,
    }
}

/// The factor that makes a light path's scattering the adjoint of the camera's where a bump or
/// normal map bends the shading normal away from `ng` (Veach 1997, 5.3; pbrt's
/// `CorrectShadingNormal`): |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|), with `wo` toward the light side
/// and `wi` the direction the light leaves along. Exactly 1 where the two normals are one, so
/// unbumped surfaces are untouched; 0 at a grazing geometric angle.
pub fn shading_adjoint(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    if b.kind == MATERIAL_PHASE || b.ns == b.ng {
        return 1.0;
    }
    let den = wo.dot(b.ng).abs() * wi.dot(b.ns).abs();
    if den <= 0.0 {
        return 0.0;
    }
    wo.dot(b.ns).abs() * wi.dot(b.ng).abs() / den
}

/// The shading normal turned to the side of `w`.
pub fn facing(b: &Bsdf, w: Vec3) -> Vec3 {
    if w.dot(b.ng) > 0.0 {
        b.ns
    } else {
        -b.ns
    }
}

// Diffuse: Lambertian reflection of albedo color0 on both sides.

/// Reflection needs `wi` on `wo`'s side of the shading normal and of the geometric one, so a
/// bumped normal cannot let light in from under the surface.
pub fn same_side(b: &Bsdf, wo: Vec3, wi: Vec3) -> bool {
    wi.dot(facing(b, wo)) > 0.0 && wi.dot(b.ng) * wo.dot(b.ng) > 0.0
}

pub fn diffuse_eval(b: &Bsdf, wo: Vec3, wi: Vec3) -> Vec3 {
    if same_side(b, wo, wi) {
        b.color0 * (1.0 / PI)
    } else {
        Vec3::ZERO
    }
}

pub fn diffuse_pdf(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    if same_side(b, wo, wi) {
        wi.dot(facing(b, wo)) * (1.0 / PI)
    } else {
        0.0
    }
}

pub fn diffuse_sample(b: &Bsdf, wo: Vec3, u: [f32; 3]) -> BsdfSample {
    let n = facing(b, wo);
    let wi = cosine_direction(n, [u[1], u[2]]);
    if !same_side(b, wo, wi) {
        return BsdfSample::default();
    }
    // Cosine sampling cancels the cosine and the 1/pi: the weight is the albedo.
    BsdfSample {
        wi,
        weight: b.color0,
        pdf: wi.dot(n).max(0.0) * (1.0 / PI),
        flags: BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE,
    }
}

// Mirror: perfect reflection tinted by color0, on both sides.

pub fn mirror_sample(b: &Bsdf, wo: Vec3) -> BsdfSample {
    BsdfSample {
        wi: reflect(-wo, facing(b, wo)),
        weight: b.color0,
        pdf: 0.0,
        flags: BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH,
    }
}

/// Thin dielectric: a pane of index `ior` (Mitsuba's `thindielectric`). Its reflectance sums the
/// light bouncing inside the pane, R' = R + T² R / (1 - R²) with T = 1 - R (incoherently: the
/// pane is thick beside the wavelength); the rest passes straight through, as the two parallel
/// faces of a pane return a ray to its direction (the small sideways shift is neglected).
/// Chosen against `u[0]`, weight 1: the pane absorbs nothing.
pub fn thin_dielectric_sample(b: &Bsdf, wo: Vec3, u: [f32; 3]) -> BsdfSample {
    let n = facing(b, wo);
    let (mut r, _) = mf_fresnel_dielectric(wo.dot(n).abs(), 1.0, b.ior);
    if r < 1.0 {
        r += (1.0 - r) * (1.0 - r) * r / (1.0 - r * r);
    }
    if u[0] < r {
        return BsdfSample {
            wi: reflect(-wo, n),
            weight: Vec3::ONE,
            pdf: 0.0,
            flags: BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH,
        };
    }
    BsdfSample { wi: -wo, weight: Vec3::ONE, pdf: 0.0, flags: BSDF_SPECULAR | BSDF_TRANSMISSION | BSDF_PATH }
}

/// Dielectric: smooth interface of index `ior` inside (the side opposite `ng`), reflection or
/// refraction chosen with the Fresnel probability against `u[0]`, weight 1.
pub fn smooth_dielectric_sample(b: &Bsdf, wo: Vec3, u: [f32; 3]) -> BsdfSample {
    let d = -wo;
    let front = b.ng.dot(d) < 0.0;
    let nf = if front { b.ng } else { -b.ng };
    let (eta_i, eta_t) = if front { (1.0, b.ior) } else { (b.ior, 1.0) };
    let cos_i = -d.dot(nf);
    let (fr, cos_t) = mf_fresnel_dielectric(cos_i, eta_i, eta_t);
    if u[0] < fr {
        return BsdfSample {
            wi: reflect(d, nf),
            weight: Vec3::ONE,
            pdf: 0.0,
            flags: BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH,
        };
    }
    let eta = eta_i / eta_t;
    BsdfSample {
        wi: (eta * d + (eta * cos_i - cos_t) * nf).normalize(),
        weight: Vec3::ONE,
        pdf: 0.0,
        flags: BSDF_SPECULAR | BSDF_TRANSMISSION | BSDF_PATH,
    }
}

/// The local frame of `b` around normal `n` (x along `ts` where it is known).
pub fn bsdf_frame(b: &Bsdf, n: Vec3) -> (Vec3, Vec3) {
    let tt = b.ts - n * n.dot(b.ts);
    if tt.dot(tt) > 1e-12 {
        let t = tt.normalize();
        (t, n.cross(t))
    } else {
        onb(n)
    }
}

/// `v` in the frame (t, bt, n), and back.
pub fn to_local(v: Vec3, (t, bt, n): (Vec3, Vec3, Vec3)) -> Vec3 {
    Vec3::new(v.dot(t), v.dot(bt), v.dot(n))
}

pub fn to_world(v: Vec3, (t, bt, n): (Vec3, Vec3, Vec3)) -> Vec3 {
    v.x * t + v.y * bt + v.z * n
}

fn frame_around(b: &Bsdf, n: Vec3) -> (Vec3, Vec3, Vec3) {
    let (t, bt) = bsdf_frame(b, n);
    (t, bt, n)
}

pub fn is_smooth(b: &Bsdf) -> bool {
    mf_is_smooth(b.alpha)
}

/// A microfacet sample as a `BsdfSample`: `rough` lobe flags unless its pdf is 0 (a delta).
fn microfacet_result(sample: Option<MfSample>, frame: (Vec3, Vec3, Vec3), rough: u32) -> BsdfSample {
    let Some(m) = sample else {
        return BsdfSample::default();
    };
    let side = if m.lobe == MF_TRANSMISSION { BSDF_TRANSMISSION } else { BSDF_REFLECTION };
    let kind = if m.pdf == 0.0 { BSDF_SPECULAR | BSDF_PATH } else { rough };
    BsdfSample { wi: to_world(m.wi, frame), weight: m.weight, pdf: m.pdf, flags: kind | side }
}

/// The flags of a glossy lobe: followed by paths up to the threshold, an estimate lobe above it.
pub fn glossy_flags(b: &Bsdf) -> u32 {
    BSDF_GLOSSY | if b.glossy_path { BSDF_PATH } else { BSDF_ESTIMATE }
}

fn same_geometric_side(b: &Bsdf, wo: Vec3, wi: Vec3) -> bool {
    wi.dot(b.ng) * wo.dot(b.ng) > 0.0
}

/// The microfacet distribution of a rough material (`MICROFACET_*`, from its flags).
pub fn microfacet_dist(b: &Bsdf) -> u32 {
    if b.flags & MATERIAL_FLAG_BECKMANN != 0 {
        MICROFACET_BECKMANN
    } else {
        MICROFACET_GGX
    }
}

// Conductor: GGX or Beckmann metal with complex index color0 + i color1, reflecting on both
// sides.

pub fn conductor_bsdf_eval(b: &Bsdf, wo: Vec3, wi: Vec3) -> Vec3 {
    if !same_geometric_side(b, wo, wi) {
        return Vec3::ZERO;
    }
    let f = frame_around(b, facing(b, wo));
    b.color2 * conductor_eval(to_local(wo, f), to_local(wi, f), b.alpha, microfacet_dist(b), b.color0, b.color1)
}

pub fn conductor_bsdf_pdf(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    if !same_geometric_side(b, wo, wi) {
        return 0.0;
    }
    let f = frame_around(b, facing(b, wo));
    conductor_pdf(to_local(wo, f), to_local(wi, f), b.alpha, microfacet_dist(b))
}

pub fn conductor_bsdf_sample(b: &Bsdf, wo: Vec3, u: [f32; 3]) -> BsdfSample {
    let f = frame_around(b, facing(b, wo));
    let m = conductor_sample(to_local(wo, f), b.alpha, microfacet_dist(b), b.color0, b.color1, Vec2::new(u[1], u[2]))
        .map(|m| MfSample { weight: b.color2 * m.weight, ..m });
    let smp = microfacet_result(m, f, glossy_flags(b));
    if !same_geometric_side(b, wo, smp.wi) {
        return BsdfSample::default();
    }
    smp
}

// Rough dielectric: GGX or Beckmann reflection and refraction (the smooth one is `smooth_dielectric_sample`).

pub fn rough_dielectric_eval(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    let f = frame_around(b, b.ns);
    dielectric_eval(to_local(wo, f), to_local(wi, f), b.alpha, microfacet_dist(b), b.ior)
}

pub fn rough_dielectric_pdf(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    let f = frame_around(b, b.ns);
    dielectric_pdf(to_local(wo, f), to_local(wi, f), b.alpha, microfacet_dist(b), b.ior)
}

pub fn rough_dielectric_sample(b: &Bsdf, wo: Vec3, u: [f32; 3]) -> BsdfSample {
    let f = frame_around(b, b.ns);
    let m = dielectric_sample(to_local(wo, f), b.alpha, microfacet_dist(b), b.ior, Vec3::from(u))
        .map(|m| MfSample { weight: m.weight * b.color0, ..m });
    microfacet_result(m, f, glossy_flags(b))
}

// Plastic: diffuse base color0 under a dielectric coat of index ior, on both sides. A smooth
// coat is a path lobe (a delta); a rough coat is read with the base as an estimate lobe.

/// The plastic's coat: `MATERIAL_FLAG_NONLINEAR` and its table (`data`) in the texture data.
pub fn plastic_coat<'a>(b: &Bsdf<'a>) -> PlasticCoat<'a> {
    PlasticCoat { nonlinear: b.flags & MATERIAL_FLAG_NONLINEAR != 0, words: b.words, table: b.data }
}

pub fn plastic_bsdf_eval(b: &Bsdf, wo: Vec3, wi: Vec3) -> Vec3 {
    if !same_geometric_side(b, wo, wi) {
        return Vec3::ZERO;
    }
    let f = frame_around(b, facing(b, wo));
    plastic_eval(to_local(wo, f), to_local(wi, f), b.alpha, microfacet_dist(b), b.ior, b.color0, &plastic_coat(b))
}

pub fn plastic_bsdf_pdf(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    if !same_geometric_side(b, wo, wi) {
        return 0.0;
    }
    let f = frame_around(b, facing(b, wo));
    let (wo_l, wi_l) = (to_local(wo, f), to_local(wi, f));
    // With a smooth coat the estimate lobe is the base alone, sampled by cosine.
    if is_smooth(b) {
        wi_l.z.max(0.0) * (1.0 / PI)
    } else {
        plastic_pdf(wo_l, wi_l, b.alpha, microfacet_dist(b), b.ior, b.color0)
    }
}

pub fn plastic_coat_probability(b: &Bsdf, wo: Vec3) -> f32 {
    let f = frame_around(b, facing(b, wo));
    mf_plastic_coat_probability(to_local(wo, f), b.ior, b.color0)
}

pub fn plastic_bsdf_sample(b: &Bsdf, wo: Vec3, u: [f32; 3], lobes: u32) -> BsdfSample {
    let n = facing(b, wo);
    let f = frame_around(b, n);
    let wo_l = to_local(wo, f);
    if is_smooth(b) && lobes == LOBES_PATH {
        // The coat alone: a mirror weighted by its Fresnel reflectance.
        let (fr, _) = mf_fresnel_dielectric(wo_l.z, 1.0, b.ior);
        return BsdfSample {
            wi: reflect(-wo, n),
            weight: Vec3::splat(fr),
            pdf: 0.0,
            flags: BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH,
        };
    }
    if is_smooth(b) && lobes == LOBES_ESTIMATE {
        // The base alone, by cosine: weight f cos / pdf = pi f.
        let wi_l = mf_cosine_direction(Vec2::new(u[1], u[2]));
        let fr = plastic_eval(wo_l, wi_l, b.alpha, microfacet_dist(b), b.ior, b.color0, &plastic_coat(b));
        let smp = BsdfSample {
            wi: to_world(wi_l, f),
            weight: PI * fr,
            pdf: wi_l.z * (1.0 / PI),
            flags: BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE,
        };
        return if same_geometric_side(b, wo, smp.wi) && wi_l.z > 0.0 { smp } else { BsdfSample::default() };
    }
    let m = plastic_sample(wo_l, b.alpha, microfacet_dist(b), b.ior, b.color0, &plastic_coat(b), Vec3::from(u));
    let smp = microfacet_result(m, f, BSDF_GLOSSY | BSDF_DIFFUSE | BSDF_ESTIMATE);
    if !same_geometric_side(b, wo, smp.wi) {
        return BsdfSample::default();
    }
    smp
}

/// A medium's scattering point scatters into every direction and ends camera paths (light
/// sampling, the volume photon map) like a diffuse surface.
pub const PHASE_FLAGS: u32 = BSDF_GLOSSY | BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_ESTIMATE;

/// The lobes of `b` (`BSDF_*` flags); 0 for a black surface, which ends paths (its photons are
/// stored for its neighbours' lookups, see `emit_photons`).
pub fn bsdf_flags(b: &Bsdf) -> u32 {
    match b.kind {
        MATERIAL_DIFFUSE if b.color0 == Vec3::ZERO => 0,
        MATERIAL_DIFFUSE => BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE,
        MATERIAL_MIRROR => BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH,
        MATERIAL_DIELECTRIC => {
            BSDF_REFLECTION | BSDF_TRANSMISSION | if is_smooth(b) { BSDF_SPECULAR | BSDF_PATH } else { glossy_flags(b) }
        }
        MATERIAL_CONDUCTOR => BSDF_REFLECTION | if is_smooth(b) { BSDF_SPECULAR | BSDF_PATH } else { glossy_flags(b) },
        MATERIAL_PLASTIC => {
            let coat = if is_smooth(b) { BSDF_SPECULAR | BSDF_PATH } else { BSDF_GLOSSY | BSDF_ESTIMATE };
            let base = if b.color0 == Vec3::ZERO { 0 } else { BSDF_DIFFUSE | BSDF_ESTIMATE };
            BSDF_REFLECTION | coat | base
        }
        MATERIAL_PHASE => PHASE_FLAGS,
        MATERIAL_THIN_DIELECTRIC => BSDF_SPECULAR | BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_PATH,
        _ => 0, // unreachable: the host packs only known kinds (tested)
    }
}

/// Probability that a camera path seen from `wo` follows the path lobes rather than ending in the
/// estimate lobes: 0 for a surface with estimate lobes alone, 1 for path lobes alone.
pub fn bsdf_path_probability(b: &Bsdf, wo: Vec3) -> f32 {
    let flags = bsdf_flags(b);
    if flags & BSDF_PATH == 0 {
        return 0.0;
    }
    if flags & BSDF_ESTIMATE == 0 {
        return 1.0;
    }
    // Both: a smooth plastic; its coat is chosen as the plastic's own sampling chooses it.
    plastic_coat_probability(b, wo)
}

/// True when the estimate lobes have the same value for every `wi` on `wo`'s side (Lambertian),
/// so a photon estimate may sum the irradiance first and apply the BSDF once.
pub fn bsdf_estimate_is_constant(b: &Bsdf) -> bool {
    b.kind == MATERIAL_DIFFUSE
}

/// f(wo, wi) of the estimate lobes, without the cosine; 0 for path lobes (they are sampled).
pub fn bsdf_eval(b: &Bsdf, wo: Vec3, wi: Vec3) -> Vec3 {
    if bsdf_flags(b) & BSDF_ESTIMATE == 0 {
        return Vec3::ZERO;
    }
    match b.kind {
        MATERIAL_DIFFUSE => diffuse_eval(b, wo, wi),
        MATERIAL_DIELECTRIC => b.color0 * rough_dielectric_eval(b, wo, wi),
        MATERIAL_CONDUCTOR => conductor_bsdf_eval(b, wo, wi),
        MATERIAL_PLASTIC => plastic_bsdf_eval(b, wo, wi),
        MATERIAL_PHASE => Vec3::splat(phase_hg(wo.dot(wi), b.ior)),
        _ => Vec3::ZERO,
    }
}

/// Solid-angle pdf of `bsdf_sample(.., LOBES_ESTIMATE)` choosing `wi`.
pub fn bsdf_pdf(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    if bsdf_flags(b) & BSDF_ESTIMATE == 0 {
        return 0.0;
    }
    match b.kind {
        MATERIAL_DIFFUSE => diffuse_pdf(b, wo, wi),
        MATERIAL_DIELECTRIC => rough_dielectric_pdf(b, wo, wi),
        MATERIAL_CONDUCTOR => conductor_bsdf_pdf(b, wo, wi),
        MATERIAL_PLASTIC => plastic_bsdf_pdf(b, wo, wi),
        MATERIAL_PHASE => phase_hg(wo.dot(wi), b.ior),
        _ => 0.0,
    }
}

/// A direction from the lobes in `lobes` (`LOBES_*`): `u[0]` picks among lobes (or Fresnel),
/// `u[1..]` place the direction. The weight is that of the chosen lobes alone; a sample with
/// flags 0 when `b` has none of them.
pub fn bsdf_sample(b: &Bsdf, wo: Vec3, u: [f32; 3], lobes: u32) -> BsdfSample {
    if bsdf_flags(b) & lobes == 0 {
        return BsdfSample::default();
    }
    match b.kind {
        MATERIAL_DIFFUSE => diffuse_sample(b, wo, u),
        MATERIAL_MIRROR => mirror_sample(b, wo),
        MATERIAL_DIELECTRIC if is_smooth(b) => smooth_dielectric_sample(b, wo, u),
        MATERIAL_DIELECTRIC => rough_dielectric_sample(b, wo, u),
        MATERIAL_CONDUCTOR => conductor_bsdf_sample(b, wo, u),
        MATERIAL_PLASTIC => plastic_bsdf_sample(b, wo, u, lobes),
        MATERIAL_THIN_DIELECTRIC => thin_dielectric_sample(b, wo, u),
        MATERIAL_PHASE => {
            // Sampled exactly by its own pdf: the weight is 1.
            let wi = phase_hg_sample(wo, b.ior, [u[1], u[2]]);
            BsdfSample { wi, weight: Vec3::ONE, pdf: phase_hg(wo.dot(wi), b.ior), flags: PHASE_FLAGS }
        }
        _ => BsdfSample::default(),
    }
}

/// Opacity of the material at `h`, in [0, 1].
pub fn material_opacity(s: &SceneView, m: &Material, h: &Hit) -> f32 {
    param_scalar(s, m.alpha, m.alpha_tex, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_matches_known_values() {
        // Normal incidence on glass: ((1.5 - 1) / (1.5 + 1))^2 = 0.04.
        let (f, cos_t) = mf_fresnel_dielectric(1.0, 1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-6 && (cos_t - 1.0).abs() < 1e-6);
        // Brewster's angle, atan(1.5): p-polarised reflectance vanishes, so F = rs^2 / 2.
        let theta = 1.5f32.atan();
        let (f, _) = mf_fresnel_dielectric(theta.cos(), 1.0, 1.5);
        assert!((f - 0.0739).abs() < 1e-3, "{f}");
        // Total internal reflection beyond the critical angle asin(1/1.5) = 41.8 degrees.
        assert_eq!(mf_fresnel_dielectric(45f32.to_radians().cos(), 1.5, 1.0).0, 1.0);
    }
}
