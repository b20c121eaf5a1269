//! The CPU reference: each file is the twin of the shader of the same name and reads the same
//! flattened arrays, so GPU and CPU results can be compared sample for sample.

pub mod bsdf;
pub mod csg;
pub mod emit_photons;
pub mod gather;
pub mod grid;
pub mod grid_build;
pub mod image_texture;
pub mod instance;
pub mod light;
pub mod medium;
pub mod microfacet;
pub mod pattern;
pub mod phase;
pub mod photon;
pub mod render;
pub mod rng;
pub mod sampling;
pub mod shading;
pub mod shape;
pub mod texture;
pub mod trace;
pub mod voxel;

use crate::layout::{BvhNode, FrameParams, GridParams, Light, Material, Medium, Photon, Primitive, Texture};

/// The arrays a kernel sees through its bindings, borrowed.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub frame: &'a FrameParams,
    pub nodes: &'a [BvhNode],
    pub primitives: &'a [Primitive],
    pub materials: &'a [Material],
    pub lights: &'a [Light],
    pub textures: &'a [Texture],
    pub texture_data: &'a [u32],
    pub shape_data: &'a [f32],
    pub media: &'a [Medium],
    pub maps: MapsView<'a>,
}

/// The photon maps as the camera kernel binds them: grid parameters (`MAP_*`: global, caustic,
/// volume), photons sorted by bucket and bucket starts.
#[derive(Clone, Copy)]
pub struct MapsView<'a> {
    pub grids: &'a [GridParams; 3],
    pub global_photons: &'a [Photon],
    pub global_starts: &'a [u32],
    pub caustic_photons: &'a [Photon],
    pub caustic_starts: &'a [u32],
    pub volume_photons: &'a [Photon],
    pub volume_starts: &'a [u32],
}

/// No photon maps: grids with no photons, which every lookup skips.
pub const NO_MAPS: MapsView<'static> = MapsView {
    grids: &[GridParams { cell_size: 1.0, radius: 0.5, table_mask: 0, photon_count: 0, flux_scale: 1.0, _pad: [0; 3] };
        3],
    global_photons: &[],
    global_starts: &[0, 0],
    caustic_photons: &[],
    caustic_starts: &[0, 0],
    volume_photons: &[],
    volume_starts: &[0, 0],
};

impl<'a> SceneView<'a> {
    /// Geometry alone (no materials, lights or textures): enough to trace rays through opaque
    /// primitives, for tests and tools.
    pub fn geometry(frame: &'a FrameParams, nodes: &'a [BvhNode], primitives: &'a [Primitive]) -> SceneView<'a> {
        SceneView {
            frame,
            nodes,
            primitives,
            materials: &[],
            lights: &[],
            textures: &[],
            texture_data: &[],
            shape_data: &[],
            media: &[],
            maps: NO_MAPS,
        }
    }
}
