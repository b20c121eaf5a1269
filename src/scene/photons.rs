//! How the photon maps of a scene are made and read: part of the scene, so that the scene file
//! and the renderer share one description.

/// How the photon maps are made and read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photon paths traced for the global map.
    pub photons: u32,
    /// Photon paths traced for the caustic map (each ends at its first diffuse surface).
    pub caustic_photons: u32,
    /// Lookup radius of the global map (scene units); `None` derives it from the scene's surface
    /// area and the stored photon count.
    pub radius: Option<f32>,
    /// Lookup radius of the caustic map; `None` is half the global radius.
    pub caustic_radius: Option<f32>,
    /// Lookup radius of the volume map (collisions in media); `None` derives it from the
    /// media's volume and the stored photon count.
    pub volume_radius: Option<f32>,
    /// Final-gather rays per camera sample; 0 reads the global map directly.
    pub gather_rays: u32,
    /// Most surfaces a photon path visits.
    pub max_depth: u32,
    /// Radius reduction of progressive passes, in (0, 1): see `pass_radius_scale`.
    pub alpha: f32,
    /// Glossy lobes with GGX width up to this are followed by paths; rougher ones read photons.
    pub glossy_threshold: f32,
}

/// The default `alpha`: Knaus and Zwicker's 2/3 balances noise and a bias that falls as r^2;
/// with the edges' bias gone (the probes, open edges) a slower shrink pays: 0.8 lowered
/// cornell-box's error at 30 s by 11% and at 240 s by 2% on the CPU (BENCHMARKS.md, "Open edges,
/// black surfaces and alpha 0.8").
pub const DEFAULT_ALPHA: f32 = 0.8;

impl Default for PhotonSettings {
    fn default() -> Self {
        PhotonSettings {
            photons: 200_000,
            caustic_photons: 200_000,
            radius: None,
            caustic_radius: None,
            volume_radius: None,
            gather_rays: 8,
            max_depth: 16,
            alpha: DEFAULT_ALPHA,
            glossy_threshold: crate::layout::constants::GLOSSY_THRESHOLD,
        }
    }
}
