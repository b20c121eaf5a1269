//! The CPU reference: each file is the twin of the shader of the same name and reads the same
//! flattened arrays, so GPU and CPU results can be compared sample for sample.

pub mod emit_photons;
pub mod gather;
pub mod grid;
pub mod grid_build;
pub mod microfacet;
pub mod photon;
pub mod render;
pub mod rng;
pub mod shading;
pub mod trace;

use crate::layout::{BvhNode, FrameParams, GridParams, Light, Material, Photon, Primitive};

/// The arrays a kernel sees through its bindings, borrowed.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub frame: &'a FrameParams,
    pub nodes: &'a [BvhNode],
    pub primitives: &'a [Primitive],
    pub materials: &'a [Material],
    pub lights: &'a [Light],
    pub maps: MapsView<'a>,
}

/// The two photon maps as the camera kernel binds them: grid parameters (0 global, 1 caustic),
/// photons sorted by bucket and bucket starts.
#[derive(Clone, Copy)]
pub struct MapsView<'a> {
    pub grids: &'a [GridParams; 2],
    pub global_photons: &'a [Photon],
    pub global_starts: &'a [u32],
    pub caustic_photons: &'a [Photon],
    pub caustic_starts: &'a [u32],
}

/// No photon maps: grids with no photons, which every lookup skips.
pub const NO_MAPS: MapsView<'static> = MapsView {
    grids: &[GridParams { cell_size: 1.0, radius: 0.5, table_mask: 0, photon_count: 0, flux_scale: 1.0, _pad: [0; 3] };
        2],
    global_photons: &[],
    global_starts: &[0, 0],
    caustic_photons: &[],
    caustic_starts: &[0, 0],
};
