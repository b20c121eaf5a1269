//! The Vulkan backend (ash 0.38, gpu-allocator 0.28): a context on one device, named storage
//! buffers, compute kernels, batched dispatches with timings, and the validation layer.
//!
//! ```no_run
//! use photonix::gpu::{GpuContext, GpuOptions};
//! # fn main() -> Result<(), photonix::gpu::GpuError> {
//! let gpu = GpuContext::new(&GpuOptions::from_env(None))?;
//! let data = gpu.upload("numbers", &[1u32, 2, 3])?;
//! let spirv = photonix::shaders::spirv("test_add").expect("built by build.rs");
//! let add = gpu.create_kernel("test_add", &spirv, 1, 8)?;
//! gpu.run("add", |r| r.dispatch(&add, &[&data], bytemuck::bytes_of(&[3u32, 7]), [1, 1, 1]))?;
//! assert_eq!(gpu.download::<u32>(&data)?, [8, 9, 10]);
//! # Ok(()) }
//! ```
//!
//! Everything is synchronous: each call returns after the GPU finished its work. Buffers and
//! kernels hold an `Arc` of the device, so they may be dropped before or after the context.
//! `unsafe` lives only in this module.

mod buffer;
mod context;
mod device_info;
mod error;
mod kernel;
mod validation;

pub use buffer::Buffer;
pub use context::{list_devices, GpuContext, GpuOptions};
pub use device_info::DeviceInfo;
pub use error::GpuError;
pub use kernel::{Kernel, Recorder};
