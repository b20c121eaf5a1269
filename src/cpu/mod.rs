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
pub mod photon_index;
pub mod pixel_list;
pub mod render;
pub mod render_features;
pub mod render_pt;
pub mod rng;
pub mod sampling;
pub mod shading;
pub mod shape;
pub mod texture;
pub mod trace;
pub mod vcm;
pub mod voxel;

use crate::accel::wide::WideBvh;
use crate::layout::{BvhNode, FrameParams, GridParams, Light, Material, Medium, Primitive, Texture};
use photon_index::PhotonIndex;

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
    /// The CPU backend's four-wide form of `nodes` (`accel::wide`), which `trace_ray` walks
    /// where it is present; `None` walks `nodes` as the kernels do.
    pub wide: Option<&'a WideBvh>,
    /// The pixel list that dispatches with a `pixel_list` index (`cpu::pixel_list`); empty
    /// where every dispatch renders its whole band.
    pub pixel_list: &'a [u32],
}

/// The photon maps (`MAP_*`: global, caustic, volume) as the CPU backend reads them: the kernels
/// bind grid parameters, photons sorted by bucket and bucket starts; the CPU the same photons
/// in its own lookup layout (`photon_index.rs`), which gives the same sums.
#[derive(Clone, Copy)]
pub struct MapsView<'a> {
    pub grids: &'a [GridParams; 3],
    pub indices: &'a [PhotonIndex; 3],
}

/// No photon maps: maps with no photons, which every lookup skips.
pub const NO_MAPS: MapsView<'static> = MapsView {
    grids: &[GridParams { cell_size: 1.0, radius: 0.5, table_mask: 0, photon_count: 0, flux_scale: 1.0, _pad: [0; 3] };
        3],
    indices: &[PhotonIndex::EMPTY, PhotonIndex::EMPTY, PhotonIndex::EMPTY],
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
            wide: None,
            pixel_list: &[],
        }
    }
}
