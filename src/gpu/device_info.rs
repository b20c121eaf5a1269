//! What `photonix devices` prints: a physical device's name, driver and the limits that matter.

use std::fmt;

use ash::vk;

use super::error::human_bytes;

/// A physical device and the limits the renderer must respect.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceInfo {
    /// Position in the loader's device list; `--device` accepts it.
    pub index: usize,
    pub name: String,
    /// "discrete GPU", "integrated GPU", "virtual GPU", "CPU" or "other".
    pub device_type: String,
    /// Driver name and driver info, e.g. "llvmpipe (Mesa 22.3.6 (LLVM 15.0.6))".
    pub driver: String,
    /// The device's Vulkan version, e.g. "1.3.230".
    pub api_version: String,
    /// Largest storage-buffer binding, in bytes.
    pub max_storage_buffer_range: u64,
    /// Most texels a texel-buffer view may span.
    pub max_texel_buffer_elements: u64,
    /// Largest single memory allocation, in bytes.
    pub max_memory_allocation_size: u64,
    pub max_compute_workgroup_invocations: u32,
    pub max_compute_workgroup_count: [u32; 3],
    /// In bytes.
    pub max_push_constants_size: u32,
    /// Invocations per subgroup; never assume 32 or 64 (lavapipe has 8).
    pub subgroup_size: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f32,
    /// Sum of the device-local heaps, in bytes.
    pub device_local_heap_bytes: u64,
    /// Optional features the device supports and the context enables, by their Vulkan names
    /// (e.g. "shaderFloat64", "shaderBufferFloat32AtomicAdd").
    pub features: Vec<&'static str>,
}

impl DeviceInfo {
    /// Whether the optional feature `name` (a Vulkan feature name) is supported and enabled.
    pub fn has_feature(&self, name: &str) -> bool {
        self.features.contains(&name)
    }

    /// A readable multi-line summary, as `photonix devices` prints it.
    pub fn describe(&self) -> String {
        self.to_string()
    }
}

impl fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [gx, gy, gz] = self.max_compute_workgroup_count;
        writeln!(f, "{}: {} ({})", self.index, self.name, self.device_type)?;
        writeln!(f, "    driver: {}, Vulkan {}", self.driver, self.api_version)?;
        writeln!(f, "    device-local memory: {}", human_bytes(self.device_local_heap_bytes))?;
        writeln!(
            f,
            "    largest storage buffer: {}, largest allocation: {}, largest texel buffer: {} texels",
            human_bytes(self.max_storage_buffer_range),
            human_bytes(self.max_memory_allocation_size),
            self.max_texel_buffer_elements
        )?;
        writeln!(
            f,
            "    workgroup: up to {} invocations, {gx} x {gy} x {gz} groups; subgroup size {}",
            self.max_compute_workgroup_invocations, self.subgroup_size
        )?;
        writeln!(
            f,
            "    push constants: {} bytes; timestamp tick: {} ns",
            self.max_push_constants_size, self.timestamp_period_ns
        )?;
        let features = if self.features.is_empty() { "none".to_string() } else { self.features.join(", ") };
        write!(f, "    optional features: {features}")
    }
}

/// "discrete GPU", "integrated GPU", ... for a Vulkan device type.
pub(crate) fn device_type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

/// Preference when no device is named: discrete, integrated, virtual, CPU, other (lower wins).
pub(crate) fn device_type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// "1.3.230" for a packed Vulkan version.
pub(crate) fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}
