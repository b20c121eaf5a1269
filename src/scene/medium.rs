//! Participating media as the scene describes them (`[media.NAME]`, `[atmosphere]`, and the
//! `interior` and `exterior` of closed shapes); `render::prepare` packs them into `Medium`.

use glam::Vec3;

/// A medium: coefficients per channel in 1 / scene unit (at density 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumDesc {
    pub sigma_a: Vec3,
    pub sigma_s: Vec3,
    /// Radiance emitted per unit length (added along camera rays; it lights nothing else).
    pub emission: Vec3,
    pub phase: Phase,
    /// A heterogeneous medium's density: the coefficients and the emission are scaled by it.
    pub density: Option<Density>,
}

/// Where a heterogeneous medium's density comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Density {
    /// The texture (index into `Scene::textures`) whose first channel, looked up at the point
    /// in world space, is the density.
    pub texture: u32,
    /// The largest density anywhere (sets the tracking majorant).
    pub max: f32,
}

impl MediumDesc {
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }
}

/// The phase function of a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    Isotropic,
    /// Henyey-Greenstein with asymmetry `g` in (-1, 1); g > 0 scatters forward.
    HenyeyGreenstein {
        g: f32,
    },
}

impl Phase {
    /// The asymmetry g (0 for the isotropic phase).
    pub fn g(&self) -> f32 {
        match self {
            Phase::Isotropic => 0.0,
            Phase::HenyeyGreenstein { g } => *g,
        }
    }
}

/// The media on either side of a closed shape's surface (medium ids; `None` is vacuum). The
/// interior is the side the outward normal points away from (a triangle mesh's winding normal
/// points out; loading turns inward-wound meshes around).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MediumInterface {
    pub interior: Option<u32>,
    pub exterior: Option<u32>,
}
