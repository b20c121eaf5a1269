//! The open logical device: [`Shared`] holds the instance, device, allocator and the one queue
//! every command goes to.
//!
//! Ownership: [`Shared`] sits behind an `Arc`. The context, every [`Buffer`](super::Buffer),
//! [`Kernel`](super::Kernel) and the submitter keep a clone of that `Arc`, so whatever order the
//! caller drops things in, all allocations are freed before the allocator, the allocator before
//! the device and the device before the instance.

use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::device_info::DeviceInfo;
use super::error::GpuError;
use super::instance::{Candidate, InstanceOwner};

/// The instance, device and allocator, shared by the context and everything it creates.
pub(super) struct Shared {
    pub(super) device: ash::Device,
    /// `None` only while dropping: the allocator must go before the device.
    allocator: Mutex<Option<Allocator>>,
    /// Present when validation is on: names objects so messages can say which buffer or kernel.
    debug_utils: Option<ash::ext::debug_utils::Device>,
    pub(super) queue: vk::Queue,
    pub(super) queue_family: u32,
    /// `timestampValidBits` of the queue; 0 means no timings.
    pub(super) timestamp_valid_bits: u32,
    pub(super) info: DeviceInfo,
    /// Declared last: destroyed after the device (fields drop after `Drop::drop`).
    instance: InstanceOwner,
}

impl Shared {
    /// Attaches `name` to a Vulkan object for validation messages; a no-op without validation.
    pub(super) fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(utils) = &self.debug_utils else {
            return;
        };
        let Ok(name) = std::ffi::CString::new(name.replace('\0', " ")) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
        // SAFETY: `handle` is a live object of this device; naming is best-effort, so a failure
        // is ignored.
        let _ = unsafe { utils.set_debug_utils_object_name(&info) };
    }

    /// The allocator; only `Drop` takes it away.
    pub(super) fn allocator(&self) -> MutexGuard<'_, Option<Allocator>> {
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// [`GpuError::Validation`] when the layer reported anything since the last check.
    pub(super) fn check_validation(&self) -> Result<(), GpuError> {
        self.instance.log.check()
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: the device is valid; waiting makes sure nothing still uses the memory below.
        let _ = unsafe { self.device.device_wait_idle() };
        // Every Buffer holds an Arc of `Shared`, so all allocations were freed already.
        drop(self.allocator().take());
        // SAFETY: all child objects (buffers, kernels, pools, the allocator's memory) are
        // destroyed, since each holds an Arc of `Shared` or is owned by the context.
        unsafe { self.device.destroy_device(None) };
        // Messages raised while tearing down have no caller left to return them to.
        for message in self.instance.log.take() {
            eprintln!("photonix: Vulkan validation at shutdown: {message}");
        }
    }
}

impl Shared {
    /// Creates the logical device of `candidate` (one of `instance`'s devices, as
    /// [`choose_device`](super::instance::choose_device) returned it) with only the compute
    /// queue and the supported optional features, and its allocator.
    pub(super) fn open(
        instance: InstanceOwner,
        candidate: &Candidate,
        validation: bool,
    ) -> Result<Arc<Shared>, GpuError> {
        let (queue_family, timestamp_valid_bits) =
            candidate.queue_family.expect("choose_device returns only devices with a compute queue");

        let f = candidate.features;
        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let mut extensions = Vec::new();
        if f.atomic_float_extension {
            extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        }
        if f.portability_subset {
            extensions.push(ash::khr::portability_subset::NAME.as_ptr());
        }
        let f10 = vk::PhysicalDeviceFeatures::default()
            .shader_float64(f.shader_float64)
            .shader_int64(f.shader_int64)
            .shader_int16(f.shader_int16);
        let mut v11 =
            vk::PhysicalDeviceVulkan11Features::default().storage_buffer16_bit_access(f.storage_buffer16_bit_access);
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default()
            .storage_buffer8_bit_access(f.storage_buffer8_bit_access)
            .shader_int8(f.shader_int8)
            .scalar_block_layout(f.scalar_block_layout)
            .shader_buffer_int64_atomics(f.shader_buffer_int64_atomics)
            .host_query_reset(f.host_query_reset)
            .timeline_semaphore(f.timeline_semaphore);
        let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(f.shader_buffer_float32_atomic_add)
            .shader_shared_float32_atomic_add(f.shader_shared_float32_atomic_add);
        let mut features2 =
            vk::PhysicalDeviceFeatures2::default().features(f10).push_next(&mut v11).push_next(&mut v12);
        if f.atomic_float_extension {
            features2 = features2.push_next(&mut atomic_float);
        }
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&extensions)
            .push_next(&mut features2);
        // SAFETY: the physical device belongs to this instance; every feature and extension
        // enabled was reported as supported by `describe_device`; pointers refer to locals.
        let device = unsafe { instance.instance.create_device(candidate.physical, &device_info, None) }
            .map_err(|e| GpuError::vk("vkCreateDevice", &candidate.info.name, e))?;
        // SAFETY: the queue family and index 0 were requested in `device_info`.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.instance.clone(),
            device: device.clone(),
            physical_device: candidate.physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: nothing was created from the device yet.
                unsafe { device.destroy_device(None) };
                return Err(GpuError::allocator("the allocator", 0, e));
            }
        };
        let debug_utils = validation.then(|| ash::ext::debug_utils::Device::new(&instance.instance, &device));
        let shared = Arc::new(Shared {
            device,
            allocator: Mutex::new(Some(allocator)),
            debug_utils,
            queue,
            queue_family,
            timestamp_valid_bits,
            info: candidate.info.clone(),
            instance,
        });
        shared.set_name(shared.queue, "compute queue");
        Ok(shared)
    }
}

/// [`GpuError::ForeignObject`] unless the buffer or kernel `name`, made on the device `theirs`,
/// belongs to the device `ours`.
pub(super) fn check_same_device(ours: &Arc<Shared>, theirs: &Arc<Shared>, name: &str) -> Result<(), GpuError> {
    if Arc::ptr_eq(ours, theirs) {
        Ok(())
    } else {
        Err(GpuError::ForeignObject { name: name.to_string() })
    }
}
