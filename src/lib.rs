//! Photonix: physically based photon mapping on Vulkan compute shaders, with a CPU twin.

pub mod gpu;
// src/layout/mod.rs has `size % 16 == 0` in a const assert, which clippy 1.95 flags; the
// layout owner can switch it to `is_multiple_of` and drop this allow.
#[allow(clippy::manual_is_multiple_of)]
pub mod layout;
pub mod scene;
pub mod shaders;
pub mod accel;
pub mod cpu;
pub mod gpu;
pub mod io;
pub mod render;
pub mod scene;
