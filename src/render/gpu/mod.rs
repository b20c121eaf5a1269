//! Rendering on a Vulkan device, by stage: the kernels (`kernels`), the scene's upload
//! (`scene`), the light stage that traces photons and builds their grids (`maps`), and the camera
//! stage with the renderer that drives them pass after pass (`camera`); the bidirectional
//! integrators' two stages (`bidirectional`).

mod bidirectional;
mod camera;
mod kernels;
mod maps;
mod scene;

pub use camera::{render_gpu, GpuRenderer};
pub use kernels::{GpuKernels, SCENE_BINDING_TYPES};
pub use maps::{build_maps_gpu, DeviceMap, DeviceMaps};
pub use scene::{DeviceScene, PageSize, PagedArray, PAGE_BYTES_VAR};
