//! Photonix: physically based photon mapping on Vulkan compute shaders, with a CPU twin.

pub mod accel;
pub mod cpu;
pub mod editor;
pub mod gpu;
pub mod io;
pub mod layout;
pub mod limits;
pub mod render;
pub mod scene;
pub mod shaders;
