//! The open GPU: [`GpuContext`] ties the device, the submitter and the timings together, and
//! is the public face of this module: buffers in and out, kernels, and batches of dispatches.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use bytemuck::Pod;
use gpu_allocator::MemoryLocation;

use super::batch::Recorder;
use super::buffer::Buffer;
use super::device::{check_same_device, Shared};
use super::device_info::DeviceInfo;
use super::error::GpuError;
use super::instance::{choose_device, InstanceOwner};
use super::kernel::{BindingTypes, Kernel};
use super::submitter::Submitter;

/// How to open the GPU.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GpuOptions {
    /// A device index (as `photonix devices` lists them) or a case-insensitive part of its name;
    /// `None` picks a discrete GPU, then an integrated one, then a virtual one, then a CPU device.
    pub device: Option<String>,
    /// Enable `VK_LAYER_KHRONOS_validation` and turn every warning or error it reports into
    /// [`GpuError::Validation`].
    pub validation: bool,
}

impl GpuOptions {
    /// Options for `device`, with validation as `PHOTONIX_VALIDATION` says: `1`, `true`, `yes`,
    /// `on` turn it on, `0`, `false`, `no`, `off` or an empty or unset variable leave it off (any
    /// case); anything else is an error rather than a silent "off".
    pub fn from_env(device: Option<String>) -> Result<Self, GpuError> {
        let validation = match std::env::var_os("PHOTONIX_VALIDATION") {
            None => false,
            Some(value) => parse_switch(&value.to_string_lossy()).ok_or_else(|| GpuError::BadValidationSetting {
                value: crate::limits::printable(&value.to_string_lossy()),
            })?,
        };
        Ok(GpuOptions { device, validation })
    }
}

/// An on/off setting as people write it, or `None` when it is neither.
pub fn parse_switch(value: &str) -> Option<bool> {
    match value.trim().to_ascii_lowercase().as_str() {
        "1" | "true" | "yes" | "on" => Some(true),
        "0" | "false" | "no" | "off" | "" => Some(false),
        _ => None,
    }
}

/// An open GPU: the device, a command buffer for synchronous submissions, and the timings.
pub struct GpuContext {
    shared: Arc<Shared>,
    submitter: Mutex<Submitter>,
    /// Per kernel name: (total seconds, dispatch count), in first-dispatch order.
    timings: Mutex<Vec<(String, f64, u32)>>,
    /// Always go through staging buffers, even where device memory is host-visible.
    force_staging: AtomicBool,
    /// The staging and the readback buffer of the last copies, kept for the next ones (up to
    /// [`KEPT_TRANSFER_BYTES`]): a render's per-pass uploads and readbacks then allocate nothing.
    staging: Mutex<Option<Buffer>>,
    readback: Mutex<Option<Buffer>>,
}

/// The largest staging or readback buffer kept between copies; larger ones (scene uploads) are
/// made for their copy and freed after it.
const KEPT_TRANSFER_BYTES: u64 = 64 << 20;

/// A transfer buffer of at least `size` bytes: the kept one when it is large enough, else a new
/// one (rounded up to a power of two when it may be kept, so growing images reuse it).
fn transfer_buffer(
    shared: &Arc<Shared>,
    kept: &mut Option<Buffer>,
    name: &str,
    size: u64,
    usage: vk::BufferUsageFlags,
    location: MemoryLocation,
) -> Result<Buffer, GpuError> {
    if let Some(buffer) = kept.take_if(|b| b.size() >= size) {
        return Ok(buffer);
    }
    let size = if size <= KEPT_TRANSFER_BYTES { size.next_power_of_two().min(KEPT_TRANSFER_BYTES) } else { size };
    Buffer::create(shared, name, size, usage, location)
}

/// Keeps `buffer` for the next copy when it is small enough.
fn keep_transfer(kept: &mut Option<Buffer>, buffer: Buffer) {
    if buffer.size() <= KEPT_TRANSFER_BYTES {
        *kept = Some(buffer);
    }
}

impl GpuContext {
    /// Opens the device chosen by `options` (see [`GpuOptions`]).
    pub fn new(options: &GpuOptions) -> Result<GpuContext, GpuError> {
        let instance = InstanceOwner::new(options.validation)?;
        let candidates = instance.candidates()?;
        let chosen = choose_device(&candidates, options.device.as_deref())?;
        let shared = Shared::open(instance, &candidates[chosen], options.validation)?;
        let submitter = Submitter::new(&shared)?;
        let context = GpuContext {
            shared,
            submitter: Mutex::new(submitter),
            timings: Mutex::new(Vec::new()),
            force_staging: AtomicBool::new(false),
            staging: Mutex::new(None),
            readback: Mutex::new(None),
        };
        context.shared.check_validation()?;
        Ok(context)
    }

    /// The chosen device.
    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    /// Always copy through staging buffers, as on a discrete GPU, even where device-local memory
    /// is host-visible (lavapipe, integrated GPUs). For tests of the staging path.
    pub fn set_force_staging(&self, on: bool) {
        self.force_staging.store(on, Ordering::Relaxed);
    }

    /// Per-kernel GPU time from timestamp queries, summed per kernel name since creation or the
    /// last call: (name, total seconds, dispatch count), in order of first dispatch. Empty when
    /// the queue has no timestamps.
    pub fn take_timings(&self) -> Vec<(String, f64, u32)> {
        std::mem::take(&mut *self.timings.lock().unwrap_or_else(|e| e.into_inner()))
    }

    // Buffers
    //
    // Data goes through a `CpuToGpu` staging buffer and comes back through a `GpuToCpu` readback
    // buffer, as a discrete GPU needs. Where the device-local memory is also host-visible and
    // coherent (lavapipe's single heap, many integrated GPUs) the copies go straight through the
    // mapping instead, which saves a second copy of every buffer in the one heap;
    // `set_force_staging` turns that shortcut off.

    /// The mapping of `buffer`, unless staging is forced or the memory is not host-visible.
    fn direct_ptr(&self, buffer: &Buffer) -> Option<*mut u8> {
        if self.force_staging.load(Ordering::Relaxed) {
            None
        } else {
            buffer.host_ptr()
        }
    }

    /// Device-local storage buffer filled from `data` through a staging buffer. Empty slices
    /// are allowed (the Vulkan buffer then has 16 zero bytes, and `size()` is 0).
    pub fn upload<T: Pod>(&self, name: &str, data: &[T]) -> Result<Buffer, GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buffer = Buffer::create_storage(&self.shared, name, bytes.len() as u64)?;
        self.write_bytes(&buffer, bytes, buffer.vk_size, &format!("upload `{name}`"))?;
        self.shared.check_validation()?;
        Ok(buffer)
    }

    /// Zero-filled device-local storage buffer of `size` bytes.
    pub fn create_buffer(&self, name: &str, size: u64) -> Result<Buffer, GpuError> {
        let buffer = Buffer::create_storage(&self.shared, name, size)?;
        self.zero(&buffer, &format!("create `{name}`"))?;
        self.shared.check_validation()?;
        Ok(buffer)
    }

    /// Device-local storage buffer of `size` bytes whose contents are undefined until a kernel,
    /// fill or copy writes them: for scratch space the next command overwrites, where zeroing
    /// would cost a submission.
    pub fn create_scratch(&self, name: &str, size: u64) -> Result<Buffer, GpuError> {
        let buffer = Buffer::create_storage(&self.shared, name, size)?;
        self.shared.check_validation()?;
        Ok(buffer)
    }

    /// Overwrites the start of `buffer` with `data`; the rest keeps its contents.
    pub fn write<T: Pod>(&self, buffer: &Buffer, data: &[T]) -> Result<(), GpuError> {
        self.check_same_context(&buffer.shared, buffer.name())?;
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > buffer.size() {
            return Err(GpuError::WriteTooLarge {
                name: buffer.name().to_string(),
                len: bytes.len() as u64,
                size: buffer.size(),
            });
        }
        self.write_bytes(buffer, bytes, 0, &format!("write `{}`", buffer.name()))?;
        self.shared.check_validation()
    }

    /// The whole buffer (`size()` bytes) as `T`s, through a readback buffer.
    pub fn download<T: Pod>(&self, buffer: &Buffer) -> Result<Vec<T>, GpuError> {
        self.check_same_context(&buffer.shared, buffer.name())?;
        let element_size = size_of::<T>();
        if element_size == 0 {
            return Ok(Vec::new());
        }
        if !buffer.size().is_multiple_of(element_size as u64) {
            return Err(GpuError::ElementSizeMismatch {
                name: buffer.name().to_string(),
                size: buffer.size(),
                element_size,
            });
        }
        let mut out = vec![T::zeroed(); (buffer.size() / element_size as u64) as usize];
        if out.is_empty() {
            return Ok(out);
        }
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        let label = format!("download `{}`", buffer.name());
        if let Some(ptr) = self.direct_ptr(buffer) {
            let _submitter = self.lock_submitter();
            buffer.read_mapped(ptr, dst);
        } else {
            let mut kept = self.readback.lock().unwrap_or_else(|e| e.into_inner());
            let readback = transfer_buffer(
                &self.shared,
                &mut kept,
                "readback",
                buffer.size(),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;
            let region = [vk::BufferCopy::default().size(buffer.size())];
            self.one_shot(&label, |device, cb| {
                // SAFETY: both buffers are live, the region lies inside both, and the command
                // buffer is recording.
                unsafe { device.cmd_copy_buffer(cb, buffer.handle, readback.handle, &region) };
            })?;
            let ptr = readback.host_ptr().expect("GpuToCpu memory is host-visible, coherent and mapped");
            readback.read_mapped(ptr, dst);
            keep_transfer(&mut kept, readback);
        }
        self.shared.check_validation()?;
        Ok(out)
    }

    /// Sets every byte of `buffer` to zero.
    pub fn fill_zero(&self, buffer: &Buffer) -> Result<(), GpuError> {
        self.check_same_context(&buffer.shared, buffer.name())?;
        self.zero(buffer, &format!("fill_zero `{}`", buffer.name()))?;
        self.shared.check_validation()
    }

    fn zero(&self, buffer: &Buffer, label: &str) -> Result<(), GpuError> {
        if let Some(ptr) = self.direct_ptr(buffer) {
            let _submitter = self.lock_submitter();
            buffer.write_mapped(ptr, &[], buffer.vk_size);
            return Ok(());
        }
        self.one_shot(label, |device, cb| {
            // SAFETY: the buffer is live and was created with TRANSFER_DST; WHOLE_SIZE covers
            // its `vk_size`, a multiple of 4.
            unsafe { device.cmd_fill_buffer(cb, buffer.handle, 0, vk::WHOLE_SIZE, 0) };
        })
    }

    /// Writes `bytes` at offset 0 and zeroes the buffer from there up to `zero_to` bytes.
    fn write_bytes(&self, buffer: &Buffer, bytes: &[u8], zero_to: u64, label: &str) -> Result<(), GpuError> {
        if let Some(ptr) = self.direct_ptr(buffer) {
            let _submitter = self.lock_submitter();
            buffer.write_mapped(ptr, bytes, zero_to);
            return Ok(());
        }
        let copy_size = (bytes.len() as u64).max(zero_to);
        if copy_size == 0 {
            return Ok(());
        }
        let mut kept = self.staging.lock().unwrap_or_else(|e| e.into_inner());
        let staging = transfer_buffer(
            &self.shared,
            &mut kept,
            "staging",
            copy_size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let ptr = staging.host_ptr().expect("CpuToGpu memory is host-visible, coherent and mapped");
        staging.write_mapped(ptr, bytes, copy_size);
        let region = [vk::BufferCopy::default().size(copy_size)];
        self.one_shot(label, |device, cb| {
            // SAFETY: both buffers are live, the region lies inside both (`copy_size` is at most
            // the target's `vk_size` and the staging buffer's size), and the command buffer is
            // recording.
            unsafe { device.cmd_copy_buffer(cb, staging.handle, buffer.handle, &region) };
        })?;
        keep_transfer(&mut kept, staging);
        Ok(())
    }

    // Kernels

    /// A compute pipeline from SPIR-V words with `binding_count` storage-buffer bindings (set 0,
    /// bindings 0..n) and push constants of `push_constant_size` bytes (0 = none). The entry
    /// point is `main`.
    pub fn create_kernel(
        &self,
        name: &str,
        spirv: &[u32],
        binding_count: u32,
        push_constant_size: u32,
    ) -> Result<Kernel, GpuError> {
        self.create_specialized_kernel(name, spirv, binding_count, BindingTypes::default(), push_constant_size, &[])
    }

    /// `create_kernel` with specialization constants: `constants[i]` is the value of
    /// `constant_id = i` (a bool as 0 or 1); the bindings `binding_types` names are uniform
    /// texel buffers over the buffer bound there, the others storage buffers.
    pub fn create_specialized_kernel(
        &self,
        name: &str,
        spirv: &[u32],
        binding_count: u32,
        binding_types: BindingTypes,
        push_constant_size: u32,
        constants: &[u32],
    ) -> Result<Kernel, GpuError> {
        let kernel =
            Kernel::create(&self.shared, name, spirv, binding_count, binding_types, push_constant_size, constants)?;
        self.shared.check_validation()?;
        Ok(kernel)
    }

    /// Records a batch of commands with `record`, submits it once and waits. Between consecutive
    /// commands a barrier makes compute and transfer writes visible to the next compute or
    /// transfer command. Nothing is submitted when `record` fails. `label` names the batch in
    /// errors; timings go by kernel name.
    pub fn run<'a>(
        &'a self,
        label: &str,
        record: impl FnOnce(&mut Recorder<'a>) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
        let mut recorder = Recorder::new(&self.shared);
        record(&mut recorder)?;
        if recorder.is_empty() {
            return self.shared.check_validation();
        }
        let mut submitter = self.lock_submitter();
        let dispatch_seconds = recorder.submit(&mut submitter, label)?;
        let mut timings = self.timings.lock().unwrap_or_else(|e| e.into_inner());
        for (kernel, seconds) in dispatch_seconds {
            match timings.iter_mut().find(|(name, _, _)| name == kernel) {
                Some(entry) => {
                    entry.1 += seconds;
                    entry.2 += 1;
                }
                None => timings.push((kernel.to_string(), seconds, 1)),
            }
        }
        drop(timings);
        drop(submitter);
        self.shared.check_validation()
    }

    // Submission

    fn lock_submitter(&self) -> MutexGuard<'_, Submitter> {
        self.submitter.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records the commands of `record` into one command buffer, submits it and waits.
    fn one_shot(&self, label: &str, record: impl FnOnce(&ash::Device, vk::CommandBuffer)) -> Result<(), GpuError> {
        self.lock_submitter().one_shot(label, record)
    }

    fn check_same_context(&self, shared: &Arc<Shared>, name: &str) -> Result<(), GpuError> {
        check_same_device(&self.shared, shared, name)
    }
}
