//! Photonix: physically based photon mapping on Vulkan compute shaders, with a CPU twin.

pub mod layout;
pub mod scene;
pub mod shaders;
