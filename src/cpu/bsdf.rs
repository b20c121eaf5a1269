//! Materials as BSDFs: every material kind, one match per operation; twin of `shaders/bsdf.glsl`.
//! Directions point away from the surface: `wo` toward the previous vertex (the viewer), `wi`
//! toward the next one. The path loops never ask which kind they hold, only what its lobes are:
//! `BSDF_ESTIMATE` lobes end a camera path (light sampling, photon lookups, final gather) and
//! store photons; `BSDF_PATH` lobes are followed.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::sampling::{cosine_direction, reflect};
use super::shape::Hit;
use super::texture::{bump_normal, normal_map_normal, param_color, param_scalar};
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Material;

/// A material evaluated at one surface point: its textures looked up, its frame set.
#[derive(Clone, Copy, Debug, Default)]
pub struct Bsdf {
    pub kind: u32,
    pub color0: Vec3,
    pub color1: Vec3,
    pub alpha: Vec2,
    pub ior: f32,
    /// Geometric normal (a triangle's winding side, a sphere's outside).
    pub ng: Vec3,
    /// Shading normal, on the side of `ng`.
    pub ns: Vec3,
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

pub fn material_bsdf(s: &SceneView, m: &Material, h: &Hit) -> Bsdf {
    Bsdf {
        kind: m.kind,
        color0: param_color(s, m.color0, m.color0_tex, h),
        color1: param_color(s, m.color1, m.color1_tex, h),
        alpha: Vec2::from(m.roughness),
        ior: m.ior,
        ng: h.ng,
        // Bump and normal maps change the shading normal only: the geometric normal keeps
        // deciding sides, offsets and leaks.
        ns: if m.bump_tex != NO_TEXTURE {
            bump_normal(s, m.bump_tex, m.bump_strength, h)
        } else if m.normal_tex != NO_TEXTURE {
            normal_map_normal(s, m.normal_tex, h)
        } else {
            h.ns
        },
    }
}

/// The shading normal turned to the side of `w`.
pub fn facing(b: &Bsdf, w: Vec3) -> Vec3 {
    if w.dot(b.ng) > 0.0 {
        b.ns
    } else {
        -b.ns
    }
}

/// Unpolarised Fresnel reflectance for a ray meeting the interface with `cos_i > 0`, going from
/// index `eta_i` into `eta_t`; returns (reflectance, cos_t), reflectance 1 under total internal
/// reflection.
pub fn fresnel_dielectric(cos_i: f32, eta_i: f32, eta_t: f32) -> (f32, f32) {
    let eta = eta_i / eta_t;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
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

/// Dielectric: smooth interface of index `ior` inside (the side opposite `ng`), reflection or
/// refraction chosen with the Fresnel probability against `u[0]`, weight 1.
pub fn dielectric_sample(b: &Bsdf, wo: Vec3, u: [f32; 3]) -> BsdfSample {
    let d = -wo;
    let front = b.ng.dot(d) < 0.0;
    let nf = if front { b.ng } else { -b.ng };
    let (eta_i, eta_t) = if front { (1.0, b.ior) } else { (b.ior, 1.0) };
    let cos_i = -d.dot(nf);
    let (fr, cos_t) = fresnel_dielectric(cos_i, eta_i, eta_t);
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

/// The lobes of `b` (`BSDF_*` flags); 0 for a black surface, which ends paths and stores nothing.
pub fn bsdf_flags(b: &Bsdf) -> u32 {
    match b.kind {
        MATERIAL_DIFFUSE if b.color0 == Vec3::ZERO => 0,
        MATERIAL_DIFFUSE => BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE,
        MATERIAL_MIRROR => BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH,
        MATERIAL_DIELECTRIC => BSDF_SPECULAR | BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_PATH,
        _ => 0, // unreachable: the host packs only known kinds (tested)
    }
}

/// Probability that a camera path seen from `wo` follows the path lobes rather than ending in the
/// estimate lobes: 0 for a surface with estimate lobes alone, 1 for path lobes alone.
pub fn bsdf_path_probability(b: &Bsdf, _wo: Vec3) -> f32 {
    match b.kind {
        MATERIAL_MIRROR | MATERIAL_DIELECTRIC => 1.0,
        _ => 0.0,
    }
}

/// True when the estimate lobes have the same value for every `wi` on `wo`'s side (Lambertian),
/// so a photon estimate may sum the irradiance first and apply the BSDF once.
pub fn bsdf_estimate_is_constant(b: &Bsdf) -> bool {
    b.kind == MATERIAL_DIFFUSE
}

/// f(wo, wi) of the estimate lobes, without the cosine; 0 for path lobes (they are sampled).
pub fn bsdf_eval(b: &Bsdf, wo: Vec3, wi: Vec3) -> Vec3 {
    match b.kind {
        MATERIAL_DIFFUSE => diffuse_eval(b, wo, wi),
        _ => Vec3::ZERO,
    }
}

/// Solid-angle pdf of `bsdf_sample(.., LOBES_ESTIMATE)` choosing `wi`.
pub fn bsdf_pdf(b: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    match b.kind {
        MATERIAL_DIFFUSE => diffuse_pdf(b, wo, wi),
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
        MATERIAL_DIELECTRIC => dielectric_sample(b, wo, u),
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
        let (f, cos_t) = fresnel_dielectric(1.0, 1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-6 && (cos_t - 1.0).abs() < 1e-6);
        // Brewster's angle, atan(1.5): p-polarised reflectance vanishes, so F = rs^2 / 2.
        let theta = 1.5f32.atan();
        let (f, _) = fresnel_dielectric(theta.cos(), 1.0, 1.5);
        assert!((f - 0.0739).abs() < 1e-3, "{f}");
        // Total internal reflection beyond the critical angle asin(1/1.5) = 41.8 degrees.
        assert_eq!(fresnel_dielectric(45f32.to_radians().cos(), 1.5, 1.0).0, 1.0);
    }
}
