//! Compute kernels, and the submission of batches of dispatches with barriers and timestamps.

use std::sync::{Arc, MutexGuard};

use ash::vk;

use super::buffer::Buffer;
use super::context::{GpuContext, Shared};
use super::GpuError;

/// SPIR-V's magic number, the first word of every module.
const SPIRV_MAGIC: u32 = 0x0723_0203;

/// A compute pipeline with `binding_count` storage buffers (set 0, bindings 0..n) and
/// `push_constant_size` bytes of push constants. Keeps the device alive, so it may outlive its
/// [`GpuContext`]; destroys its Vulkan objects when dropped.
pub struct Kernel {
    name: String,
    binding_count: u32,
    push_constant_size: u32,
    shader: vk::ShaderModule,
    /// Null when the kernel has no bindings.
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    shared: Arc<Shared>,
}

impl Kernel {
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

/// One recorded command of a batch; recorded into Vulkan only when the batch is complete.
enum Command<'a> {
    Dispatch { kernel: &'a Kernel, buffers: Vec<&'a Buffer>, push_constants: Vec<u8>, groups: [u32; 3] },
    FillZero(&'a Buffer),
    Copy { src: &'a Buffer, dst: &'a Buffer },
}

/// Collects the commands of one [`GpuContext::run`]. Commands execute in order, each after the
/// previous one's writes are visible.
pub struct Recorder<'a> {
    context: &'a GpuContext,
    commands: Vec<Command<'a>>,
}

impl<'a> Recorder<'a> {
    /// Dispatches `groups` workgroups of `kernel` with `buffers` bound to bindings 0..n in order
    /// and `push_constants` as the kernel's push-constant block (its exact size; empty for none).
    pub fn dispatch(
        &mut self,
        kernel: &'a Kernel,
        buffers: &[&'a Buffer],
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<(), GpuError> {
        self.context.check_same_context(&kernel.shared, &kernel.name)?;
        for buffer in buffers {
            self.context.check_same_context(&buffer.shared, buffer.name())?;
        }
        if buffers.len() != kernel.binding_count as usize {
            return Err(GpuError::BindingCount {
                kernel: kernel.name.clone(),
                given: buffers.len(),
                expected: kernel.binding_count,
            });
        }
        if push_constants.len() != kernel.push_constant_size as usize {
            return Err(GpuError::PushConstantSize {
                kernel: kernel.name.clone(),
                given: push_constants.len(),
                expected: kernel.push_constant_size,
            });
        }
        let limit = self.context.shared.info.max_compute_workgroup_count;
        if groups.iter().zip(limit).any(|(&g, l)| g > l) {
            return Err(GpuError::TooManyGroups { kernel: kernel.name.clone(), groups, limit });
        }
        self.commands.push(Command::Dispatch {
            kernel,
            buffers: buffers.to_vec(),
            push_constants: push_constants.to_vec(),
            groups,
        });
        Ok(())
    }

    /// Zeroes `buffer` at this point of the batch.
    pub fn fill_zero(&mut self, buffer: &'a Buffer) -> Result<(), GpuError> {
        self.context.check_same_context(&buffer.shared, buffer.name())?;
        self.commands.push(Command::FillZero(buffer));
        Ok(())
    }

    /// Copies all of `src` (its `size()` bytes) to the start of `dst` at this point of the batch.
    pub fn copy(&mut self, src: &'a Buffer, dst: &'a Buffer) -> Result<(), GpuError> {
        self.context.check_same_context(&src.shared, src.name())?;
        self.context.check_same_context(&dst.shared, dst.name())?;
        if src.size() > dst.size() {
            return Err(GpuError::WriteTooLarge { name: dst.name().to_string(), len: src.size(), size: dst.size() });
        }
        self.commands.push(Command::Copy { src, dst });
        Ok(())
    }
}

/// The command buffer, fence and pools every submission goes through, one at a time.
pub(crate) struct Submitter {
    command_pool: vk::CommandPool,
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    /// Reset at every run; recreated larger when a run needs more.
    descriptor_pool: vk::DescriptorPool,
    descriptor_set_capacity: u32,
    descriptor_capacity: u32,
    /// Two timestamps per dispatch; recreated larger when a run needs more.
    query_pool: vk::QueryPool,
    query_capacity: u32,
    shared: Arc<Shared>,
}

impl Submitter {
    pub(crate) fn new(shared: &Arc<Shared>) -> Result<Submitter, GpuError> {
        let device = &shared.device;
        let mut submitter = Submitter {
            command_pool: vk::CommandPool::null(),
            command_buffer: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            descriptor_pool: vk::DescriptorPool::null(),
            descriptor_set_capacity: 0,
            descriptor_capacity: 0,
            query_pool: vk::QueryPool::null(),
            query_capacity: 0,
            shared: shared.clone(),
        };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(shared.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info for this device; the pool is destroyed in Drop.
        submitter.command_pool = unsafe { device.create_command_pool(&pool_info, None) }
            .map_err(|e| GpuError::vk("vkCreateCommandPool", "startup", e))?;
        let alloc_info = vk::CommandBufferAllocateInfo::default()
            .command_pool(submitter.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is live; the buffer is freed with the pool.
        submitter.command_buffer = unsafe { device.allocate_command_buffers(&alloc_info) }
            .map_err(|e| GpuError::vk("vkAllocateCommandBuffers", "startup", e))?[0];
        // SAFETY: valid create info; destroyed in Drop.
        submitter.fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .map_err(|e| GpuError::vk("vkCreateFence", "startup", e))?;
        shared.set_name(submitter.command_buffer, "photonix commands");
        submitter.ensure_descriptors(64, 512)?;
        Ok(submitter)
    }

    /// Makes the descriptor pool hold at least `sets` sets and `descriptors` storage buffers,
    /// and resets it.
    fn ensure_descriptors(&mut self, sets: u32, descriptors: u32) -> Result<(), GpuError> {
        let device = &self.shared.device;
        if sets <= self.descriptor_set_capacity && descriptors <= self.descriptor_capacity {
            // SAFETY: no set from this pool is in use: the previous submission was waited for.
            return unsafe {
                device.reset_descriptor_pool(self.descriptor_pool, vk::DescriptorPoolResetFlags::empty())
            }
            .map_err(|e| GpuError::vk("vkResetDescriptorPool", "descriptor pool", e));
        }
        let sets = sets.max(self.descriptor_set_capacity * 2).max(64);
        let descriptors = descriptors.max(self.descriptor_capacity * 2).max(512);
        // SAFETY: no set from the old pool is in use (see above); null is a no-op.
        unsafe { device.destroy_descriptor_pool(self.descriptor_pool, None) };
        self.descriptor_pool = vk::DescriptorPool::null();
        self.descriptor_set_capacity = 0;
        self.descriptor_capacity = 0;
        let sizes = [vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_BUFFER, descriptor_count: descriptors }];
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(sets).pool_sizes(&sizes);
        // SAFETY: valid create info; destroyed in Drop or when replaced.
        self.descriptor_pool = unsafe { device.create_descriptor_pool(&info, None) }
            .map_err(|e| GpuError::vk("vkCreateDescriptorPool", "descriptor pool", e))?;
        self.descriptor_set_capacity = sets;
        self.descriptor_capacity = descriptors;
        self.shared.set_name(self.descriptor_pool, "photonix descriptors");
        Ok(())
    }

    /// Makes the timestamp query pool hold at least `queries` queries.
    fn ensure_queries(&mut self, queries: u32) -> Result<(), GpuError> {
        if queries <= self.query_capacity {
            return Ok(());
        }
        let device = &self.shared.device;
        let queries = queries.max(self.query_capacity * 2).max(256);
        // SAFETY: the previous submission was waited for, so the old pool is unused; null is a no-op.
        unsafe { device.destroy_query_pool(self.query_pool, None) };
        self.query_pool = vk::QueryPool::null();
        self.query_capacity = 0;
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(queries);
        // SAFETY: valid create info; destroyed in Drop or when replaced.
        self.query_pool = unsafe { device.create_query_pool(&info, None) }
            .map_err(|e| GpuError::vk("vkCreateQueryPool", "timestamps", e))?;
        self.query_capacity = queries;
        self.shared.set_name(self.query_pool, "photonix timestamps");
        Ok(())
    }

    /// Resets the command buffer and begins recording.
    fn begin(&self, label: &str) -> Result<vk::CommandBuffer, GpuError> {
        let device = &self.shared.device;
        let cb = self.command_buffer;
        // SAFETY: the previous submission of `cb` completed (every submission is waited for),
        // and the pool allows resetting single buffers.
        unsafe { device.reset_command_buffer(cb, vk::CommandBufferResetFlags::empty()) }
            .map_err(|e| GpuError::vk("vkResetCommandBuffer", label, e))?;
        let info = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: `cb` is in the initial state after the reset.
        unsafe { device.begin_command_buffer(cb, &info) }
            .map_err(|e| GpuError::vk("vkBeginCommandBuffer", label, e))?;
        // Earlier submissions' transfers and dispatches, and host writes, happen before this one.
        memory_barrier(
            device,
            cb,
            vk::PipelineStageFlags::HOST | vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::HOST_WRITE | vk::AccessFlags::TRANSFER_WRITE | vk::AccessFlags::SHADER_WRITE,
        );
        Ok(cb)
    }

    /// Ends recording, submits, and waits for the GPU to finish.
    fn submit_and_wait(&self, label: &str) -> Result<(), GpuError> {
        let device = &self.shared.device;
        let cb = self.command_buffer;
        // Make every write visible to the host before the fence signals.
        let barrier = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ);
        // SAFETY: `cb` is recording; the barrier has no pointers but the local above.
        unsafe {
            device.cmd_pipeline_barrier(
                cb,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            )
        };
        // SAFETY: `cb` is recording.
        unsafe { device.end_command_buffer(cb) }.map_err(|e| GpuError::vk("vkEndCommandBuffer", label, e))?;
        let buffers = [cb];
        let submit = [vk::SubmitInfo::default().command_buffers(&buffers)];
        // SAFETY: the queue is used only under the submitter lock (held by our caller), `cb` is
        // executable, and the fence is unsignalled.
        unsafe { device.queue_submit(self.shared.queue, &submit, self.fence) }
            .map_err(|e| GpuError::vk("vkQueueSubmit", label, e))?;
        // SAFETY: the fence belongs to this device. No timeout: lavapipe has no watchdog, and a
        // real GPU reports a hang as device loss.
        unsafe { device.wait_for_fences(&[self.fence], true, u64::MAX) }
            .map_err(|e| GpuError::vk("vkWaitForFences", label, e))?;
        // SAFETY: the fence is signalled and no longer used by a pending submission.
        unsafe { device.reset_fences(&[self.fence]) }.map_err(|e| GpuError::vk("vkResetFences", label, e))
    }
}

impl Drop for Submitter {
    fn drop(&mut self) {
        let device = &self.shared.device;
        // SAFETY: waiting for idle ensures nothing below is in use; each handle is owned here
        // and destroyed once (null handles are no-ops).
        unsafe {
            let _ = device.device_wait_idle();
            device.destroy_query_pool(self.query_pool, None);
            device.destroy_descriptor_pool(self.descriptor_pool, None);
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.command_pool, None);
        }
    }
}

/// A global barrier: writes of `src_stages` (`src_access`) become visible to the transfers and
/// dispatches that follow.
fn memory_barrier(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    src_stages: vk::PipelineStageFlags,
    src_access: vk::AccessFlags,
) {
    let barrier = vk::MemoryBarrier::default().src_access_mask(src_access).dst_access_mask(
        vk::AccessFlags::SHADER_READ
            | vk::AccessFlags::SHADER_WRITE
            | vk::AccessFlags::TRANSFER_READ
            | vk::AccessFlags::TRANSFER_WRITE,
    );
    // SAFETY: `cb` is recording (callers only pass the recording command buffer).
    unsafe {
        device.cmd_pipeline_barrier(
            cb,
            src_stages,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[barrier],
            &[],
            &[],
        )
    };
}

impl GpuContext {
    pub(crate) fn lock_submitter(&self) -> MutexGuard<'_, Submitter> {
        self.submitter.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records the commands of `record` into one command buffer, submits it and waits.
    pub(crate) fn one_shot(
        &self,
        label: &str,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<(), GpuError> {
        let submitter = self.lock_submitter();
        let cb = submitter.begin(label)?;
        record(&self.shared.device, cb);
        submitter.submit_and_wait(label)
    }

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
        if spirv.len() < 5 || spirv[0] != SPIRV_MAGIC {
            let reason = if spirv.is_empty() { "empty module".to_string() } else { "no SPIR-V header".to_string() };
            return Err(GpuError::InvalidSpirv { kernel: name.to_string(), reason });
        }
        let limit = self.shared.info.max_push_constants_size;
        if !push_constant_size.is_multiple_of(4) || push_constant_size > limit {
            return Err(GpuError::PushConstantLimit { kernel: name.to_string(), size: push_constant_size, limit });
        }
        let device = &self.shared.device;
        // Each handle lands in `kernel` as soon as it exists, so an early return frees it.
        let mut kernel = Kernel {
            name: name.to_string(),
            binding_count,
            push_constant_size,
            shader: vk::ShaderModule::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            shared: self.shared.clone(),
        };

        let module_info = vk::ShaderModuleCreateInfo::default().code(spirv);
        // SAFETY: `spirv` is a slice of whole words starting with the SPIR-V magic number.
        kernel.shader = unsafe { device.create_shader_module(&module_info, None) }
            .map_err(|e| GpuError::vk("vkCreateShaderModule", name, e))?;
        self.shared.set_name(kernel.shader, name);

        let mut set_layouts = Vec::new();
        if binding_count > 0 {
            let bindings: Vec<vk::DescriptorSetLayoutBinding> = (0..binding_count)
                .map(|b| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
            // SAFETY: valid create info whose pointers refer to `bindings`.
            kernel.set_layout = unsafe { device.create_descriptor_set_layout(&info, None) }
                .map_err(|e| GpuError::vk("vkCreateDescriptorSetLayout", name, e))?;
            self.shared.set_name(kernel.set_layout, name);
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
        self.shared.set_name(kernel.layout, name);

        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(kernel.shader)
            .name(c"main");
        let pipeline_info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(kernel.layout)];
        // SAFETY: the module and layout are live; no pipeline cache is used.
        let pipelines = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &pipeline_info, None) }
            .map_err(|(_, e)| GpuError::vk("vkCreateComputePipelines", name, e))?;
        kernel.pipeline = pipelines[0];
        self.shared.set_name(kernel.pipeline, name);

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
        let mut recorder = Recorder { context: self, commands: Vec::new() };
        record(&mut recorder)?;
        let commands = recorder.commands;
        if commands.is_empty() {
            return self.shared.check_validation();
        }
        let device = &self.shared.device;
        let mut submitter = self.lock_submitter();

        // Descriptor sets: one per dispatch with bindings
        let mut set_count = 0u32;
        let mut descriptor_count = 0u32;
        let mut dispatch_count = 0u32;
        for command in &commands {
            if let Command::Dispatch { kernel, .. } = command {
                dispatch_count += 1;
                if kernel.binding_count > 0 {
                    set_count += 1;
                    descriptor_count += kernel.binding_count;
                }
            }
        }
        submitter.ensure_descriptors(set_count, descriptor_count)?;
        let layouts: Vec<vk::DescriptorSetLayout> = commands
            .iter()
            .filter_map(|c| match c {
                Command::Dispatch { kernel, .. } if kernel.binding_count > 0 => Some(kernel.set_layout),
                _ => None,
            })
            .collect();
        let sets = if layouts.is_empty() {
            Vec::new()
        } else {
            let info = vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(submitter.descriptor_pool)
                .set_layouts(&layouts);
            // SAFETY: the pool was reset and holds enough sets and descriptors for `layouts`.
            unsafe { device.allocate_descriptor_sets(&info) }
                .map_err(|e| GpuError::vk("vkAllocateDescriptorSets", label, e))?
        };
        let mut buffer_infos = Vec::with_capacity(descriptor_count as usize);
        let mut set_index = 0;
        for command in &commands {
            if let Command::Dispatch { kernel, buffers, .. } = command {
                if kernel.binding_count > 0 {
                    let infos: Vec<vk::DescriptorBufferInfo> = buffers
                        .iter()
                        .map(|b| vk::DescriptorBufferInfo { buffer: b.handle, offset: 0, range: b.vk_size })
                        .collect();
                    buffer_infos.push((sets[set_index], infos));
                    set_index += 1;
                }
            }
        }
        let writes: Vec<vk::WriteDescriptorSet> = buffer_infos
            .iter()
            .flat_map(|(set, infos)| {
                infos.iter().enumerate().map(|(binding, info)| {
                    vk::WriteDescriptorSet::default()
                        .dst_set(*set)
                        .dst_binding(binding as u32)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(std::slice::from_ref(info))
                })
            })
            .collect();
        // SAFETY: the sets are freshly allocated and unused; every buffer is live and its range
        // (`vk_size`) is within maxStorageBufferRange, checked at creation.
        unsafe { device.update_descriptor_sets(&writes, &[]) };

        // Timestamps: two per dispatch
        let timed = self.shared.timestamp_valid_bits > 0;
        if timed {
            submitter.ensure_queries(2 * dispatch_count)?;
        }

        // Record
        let cb = submitter.begin(label)?;
        if timed {
            // SAFETY: `cb` is recording and the range lies inside the pool.
            unsafe { device.cmd_reset_query_pool(cb, submitter.query_pool, 0, 2 * dispatch_count) };
        }
        let mut set_index = 0;
        let mut query = 0;
        for (i, command) in commands.iter().enumerate() {
            if i > 0 {
                memory_barrier(
                    device,
                    cb,
                    vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
                );
            }
            match command {
                Command::Dispatch { kernel, push_constants, groups, .. } => {
                    // SAFETY: `cb` is recording; the pipeline, layout and set are live and match
                    // (the set was allocated from this kernel's layout, and the push-constant
                    // size was checked in `dispatch`); the queries lie inside the pool.
                    unsafe {
                        if timed {
                            // Bottom of pipe: written once the previous commands finished.
                            device.cmd_write_timestamp(
                                cb,
                                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                                submitter.query_pool,
                                query,
                            );
                        }
                        device.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, kernel.pipeline);
                        if kernel.binding_count > 0 {
                            device.cmd_bind_descriptor_sets(
                                cb,
                                vk::PipelineBindPoint::COMPUTE,
                                kernel.layout,
                                0,
                                &[sets[set_index]],
                                &[],
                            );
                            set_index += 1;
                        }
                        if !push_constants.is_empty() {
                            device.cmd_push_constants(
                                cb,
                                kernel.layout,
                                vk::ShaderStageFlags::COMPUTE,
                                0,
                                push_constants,
                            );
                        }
                        device.cmd_dispatch(cb, groups[0], groups[1], groups[2]);
                        if timed {
                            device.cmd_write_timestamp(
                                cb,
                                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                                submitter.query_pool,
                                query + 1,
                            );
                        }
                    }
                    query += 2;
                }
                Command::FillZero(buffer) => {
                    // SAFETY: `cb` is recording; the buffer is live with TRANSFER_DST usage and
                    // a size that is a multiple of 4.
                    unsafe { device.cmd_fill_buffer(cb, buffer.handle, 0, vk::WHOLE_SIZE, 0) };
                }
                Command::Copy { src, dst } => {
                    if src.size() > 0 {
                        let region = [vk::BufferCopy::default().size(src.size())];
                        // SAFETY: `cb` is recording; both buffers are live with TRANSFER usage
                        // and the region fits both (checked in `copy`).
                        unsafe { device.cmd_copy_buffer(cb, src.handle, dst.handle, &region) };
                    }
                }
            }
        }
        submitter.submit_and_wait(label)?;

        // Timings
        if timed {
            let mut stamps = vec![0u64; 2 * dispatch_count as usize];
            // SAFETY: the submission completed, so every query in the range is available.
            let read = unsafe {
                device.get_query_pool_results(
                    submitter.query_pool,
                    0,
                    &mut stamps,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
            };
            read.map_err(|e| GpuError::vk("vkGetQueryPoolResults", label, e))?;
            let bits = self.shared.timestamp_valid_bits;
            let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
            let seconds_per_tick = f64::from(self.shared.info.timestamp_period_ns) * 1e-9;
            let mut timings = self.timings.lock().unwrap_or_else(|e| e.into_inner());
            let kernels = commands.iter().filter_map(|c| match c {
                Command::Dispatch { kernel, .. } => Some(kernel),
                _ => None,
            });
            for (kernel, pair) in kernels.zip(stamps.chunks_exact(2)) {
                let seconds = (pair[1].wrapping_sub(pair[0]) & mask) as f64 * seconds_per_tick;
                match timings.iter_mut().find(|(name, _, _)| *name == kernel.name) {
                    Some(entry) => {
                        entry.1 += seconds;
                        entry.2 += 1;
                    }
                    None => timings.push((kernel.name.clone(), seconds, 1)),
                }
            }
        }
        drop(submitter);
        self.shared.check_validation()
    }
}
