//! The Vulkan backend (ash 0.38, gpu-allocator 0.28): a context on one device, named storage
//! buffers, compute kernels, batched dispatches with timings, and the validation layer.
//!
//! ```no_run
//! use photonix::gpu::{GpuContext, GpuOptions};
//! # fn main() -> Result<(), photonix::gpu::GpuError> {
//! let gpu = GpuContext::new(&GpuOptions::from_env(None)?)?;
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
//!
//! Layers, each module using only those above it (no module imports one below it):
//!
//! ```text
//! error        GpuError, byte formatting
//! device_info  DeviceInfo, what `photonix devices` prints          -> error
//! validation   the validation layer and its message log            -> error
//! instance     loader, instance, physical devices and the choice   -> error, device_info, validation
//! device       Shared: logical device, allocator, queue            -> error, device_info, instance
//! buffer       Buffer: a named buffer and its memory, mapped I/O   -> error, device
//! kernel       Kernel: a compute pipeline from SPIR-V              -> error, device
//! submitter    Submitter: command buffer, fence, pools             -> error, device
//! batch        Recorder: a checked batch, recorded and submitted   -> error, device, buffer, kernel, submitter
//! context      GpuContext: the public calls, on top of all above   -> all of the above but validation
//! ```

mod batch;
mod buffer;
mod context;
mod device;
mod device_info;
mod error;
mod instance;
mod kernel;
pub mod oidn;
mod submitter;
mod validation;

pub use batch::Recorder;
pub use buffer::Buffer;
pub use context::{parse_switch, GpuContext, GpuOptions};
pub use device_info::DeviceInfo;
pub use error::GpuError;
pub use instance::list_devices;
pub use kernel::{BindingTypes, Kernel};
