//! The Vulkan instance, the chosen device, its allocator and the one queue every command goes to.
//!
//! Ownership: [`Shared`] holds the instance, device and allocator behind an `Arc`. Every
//! [`Buffer`](super::Buffer) and [`Kernel`](super::Kernel) keeps a clone of that `Arc`, so
//! whatever order the caller drops things in, all allocations are freed before the allocator,
//! the allocator before the device and the device before the instance.

use std::ffi::CStr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::device_info::{device_type_name, device_type_rank, version_string, DeviceInfo};
use super::validation::{self, MessageLog};
use super::GpuError;

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
    /// Options for `device`, with validation on when the environment has `PHOTONIX_VALIDATION=1`.
    pub fn from_env(device: Option<String>) -> Self {
        let validation = std::env::var("PHOTONIX_VALIDATION").is_ok_and(|v| v.trim() == "1");
        GpuOptions { device, validation }
    }
}

/// The Vulkan loader and instance, and the validation messenger when there is one.
pub(crate) struct InstanceOwner {
    pub(crate) entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Read by the messenger callback through a raw pointer: dropped after the messenger.
    pub(crate) log: Arc<MessageLog>,
}

impl InstanceOwner {
    /// Loads the system loader and creates a Vulkan 1.2 instance, with the validation layer and a
    /// debug messenger when `validation` is on.
    pub(crate) fn new(validation: bool) -> Result<InstanceOwner, GpuError> {
        // SAFETY: loading libvulkan.so.1 runs its initialisers; the system loader is trusted.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader { reason: e.to_string() })?;
        // SAFETY: the entry holds a loaded loader; vkEnumerateInstanceVersion has no preconditions.
        let loader_version = match unsafe { entry.try_enumerate_instance_version() } {
            Ok(Some(v)) => v,
            Ok(None) => vk::API_VERSION_1_0,
            Err(e) => return Err(GpuError::vk("vkEnumerateInstanceVersion", "startup", e)),
        };
        if loader_version < vk::API_VERSION_1_1 {
            return Err(GpuError::LoaderTooOld { found: version_string(loader_version) });
        }

        // SAFETY: as above; `None` asks for the extensions of the loader and implicit layers.
        let available = unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
        let has_extension =
            |name: &CStr| available.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name));

        let mut layers = Vec::new();
        let mut extensions = Vec::new();
        if validation {
            if !validation::layer_available(&entry) {
                return Err(GpuError::ValidationLayerMissing);
            }
            layers.push(validation::LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        // MoltenVK and other portability drivers are only listed when asked for.
        let mut flags = vk::InstanceCreateFlags::empty();
        if has_extension(ash::khr::portability_enumeration::NAME) {
            extensions.push(ash::khr::portability_enumeration::NAME.as_ptr());
            flags |= vk::InstanceCreateFlags::ENUMERATE_PORTABILITY_KHR;
        }

        let log = Arc::new(MessageLog::default());
        let app = vk::ApplicationInfo::default()
            .application_name(c"photonix")
            .engine_name(c"photonix")
            .api_version(vk::API_VERSION_1_2);
        // Chained into the create info too, so messages from instance creation are recorded.
        let mut messenger_info = validation::messenger_info(&log);
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions)
            .flags(flags);
        if validation {
            create_info = create_info.push_next(&mut messenger_info);
        }
        // SAFETY: every pointer in `create_info` refers to locals that outlive the call, and the
        // messenger's user data is `log`, which the returned owner keeps alive.
        let instance = unsafe { entry.create_instance(&create_info, None) }.map_err(|e| match e {
            vk::Result::ERROR_INCOMPATIBLE_DRIVER | vk::Result::ERROR_INITIALIZATION_FAILED => GpuError::NoDriver,
            vk::Result::ERROR_LAYER_NOT_PRESENT => GpuError::ValidationLayerMissing,
            e => GpuError::vk("vkCreateInstance", "startup", e),
        })?;

        let mut owner = InstanceOwner { entry, instance, messenger: None, log };
        if validation {
            let loader = ash::ext::debug_utils::Instance::new(&owner.entry, &owner.instance);
            let info = validation::messenger_info(&owner.log);
            // SAFETY: the instance was created with VK_EXT_debug_utils enabled; the user data is
            // `owner.log`, dropped only after the messenger is destroyed in `Drop`.
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
                .map_err(|e| GpuError::vk("vkCreateDebugUtilsMessengerEXT", "startup", e))?;
            owner.messenger = Some((loader, messenger));
        }
        Ok(owner)
    }

    /// The physical devices, in the loader's order; none at all is [`GpuError::NoDriver`].
    pub(crate) fn physical_devices(&self) -> Result<Vec<vk::PhysicalDevice>, GpuError> {
        // SAFETY: the instance is valid for the lifetime of `self`.
        let devices = unsafe { self.instance.enumerate_physical_devices() }.map_err(|e| match e {
            vk::Result::ERROR_INITIALIZATION_FAILED | vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDriver,
            e => GpuError::vk("vkEnumeratePhysicalDevices", "startup", e),
        })?;
        if devices.is_empty() {
            return Err(GpuError::NoDriver);
        }
        Ok(devices)
    }
}

impl Drop for InstanceOwner {
    fn drop(&mut self) {
        if let Some((loader, messenger)) = self.messenger.take() {
            // SAFETY: the messenger was created from this instance and is destroyed exactly once.
            unsafe { loader.destroy_debug_utils_messenger(messenger, None) };
        }
        // SAFETY: every child object (device, messenger) is gone: `Shared` destroys the device
        // before its `InstanceOwner` field drops.
        unsafe { self.instance.destroy_instance(None) };
    }
}

/// Optional device features the kernels may use, each enabled only when supported.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Features {
    shader_float64: bool,
    shader_int64: bool,
    shader_int16: bool,
    storage_buffer16_bit_access: bool,
    storage_buffer8_bit_access: bool,
    shader_int8: bool,
    scalar_block_layout: bool,
    shader_buffer_int64_atomics: bool,
    host_query_reset: bool,
    timeline_semaphore: bool,
    /// VK_EXT_shader_atomic_float: `atomicAdd` on floats in buffers.
    shader_buffer_float32_atomic_add: bool,
    /// VK_EXT_shader_atomic_float: `atomicAdd` on floats in shared memory.
    shader_shared_float32_atomic_add: bool,
    /// The device lists VK_EXT_shader_atomic_float.
    atomic_float_extension: bool,
    /// The device lists VK_KHR_portability_subset, which must then be enabled.
    portability_subset: bool,
}

impl Features {
    fn names(&self) -> Vec<&'static str> {
        [
            (self.shader_float64, "shaderFloat64"),
            (self.shader_int64, "shaderInt64"),
            (self.shader_int16, "shaderInt16"),
            (self.shader_int8, "shaderInt8"),
            (self.storage_buffer16_bit_access, "storageBuffer16BitAccess"),
            (self.storage_buffer8_bit_access, "storageBuffer8BitAccess"),
            (self.scalar_block_layout, "scalarBlockLayout"),
            (self.shader_buffer_int64_atomics, "shaderBufferInt64Atomics"),
            (self.shader_buffer_float32_atomic_add, "shaderBufferFloat32AtomicAdd"),
            (self.shader_shared_float32_atomic_add, "shaderSharedFloat32AtomicAdd"),
            (self.host_query_reset, "hostQueryReset"),
            (self.timeline_semaphore, "timelineSemaphore"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect()
    }
}

/// One physical device as enumerated: its summary, supported features and compute queue.
pub(crate) struct Candidate {
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) info: DeviceInfo,
    api_version: u32,
    device_type: vk::PhysicalDeviceType,
    features: Features,
    /// Queue family with compute (and timestamps, when any family has them), and its
    /// `timestampValidBits`.
    queue_family: Option<(u32, u32)>,
}

/// Reads the properties, limits, features and queues of `physical`.
pub(crate) fn describe_device(instance: &ash::Instance, physical: vk::PhysicalDevice, index: usize) -> Candidate {
    // SAFETY (all calls below): `physical` came from this instance's device list; the structure
    // chains point at locals that outlive each call.
    let base = unsafe { instance.get_physical_device_properties(physical) };
    let api_version = base.api_version;
    let is_1_2 = api_version >= vk::API_VERSION_1_2;

    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup).push_next(&mut maintenance3);
    if is_1_2 {
        props2 = props2.push_next(&mut driver);
    }
    // SAFETY: see above.
    unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
    let props = props2.properties;

    // SAFETY: see above.
    let extensions = unsafe { instance.enumerate_device_extension_properties(physical) }.unwrap_or_default();
    let has_extension = |name: &CStr| extensions.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name));
    let atomic_float_extension = has_extension(ash::ext::shader_atomic_float::NAME);

    let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    let mut features2 = vk::PhysicalDeviceFeatures2::default();
    if is_1_2 {
        features2 = features2.push_next(&mut v11).push_next(&mut v12);
    }
    if atomic_float_extension {
        features2 = features2.push_next(&mut atomic_float);
    }
    // SAFETY: see above.
    unsafe { instance.get_physical_device_features2(physical, &mut features2) };
    let f10 = features2.features;
    let features = Features {
        shader_float64: f10.shader_float64 == vk::TRUE,
        shader_int64: f10.shader_int64 == vk::TRUE,
        shader_int16: f10.shader_int16 == vk::TRUE,
        storage_buffer16_bit_access: v11.storage_buffer16_bit_access == vk::TRUE,
        storage_buffer8_bit_access: v12.storage_buffer8_bit_access == vk::TRUE,
        shader_int8: v12.shader_int8 == vk::TRUE,
        scalar_block_layout: v12.scalar_block_layout == vk::TRUE,
        shader_buffer_int64_atomics: v12.shader_buffer_int64_atomics == vk::TRUE,
        host_query_reset: v12.host_query_reset == vk::TRUE,
        timeline_semaphore: v12.timeline_semaphore == vk::TRUE,
        shader_buffer_float32_atomic_add: atomic_float.shader_buffer_float32_atomic_add == vk::TRUE,
        shader_shared_float32_atomic_add: atomic_float.shader_shared_float32_atomic_add == vk::TRUE,
        atomic_float_extension,
        portability_subset: has_extension(ash::khr::portability_subset::NAME),
    };

    // SAFETY: see above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    let compute: Vec<(u32, u32)> = families
        .iter()
        .enumerate()
        .filter(|(_, f)| f.queue_flags.contains(vk::QueueFlags::COMPUTE) && f.queue_count > 0)
        .map(|(i, f)| (i as u32, f.timestamp_valid_bits))
        .collect();
    let queue_family = compute.iter().copied().find(|(_, bits)| *bits > 0).or(compute.first().copied());

    // SAFETY: see above.
    let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
    let device_local_heap_bytes = memory
        .memory_heaps_as_slice()
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .sum();

    let name = props.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let driver_text = if is_1_2 {
        let driver_name = driver.driver_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let driver_info = driver.driver_info_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if driver_info.is_empty() {
            driver_name
        } else {
            format!("{driver_name} ({driver_info})")
        }
    } else {
        format!("driver version {:#x}", props.driver_version)
    };
    let limits = &props.limits;
    let info = DeviceInfo {
        index,
        name,
        device_type: device_type_name(props.device_type).to_string(),
        driver: driver_text,
        api_version: version_string(api_version),
        max_storage_buffer_range: u64::from(limits.max_storage_buffer_range),
        max_memory_allocation_size: maintenance3.max_memory_allocation_size,
        max_compute_workgroup_invocations: limits.max_compute_work_group_invocations,
        max_compute_workgroup_count: limits.max_compute_work_group_count,
        max_push_constants_size: limits.max_push_constants_size,
        subgroup_size: subgroup.subgroup_size,
        timestamp_period_ns: limits.timestamp_period,
        device_local_heap_bytes,
        features: features.names(),
    };
    Candidate { physical, info, api_version, device_type: props.device_type, features, queue_family }
}

/// Every Vulkan device the loader finds, for `photonix devices`.
pub fn list_devices() -> Result<Vec<DeviceInfo>, GpuError> {
    let owner = InstanceOwner::new(false)?;
    let devices = owner.physical_devices()?;
    Ok(devices.into_iter().enumerate().map(|(i, pd)| describe_device(&owner.instance, pd, i).info).collect())
}

/// "  0: llvmpipe (LLVM 15.0.6, 256 bits) (CPU)" lines, for error messages.
fn device_list(candidates: &[Candidate]) -> String {
    candidates
        .iter()
        .map(|c| format!("  {}: {} ({})", c.info.index, c.info.name, c.info.device_type))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Picks the device named by `requested`, or the best kind of device when `None`.
fn choose_device(candidates: &[Candidate], requested: Option<&str>) -> Result<usize, GpuError> {
    let chosen = match requested.map(str::trim).filter(|r| !r.is_empty()) {
        Some(requested) => {
            let lower = requested.to_lowercase();
            let by_index = requested.parse::<usize>().ok().filter(|&i| i < candidates.len());
            let by_name = || candidates.iter().position(|c| c.info.name.to_lowercase().contains(&lower));
            by_index.or_else(by_name).ok_or_else(|| GpuError::DeviceNotFound {
                requested: requested.to_string(),
                available: device_list(candidates),
            })?
        }
        None => {
            let usable = candidates
                .iter()
                .enumerate()
                .filter(|(_, c)| c.api_version >= vk::API_VERSION_1_2 && c.queue_family.is_some())
                .min_by_key(|(i, c)| (device_type_rank(c.device_type), *i));
            match usable {
                Some((i, _)) => i,
                // Nothing usable: report on the best device of any version.
                None => {
                    (0..candidates.len()).min_by_key(|&i| (device_type_rank(candidates[i].device_type), i)).unwrap_or(0)
                }
            }
        }
    };
    let c = &candidates[chosen];
    if c.api_version < vk::API_VERSION_1_2 {
        return Err(GpuError::DeviceTooOld {
            index: c.info.index,
            name: c.info.name.clone(),
            found: version_string(c.api_version),
        });
    }
    if c.queue_family.is_none() {
        return Err(GpuError::NoComputeQueue { device: c.info.name.clone() });
    }
    Ok(chosen)
}

/// The instance, device and allocator, shared by the context and everything it creates.
pub(crate) struct Shared {
    pub(crate) device: ash::Device,
    /// `None` only while dropping: the allocator must go before the device.
    pub(crate) allocator: Mutex<Option<Allocator>>,
    /// Present when validation is on: names objects so messages can say which buffer or kernel.
    debug_utils: Option<ash::ext::debug_utils::Device>,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    /// `timestampValidBits` of the queue; 0 means no timings.
    pub(crate) timestamp_valid_bits: u32,
    pub(crate) info: DeviceInfo,
    /// Declared last: destroyed after the device (fields drop after `Drop::drop`).
    pub(crate) instance: InstanceOwner,
}

impl Shared {
    /// Attaches `name` to a Vulkan object for validation messages; a no-op without validation.
    pub(crate) fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
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
    pub(crate) fn allocator(&self) -> MutexGuard<'_, Option<Allocator>> {
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// [`GpuError::Validation`] when the layer reported anything since the last check.
    pub(crate) fn check_validation(&self) -> Result<(), GpuError> {
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

/// An open GPU: the device, a command buffer for synchronous submissions, and the timings.
pub struct GpuContext {
    pub(crate) shared: Arc<Shared>,
    pub(crate) submitter: Mutex<super::kernel::Submitter>,
    /// Per kernel name: (total seconds, dispatch count), in first-dispatch order.
    pub(crate) timings: Mutex<Vec<(String, f64, u32)>>,
    /// Always go through staging buffers, even where device memory is host-visible.
    pub(crate) force_staging: AtomicBool,
}

impl GpuContext {
    /// Opens the device chosen by `options` (see [`GpuOptions`]).
    pub fn new(options: &GpuOptions) -> Result<GpuContext, GpuError> {
        let instance = InstanceOwner::new(options.validation)?;
        let devices = instance.physical_devices()?;
        let candidates: Vec<Candidate> =
            devices.iter().enumerate().map(|(i, &pd)| describe_device(&instance.instance, pd, i)).collect();
        let chosen = choose_device(&candidates, options.device.as_deref())?;
        let candidate = &candidates[chosen];
        let (queue_family, timestamp_valid_bits) =
            candidate.queue_family.expect("choose_device returns only devices with a compute queue");

        // Create the device with only the compute queue and the supported optional features.
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
        let debug_utils = options.validation.then(|| ash::ext::debug_utils::Device::new(&instance.instance, &device));
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
        let submitter = super::kernel::Submitter::new(&shared)?;
        let context = GpuContext {
            shared,
            submitter: Mutex::new(submitter),
            timings: Mutex::new(Vec::new()),
            force_staging: AtomicBool::new(false),
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

    pub(crate) fn check_same_context(&self, shared: &Arc<Shared>, name: &str) -> Result<(), GpuError> {
        if Arc::ptr_eq(shared, &self.shared) {
            Ok(())
        } else {
            Err(GpuError::ForeignObject { name: name.to_string() })
        }
    }
}
