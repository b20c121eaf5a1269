//! The CPU reference: each file is the twin of the shader of the same name and reads the same
//! flattened arrays, so GPU and CPU results can be compared sample for sample.

pub mod grid;
pub mod grid_build;
pub mod photon;
pub mod render;
pub mod rng;
pub mod shading;
pub mod trace;

use crate::layout::{BvhNode, FrameParams, Light, Material, Primitive};

/// The arrays a kernel sees through its bindings, borrowed.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub frame: &'a FrameParams,
    pub nodes: &'a [BvhNode],
    pub primitives: &'a [Primitive],
    pub materials: &'a [Material],
    pub lights: &'a [Light],
}
