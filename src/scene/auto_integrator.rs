//! The integrator of a scene that names none (`[render] integrator = "auto"`, the default): the
//! one measured fastest to a given error on scenes of its kind. No integrator wins every kind
//! (BENCHMARKS.md, "Every integrator on every shared scene, quiet, with the floor": equal-error
//! time ratios against Mitsuba 3 on the CPU backend):
//!
//! | scene kind | ppm | pt | bpt |
//! | --- | --- | --- | --- |
//! | diffuse room (cornell-box) | 0.78 | 0.80 | 0.28 |
//! | caustics through glass and a mirror (cornell-caustics) | 6.46 | 0.42 | 0.99 |
//! | rough metal and glass, small light (cornell-glossy) | 0.10 | 0.25 | 0.85 |
//! | fog (cornell-fog) | 0.76 | 0.84 | 2.95 |
//!
//! So: a bidirectional integrator where ppm's camera paths would follow rough glossy lobes (they
//! find small lights through them rarely: fireflies) or where there are media (light tracing and
//! connections reach the glow around lamps in the fog, which camera paths find rarely), else
//! `ppm`, whose caustic map wins caustics and ties the diffuse room. Of the two, `vcm` on rough
//! glossy scenes lit by area lights or a sky (at equal time 18% lower error than `bpt` on
//! cornell-glossy, 20% on materials.toml, 12% on shapes.toml, even on outdoor.toml), `bpt` where
//! point, spot or sharp distant lights shine (spotlights.toml: 30-40% lower than `vcm`) and in
//! media (cornell-fog: even); BENCHMARKS.md, "vcm's merges made cheap".

use super::material::{MaterialDesc, MaterialKind, Roughness};
use super::{Integrator, LightDesc, LightKind};

/// The integrator for a scene of these materials, lights and media, and why, in words for a note.
/// `glossy_threshold` is the GGX width up to which ppm follows glossy lobes as paths
/// (`[photons] glossy_threshold`); `None` for photons: a scene that turned its photon maps off
/// asked for ppm's direct light and specular paths only, and keeps them.
pub fn auto_integrator(
    materials: &[MaterialDesc],
    lights: &[LightDesc],
    media: usize,
    glossy_threshold: Option<f32>,
) -> (Integrator, &'static str) {
    let Some(threshold) = glossy_threshold else {
        return (Integrator::Ppm, "its photon maps are off (direct light and specular paths only)");
    };
    if media > 0 {
        return (Integrator::Bpt, "it has participating media, where bpt's light paths and connections win");
    }
    if materials.iter().any(|m| glossy_path_lobe(&m.kind, threshold)) {
        if lights.iter().any(|l| is_delta(&l.kind)) {
            return (
                Integrator::Bpt,
                "it has rough glossy surfaces (GGX width up to glossy_threshold) and point, spot or sharp distant \
                 lights, where bpt's connections win",
            );
        }
        return (
            Integrator::Vcm,
            "it has rough glossy surfaces (GGX width up to glossy_threshold) lit by area lights or a sky, where \
             vcm's connections and merges win",
        );
    }
    (Integrator::Ppm, "it has no media and no rough glossy surfaces, where photon mapping wins")
}

/// Lights of a single point or direction.
fn is_delta(kind: &LightKind) -> bool {
    match kind {
        LightKind::Point { .. } | LightKind::Spot { .. } => true,
        LightKind::Distant { half_angle_deg, .. } => *half_angle_deg <= 0.0,
        LightKind::Area { .. } => false,
    }
}

/// Whether ppm's camera paths would follow the material's lobe as a path (rough, not smooth, and
/// at most `threshold` wide). A textured width may fall anywhere, so it counts when its constant
/// is rough.
fn glossy_path_lobe(kind: &MaterialKind, threshold: f32) -> bool {
    let glossy = |r: &Roughness| {
        let widest = r.alpha[0].max(r.alpha[1]);
        widest > 0.0 && (widest <= threshold || r.texture.is_some())
    };
    match kind {
        MaterialKind::Dielectric { roughness, .. }
        | MaterialKind::Conductor { roughness, .. }
        | MaterialKind::Plastic { roughness, .. } => glossy(roughness),
        MaterialKind::Diffuse { .. }
        | MaterialKind::Mirror { .. }
        | MaterialKind::ThinDielectric { .. }
        | MaterialKind::Mix { .. }
        | MaterialKind::Null => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::material::{ColorParam, ScalarParam};
    use glam::Vec3;

    fn area() -> LightDesc {
        LightDesc::new(LightKind::Area { material: 0, grid: [1, 1], jitter: false, adaptive: false })
    }

    fn conductor(alpha: f32) -> MaterialDesc {
        let c = ColorParam::constant(Vec3::ONE);
        MaterialDesc::new(MaterialKind::Conductor { eta: c, k: c, roughness: Roughness::ggx(alpha), tint: c })
    }

    #[test]
    fn rough_glossy_chooses_vcm_or_bpt_media_bpt_else_ppm() {
        let diffuse = MaterialDesc::new(MaterialKind::Diffuse { reflectance: ColorParam::constant(Vec3::splat(0.5)) });
        let mirror = MaterialDesc::new(MaterialKind::Mirror { tint: ColorParam::constant(Vec3::ONE) });
        let mix = MaterialDesc::new(MaterialKind::Mix { a: 0, b: 1, weight: ScalarParam::constant(0.5) });
        let plain = [diffuse.clone(), mirror, mix];
        assert_eq!(auto_integrator(&plain, &[], 0, Some(0.25)).0, Integrator::Ppm);
        assert_eq!(auto_integrator(&plain, &[], 1, Some(0.25)).0, Integrator::Bpt);
        assert_eq!(auto_integrator(&[diffuse.clone(), conductor(0.15)], &[area()], 0, Some(0.25)).0, Integrator::Vcm);
        let spot = LightDesc::new(LightKind::Spot {
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            intensity: Vec3::ONE,
            cos_inner: 0.9,
            cos_outer: 0.8,
            exponent: 0.0,
        });
        let sun = |half_angle_deg| {
            LightDesc::new(LightKind::Distant {
                direction: Vec3::NEG_Y,
                irradiance: Vec3::ONE,
                half_angle_deg,
                visible: true,
            })
        };
        let rough = [diffuse.clone(), conductor(0.15)];
        assert_eq!(auto_integrator(&rough, &[area(), spot], 0, Some(0.25)).0, Integrator::Bpt);
        assert_eq!(auto_integrator(&rough, &[sun(0.0)], 0, Some(0.25)).0, Integrator::Bpt);
        assert_eq!(auto_integrator(&rough, &[sun(0.5)], 0, Some(0.25)).0, Integrator::Vcm);
        assert_eq!(auto_integrator(&rough, &[area()], 1, Some(0.25)).0, Integrator::Bpt);
        // Smooth metal is a delta lobe, and a wide lobe ppm reads from its maps: both stay ppm.
        assert_eq!(auto_integrator(&[diffuse.clone(), conductor(0.0)], &[area()], 0, Some(0.25)).0, Integrator::Ppm);
        assert_eq!(auto_integrator(&[diffuse.clone(), conductor(0.4)], &[area()], 0, Some(0.25)).0, Integrator::Ppm);
        assert_eq!(auto_integrator(&[conductor(0.4)], &[], 0, Some(0.5)).0, Integrator::Vcm);
        // Photon maps turned off keep ppm's direct light and specular paths, media or not.
        assert_eq!(auto_integrator(&[conductor(0.15)], &[], 1, None).0, Integrator::Ppm);
    }
}
