//! Every way the GPU backend can fail, each with a message that says what to do.

use ash::vk;

/// A size in GiB from 1 GiB up, else in MiB, for summaries.
pub(crate) fn human_bytes(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
    } else {
        mib(bytes)
    }
}

/// Mebibytes, for messages.
pub(crate) fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}

/// An error of the Vulkan backend. `Display` is the full user-facing message.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no Vulkan loader found (libvulkan.so.1); install libvulkan1 and mesa-vulkan-drivers, or \
         use --backend cpu (loader error: {reason})"
    )]
    NoLoader { reason: String },

    #[error("no Vulkan driver found; install mesa-vulkan-drivers (lavapipe) or use --backend cpu")]
    NoDriver,

    #[error(
        "the Vulkan loader supports only Vulkan {found}; photonix needs 1.2: update libvulkan1 \
         or use --backend cpu"
    )]
    LoaderTooOld { found: String },

    #[error(
        "validation was requested (PHOTONIX_VALIDATION=1) but the layer VK_LAYER_KHRONOS_validation \
         is not installed; install the Debian package `vulkan-validationlayers` or unset \
         PHOTONIX_VALIDATION"
    )]
    ValidationLayerMissing,

    #[error(
        "PHOTONIX_VALIDATION is `{value}`; set it to 1, true, yes or on to turn the Vulkan validation layer on, or \
         0, false, no or off (or unset it) to leave it off"
    )]
    BadValidationSetting { value: String },

    #[error(
        "{call} returned {result:?} at startup, before any device was opened; the Vulkan loader reports a driver \
         manifest it cannot parse this way{manifests}: check that file, or run with VK_LOADER_DEBUG=error to see the \
         loader's complaint, or use --backend cpu"
    )]
    LoaderFailed { call: &'static str, result: vk::Result, manifests: String },

    #[error("no Vulkan device matches `{requested}`; pass an index or part of a name, one of:\n{available}")]
    DeviceNotFound { requested: String, available: String },

    #[error(
        "device {index} `{name}` supports Vulkan {found}; photonix needs 1.2: update its driver, \
         pick another device with --device, or use --backend cpu"
    )]
    DeviceTooOld { index: usize, name: String, found: String },

    #[error("device `{device}` has no compute queue; pick another device with --device or use --backend cpu")]
    NoComputeQueue { device: String },

    #[error(
        "device `{device}` lacks scalarBlockLayout, which photonix's kernels need (their uniform \
         buffers use the scalar layout); pick another device with --device or use --backend cpu"
    )]
    NoScalarBlockLayout { device: String },

    #[error(
        "buffer `{name}` is {} ({size} bytes), more than this device's {limit_name} of {} \
         ({limit} bytes); split the work into smaller buffers",
        mib(*size),
        mib(*limit)
    )]
    BufferTooLarge { name: String, size: u64, limit_name: &'static str, limit: u64 },

    #[error(
        "out of device memory while allocating `{name}` ({}); lower the photon count or image \
         size, or use --backend cpu",
        mib(*size)
    )]
    OutOfMemory { name: String, size: u64 },

    #[error(
        "out of {memory} memory during `{label}`; lower the photon count or image size, or use \
         --backend cpu"
    )]
    OutOfMemoryDuring { label: String, memory: &'static str },

    #[error("cannot write {len} bytes into buffer `{name}` of {size} bytes; create a larger buffer")]
    WriteTooLarge { name: String, len: u64, size: u64 },

    #[error(
        "buffer `{name}` holds {size} bytes, not a whole number of {element_size}-byte elements; \
         download it as a type whose size divides the buffer size"
    )]
    ElementSizeMismatch { name: String, size: u64, element_size: usize },

    #[error("buffer `{name}` was created by another GpuContext; use buffers and kernels only with the context that made them")]
    ForeignObject { name: String },

    #[error(
        "dispatch of `{kernel}` binds {given} buffers but the kernel declares {expected}; pass one \
         buffer per binding, in binding order"
    )]
    BindingCount { kernel: String, given: usize, expected: u32 },

    #[error(
        "dispatch of `{kernel}` passes {given} bytes of push constants but the kernel declares \
         {expected}; pass exactly the kernel's push-constant struct"
    )]
    PushConstantSize { kernel: String, given: usize, expected: u32 },

    #[error(
        "kernel `{kernel}` asks for {size} bytes of push constants; the size must be a multiple of \
         4 and at most this device's maxPushConstantsSize of {limit}; move the data into a buffer"
    )]
    PushConstantLimit { kernel: String, size: u32, limit: u32 },

    #[error(
        "dispatch of `{kernel}` asks for {groups:?} workgroups, more than this device's \
         maxComputeWorkGroupCount of {limit:?}; split the dispatch"
    )]
    TooManyGroups { kernel: String, groups: [u32; 3], limit: [u32; 3] },

    #[error("kernel `{kernel}` has invalid SPIR-V ({reason}); rebuild the shaders with `cargo build`")]
    InvalidSpirv { kernel: String, reason: String },

    /// Work that does not fit the device's limits even when split, with what to change.
    #[error("{0}")]
    Unsupported(String),

    #[error("device lost during `{label}`; no image was written")]
    DeviceLost { label: String },

    #[error(
        "{call} failed during `{label}`: {result}; update the GPU driver, run with \
         PHOTONIX_VALIDATION=1 for details, or use --backend cpu"
    )]
    Vulkan { call: &'static str, label: String, result: vk::Result },

    // `cause`, not a `#[source]`: the message holds its text already, and `main` prints the
    // chain of sources, which would repeat it.
    #[error("gpu memory allocator failed while allocating `{name}`: {cause}; use --backend cpu if this persists")]
    Allocator { name: String, cause: gpu_allocator::AllocationError },

    #[error(
        "Vulkan validation reported {} message(s); fix the first one:\n{}",
        .0.len(),
        .0.join("\n")
    )]
    Validation(Vec<String>),
}

impl GpuError {
    /// Maps a failed Vulkan call: device loss and exhausted memory get their own variants.
    pub(crate) fn vk(call: &'static str, label: &str, result: vk::Result) -> GpuError {
        match result {
            vk::Result::ERROR_DEVICE_LOST => GpuError::DeviceLost { label: label.to_string() },
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => {
                GpuError::OutOfMemoryDuring { label: label.to_string(), memory: "device" }
            }
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                GpuError::OutOfMemoryDuring { label: label.to_string(), memory: "host" }
            }
            _ => GpuError::Vulkan { call, label: label.to_string(), result },
        }
    }

    /// Maps a failed call of the loader or the instance, before any device exists. Running out of
    /// memory there is what the loader answers to a malformed driver manifest (a JSON file it
    /// cannot parse), not a real shortage: say so, and name the manifests the environment chose.
    pub(crate) fn loader(call: &'static str, result: vk::Result) -> GpuError {
        match result {
            vk::Result::ERROR_OUT_OF_HOST_MEMORY | vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => {
                let chosen: Vec<String> = ["VK_DRIVER_FILES", "VK_ICD_FILENAMES", "VK_ADD_DRIVER_FILES"]
                    .iter()
                    .filter_map(|name| std::env::var(name).ok().map(|v| format!("{name}={v}")))
                    .collect();
                let manifests = if chosen.is_empty() {
                    String::new()
                } else {
                    format!(" (the environment sets {})", chosen.join(", "))
                };
                GpuError::LoaderFailed { call, result, manifests: crate::limits::printable_message(&manifests) }
            }
            _ => GpuError::vk(call, "startup", result),
        }
    }

    /// Maps a failed Vulkan call that allocates `size` bytes for `name`.
    pub(crate) fn vk_alloc(call: &'static str, name: &str, size: u64, result: vk::Result) -> GpuError {
        match result {
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                GpuError::OutOfMemory { name: name.to_string(), size }
            }
            _ => GpuError::vk(call, name, result),
        }
    }

    /// Wraps a gpu-allocator error for the buffer `name` of `size` bytes.
    pub(crate) fn allocator(name: &str, size: u64, source: gpu_allocator::AllocationError) -> GpuError {
        match source {
            gpu_allocator::AllocationError::OutOfMemory => GpuError::OutOfMemory { name: name.to_string(), size },
            cause => GpuError::Allocator { name: name.to_string(), cause },
        }
    }
}
