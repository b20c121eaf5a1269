//! Compute kernels: a pipeline, its layouts and its shader module, made from SPIR-V.

use std::sync::Arc;

use ash::vk;

use super::device::Shared;
use super::error::GpuError;

/// SPIR-V's magic number, the first word of every module.
const SPIRV_MAGIC: u32 = 0x0723_0203;

/// A compute pipeline with `binding_count` storage buffers (set 0, bindings 0..n) and
/// `push_constant_size` bytes of push constants. Keeps the device alive, so it may outlive its
/// [`GpuContext`](super::GpuContext); destroys its Vulkan objects when dropped.
pub struct Kernel {
    pub(super) name: String,
    pub(super) binding_count: u32,
    pub(super) binding_types: BindingTypes,
    pub(super) push_constant_size: u32,
    shader: vk::ShaderModule,
    /// Null when the kernel has no bindings.
    pub(super) set_layout: vk::DescriptorSetLayout,
    pub(super) layout: vk::PipelineLayout,
    pub(super) pipeline: vk::Pipeline,
    pub(super) shared: Arc<Shared>,
}

impl Kernel {
    /// A compute pipeline from SPIR-V words with `binding_count` storage-buffer bindings (set 0,
    /// bindings 0..n) and push constants of `push_constant_size` bytes (0 = none). The entry
    /// point is `main`. `constants[i]` is the value of specialization constant `constant_id = i`
    /// (a bool as 0 or 1); ids the shader does not declare are ignored. The caller checks for
    /// validation messages.
    pub(super) fn create(
        shared: &Arc<Shared>,
        name: &str,
        spirv: &[u32],
        binding_count: u32,
        binding_types: BindingTypes,
        push_constant_size: u32,
        constants: &[u32],
    ) -> Result<Kernel, GpuError> {
        if spirv.len() < 5 || spirv[0] != SPIRV_MAGIC {
            let reason = if spirv.is_empty() { "empty module".to_string() } else { "no SPIR-V header".to_string() };
            return Err(GpuError::InvalidSpirv { kernel: name.to_string(), reason });
        }
        let limit = shared.info.max_push_constants_size;
        if !push_constant_size.is_multiple_of(4) || push_constant_size > limit {
            return Err(GpuError::PushConstantLimit { kernel: name.to_string(), size: push_constant_size, limit });
        }
        let device = &shared.device;
        // Each handle lands in `kernel` as soon as it exists, so an early return frees it.
        let mut kernel = Kernel {
            name: name.to_string(),
            binding_count,
            binding_types,
            push_constant_size,
            shader: vk::ShaderModule::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            shared: shared.clone(),
        };

        let module_info = vk::ShaderModuleCreateInfo::default().code(spirv);
        // SAFETY: `spirv` is a slice of whole words starting with the SPIR-V magic number.
        kernel.shader = unsafe { device.create_shader_module(&module_info, None) }
            .map_err(|e| GpuError::vk("vkCreateShaderModule", name, e))?;
        shared.set_name(kernel.shader, name);

        let mut set_layouts = Vec::new();
        if binding_count > 0 {
            let bindings: Vec<vk::DescriptorSetLayoutBinding> = (0..binding_count)
                .map(|b| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b)
                        .descriptor_type(binding_types.descriptor_type(b))
                        .descriptor_count(binding_types.descriptor_count(b))
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
            // SAFETY: valid create info whose pointers refer to `bindings`.
            kernel.set_layout = unsafe { device.create_descriptor_set_layout(&info, None) }
                .map_err(|e| GpuError::vk("vkCreateDescriptorSetLayout", name, e))?;
            shared.set_name(kernel.set_layout, name);
            set_layouts.push(kernel.set_layout);
        }
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .offset(0)
            .size(push_constant_size)];
        let ranges: &[vk::PushConstantRange] = if push_constant_size > 0 { &ranges } else { &[] };
        let layout_info =
            vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(ranges);
        // SAFETY: valid create info; the set layout is live.
        kernel.layout = unsafe { device.create_pipeline_layout(&layout_info, None) }
            .map_err(|e| GpuError::vk("vkCreatePipelineLayout", name, e))?;
        shared.set_name(kernel.layout, name);

        let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
            .map(|id| vk::SpecializationMapEntry::default().constant_id(id).offset(id * 4).size(4))
            .collect();
        let specialization =
            vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(constants));
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(kernel.shader)
            .name(c"main");
        if !constants.is_empty() {
            stage = stage.specialization_info(&specialization);
        }
        let pipeline_info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(kernel.layout)];
        // SAFETY: the module and layout are live; no pipeline cache is used.
        let pipelines = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &pipeline_info, None) }
            .map_err(|(_, e)| GpuError::vk("vkCreateComputePipelines", name, e))?;
        kernel.pipeline = pipelines[0];
        shared.set_name(kernel.pipeline, name);
        Ok(kernel)
    }

    /// The name given at creation: the debug name and the timing label.
    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn binding_count(&self) -> u32 {
        self.binding_count
    }

    pub fn push_constant_size(&self) -> u32 {
        self.push_constant_size
    }
}

/// The bindings of a kernel that are not storage buffers: uniform texel buffers (`usamplerBuffer`
/// in GLSL) over the buffer bound there, bit b of `rgba` making binding b a buffer of RGBA32UI
/// texels (16 bytes each) and bit b of `words` one of R32UI texels (a word each); and uniform
/// buffers (bit b of `uniform`), which the shader declares with the scalar block layout. A
/// binding whose bit is set in `arrays` is an array of `array_len` descriptors of its type (a
/// scene array split into pages, src/render/gpu/scene.rs), bound to as many consecutive buffers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BindingTypes {
    pub rgba: u32,
    pub words: u32,
    pub uniform: u32,
    pub arrays: u32,
    pub array_len: u32,
}

impl BindingTypes {
    /// The texel format of binding `b`, or None for a storage or uniform buffer.
    pub(super) fn format(self, b: u32) -> Option<vk::Format> {
        let bit = 1u32.checked_shl(b).unwrap_or(0);
        if self.rgba & bit != 0 {
            Some(vk::Format::R32G32B32A32_UINT)
        } else if self.words & bit != 0 {
            Some(vk::Format::R32_UINT)
        } else {
            None
        }
    }

    /// How many descriptors binding `b` holds (buffers it takes).
    pub fn descriptor_count(self, b: u32) -> u32 {
        let bit = 1u32.checked_shl(b).unwrap_or(0);
        if self.arrays & bit != 0 {
            self.array_len.max(1)
        } else {
            1
        }
    }

    /// How many buffers bindings 0..`bindings` take together.
    pub fn buffer_count(self, bindings: u32) -> u32 {
        (0..bindings).map(|b| self.descriptor_count(b)).sum()
    }

    pub(super) fn descriptor_type(self, b: u32) -> vk::DescriptorType {
        let bit = 1u32.checked_shl(b).unwrap_or(0);
        match self.format(b) {
            Some(_) => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
            None if self.uniform & bit != 0 => vk::DescriptorType::UNIFORM_BUFFER,
            None => vk::DescriptorType::STORAGE_BUFFER,
        }
    }
}

impl std::fmt::Debug for Kernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Kernel")
            .field("name", &self.name)
            .field("binding_count", &self.binding_count)
            .field("push_constant_size", &self.push_constant_size)
            .finish()
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let device = &self.shared.device;
        // SAFETY: every submission using this kernel was waited for before `run` returned; each
        // handle is either null (a no-op for vkDestroy*) or owned by this kernel alone.
        unsafe {
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
            device.destroy_shader_module(self.shader, None);
        }
    }
}
