//! The Vulkan loader and instance, and the physical devices: what each one supports, and which
//! one to open.

use std::ffi::CStr;
use std::sync::Arc;

use ash::vk;

use super::device_info::{device_type_name, device_type_rank, version_string, DeviceInfo};
use super::error::GpuError;
use super::validation::{self, MessageLog};

/// The Vulkan loader and instance, and the validation messenger when there is one.
pub(super) struct InstanceOwner {
    entry: ash::Entry,
    pub(super) instance: ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Read by the messenger callback through a raw pointer: dropped after the messenger.
    pub(super) log: Arc<MessageLog>,
}

impl InstanceOwner {
    /// Loads the system loader and creates a Vulkan 1.2 instance, with the validation layer and a
    /// debug messenger when `validation` is on.
    pub(super) fn new(validation: bool) -> Result<InstanceOwner, GpuError> {
        // SAFETY: loading libvulkan.so.1 runs its initialisers; the system loader is trusted.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader { reason: e.to_string() })?;
        // SAFETY: the entry holds a loaded loader; vkEnumerateInstanceVersion has no preconditions.
        let loader_version = match unsafe { entry.try_enumerate_instance_version() } {
            Ok(Some(v)) => v,
            Ok(None) => vk::API_VERSION_1_0,
            Err(e) => return Err(GpuError::loader("vkEnumerateInstanceVersion", e)),
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
            e => GpuError::loader("vkCreateInstance", e),
        })?;

        let mut owner = InstanceOwner { entry, instance, messenger: None, log };
        if validation {
            let loader = ash::ext::debug_utils::Instance::new(&owner.entry, &owner.instance);
            let info = validation::messenger_info(&owner.log);
            // SAFETY: the instance was created with VK_EXT_debug_utils enabled; the user data is
            // `owner.log`, dropped only after the messenger is destroyed in `Drop`.
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
                .map_err(|e| GpuError::loader("vkCreateDebugUtilsMessengerEXT", e))?;
            owner.messenger = Some((loader, messenger));
        }
        Ok(owner)
    }

    /// Every physical device, described, in the loader's order (the `--device` indices).
    pub(super) fn candidates(&self) -> Result<Vec<Candidate>, GpuError> {
        let devices = self.physical_devices()?;
        Ok(devices.into_iter().enumerate().map(|(i, pd)| describe_device(&self.instance, pd, i)).collect())
    }

    /// The physical devices, in the loader's order; none at all is [`GpuError::NoDriver`].
    fn physical_devices(&self) -> Result<Vec<vk::PhysicalDevice>, GpuError> {
        // SAFETY: the instance is valid for the lifetime of `self`.
        let devices = unsafe { self.instance.enumerate_physical_devices() }.map_err(|e| match e {
            vk::Result::ERROR_INITIALIZATION_FAILED | vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDriver,
            e => GpuError::loader("vkEnumeratePhysicalDevices", e),
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
pub(super) struct Features {
    pub(super) shader_float64: bool,
    pub(super) shader_int64: bool,
    pub(super) shader_int16: bool,
    pub(super) storage_buffer16_bit_access: bool,
    pub(super) storage_buffer8_bit_access: bool,
    pub(super) shader_int8: bool,
    pub(super) scalar_block_layout: bool,
    pub(super) shader_buffer_int64_atomics: bool,
    pub(super) host_query_reset: bool,
    pub(super) timeline_semaphore: bool,
    /// VK_EXT_shader_atomic_float: `atomicAdd` on floats in buffers.
    pub(super) shader_buffer_float32_atomic_add: bool,
    /// VK_EXT_shader_atomic_float: `atomicAdd` on floats in shared memory.
    pub(super) shader_shared_float32_atomic_add: bool,
    /// The device lists VK_EXT_shader_atomic_float.
    pub(super) atomic_float_extension: bool,
    /// The device lists VK_KHR_portability_subset, which must then be enabled.
    pub(super) portability_subset: bool,
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
pub(super) struct Candidate {
    pub(super) physical: vk::PhysicalDevice,
    pub(super) info: DeviceInfo,
    api_version: u32,
    device_type: vk::PhysicalDeviceType,
    pub(super) features: Features,
    /// Queue family with compute (and timestamps, when any family has them), and its
    /// `timestampValidBits`.
    pub(super) queue_family: Option<(u32, u32)>,
}

/// Reads the properties, limits, features and queues of `physical`.
fn describe_device(instance: &ash::Instance, physical: vk::PhysicalDevice, index: usize) -> Candidate {
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
        max_texel_buffer_elements: u64::from(limits.max_texel_buffer_elements),
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
    Ok(owner.candidates()?.into_iter().map(|c| c.info).collect())
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
pub(super) fn choose_device(candidates: &[Candidate], requested: Option<&str>) -> Result<usize, GpuError> {
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
                .filter(|(_, c)| {
                    c.api_version >= vk::API_VERSION_1_2 && c.queue_family.is_some() && c.features.scalar_block_layout
                })
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
    if !c.features.scalar_block_layout {
        return Err(GpuError::NoScalarBlockLayout { device: c.info.name.clone() });
    }
    Ok(chosen)
}
