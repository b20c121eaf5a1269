//! Batches of commands: [`Recorder`] collects the dispatches, fills and copies of one
//! [`GpuContext::run`](super::GpuContext::run), checks them, and records them into one command
//! buffer with descriptor sets, barriers and timestamps.

use std::sync::Arc;

use ash::vk;

use super::buffer::Buffer;
use super::device::{check_same_device, Shared};
use super::error::GpuError;
use super::kernel::Kernel;
use super::submitter::{memory_barrier, Submitter};

/// One recorded command of a batch; recorded into Vulkan only when the batch is complete.
enum Command<'a> {
    Dispatch { kernel: &'a Kernel, buffers: Vec<&'a Buffer>, push_constants: Vec<u8>, groups: [u32; 3] },
    FillZero(&'a Buffer),
    Copy { src: &'a Buffer, dst: &'a Buffer },
    Update { dst: &'a Buffer, bytes: Vec<u8> },
}

/// The most bytes one [`Recorder::update`] writes (Vulkan's limit for vkCmdUpdateBuffer).
pub const MAX_UPDATE_BYTES: usize = 65536;

/// Collects the commands of one [`GpuContext::run`](super::GpuContext::run). Commands execute
/// in order, each after the previous one's writes are visible.
pub struct Recorder<'a> {
    /// The device of the context that runs the batch; every kernel and buffer must be its own.
    shared: &'a Arc<Shared>,
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
        check_same_device(self.shared, &kernel.shared, &kernel.name)?;
        for buffer in buffers {
            check_same_device(self.shared, &buffer.shared, buffer.name())?;
        }
        let expected = kernel.binding_types.buffer_count(kernel.binding_count);
        if buffers.len() != expected as usize {
            return Err(GpuError::BindingCount { kernel: kernel.name.clone(), given: buffers.len(), expected });
        }
        if push_constants.len() != kernel.push_constant_size as usize {
            return Err(GpuError::PushConstantSize {
                kernel: kernel.name.clone(),
                given: push_constants.len(),
                expected: kernel.push_constant_size,
            });
        }
        let limit = self.shared.info.max_compute_workgroup_count;
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
        check_same_device(self.shared, &buffer.shared, buffer.name())?;
        self.commands.push(Command::FillZero(buffer));
        Ok(())
    }

    /// Copies all of `src` (its `size()` bytes) to the start of `dst` at this point of the batch.
    pub fn copy(&mut self, src: &'a Buffer, dst: &'a Buffer) -> Result<(), GpuError> {
        check_same_device(self.shared, &src.shared, src.name())?;
        check_same_device(self.shared, &dst.shared, dst.name())?;
        if src.size() > dst.size() {
            return Err(GpuError::WriteTooLarge { name: dst.name().to_string(), len: src.size(), size: dst.size() });
        }
        self.commands.push(Command::Copy { src, dst });
        Ok(())
    }

    /// Writes `data` (at most [`MAX_UPDATE_BYTES`], a multiple of 4 bytes) to the start of
    /// `dst` at this point of the batch, from the command buffer itself: small parameter blocks
    /// need no staging buffer and no submission of their own.
    pub fn update<T: bytemuck::Pod>(&mut self, dst: &'a Buffer, data: &[T]) -> Result<(), GpuError> {
        check_same_device(self.shared, &dst.shared, dst.name())?;
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > dst.size() || bytes.len() > MAX_UPDATE_BYTES || !bytes.len().is_multiple_of(4) {
            return Err(GpuError::WriteTooLarge {
                name: dst.name().to_string(),
                len: bytes.len() as u64,
                size: dst.size().min(MAX_UPDATE_BYTES as u64),
            });
        }
        self.commands.push(Command::Update { dst, bytes: bytes.to_vec() });
        Ok(())
    }

    /// An empty batch for the device `shared`.
    pub(super) fn new(shared: &'a Arc<Shared>) -> Recorder<'a> {
        Recorder { shared, commands: Vec::new() }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.commands.is_empty()
    }

    /// Records the batch into `submitter`'s command buffer, with a barrier between consecutive
    /// commands, submits it and waits. Returns each dispatch's kernel name and GPU seconds, in
    /// dispatch order; empty when the queue has no timestamps.
    pub(super) fn submit(self, submitter: &mut Submitter, label: &str) -> Result<Vec<(&'a str, f64)>, GpuError> {
        let commands = self.commands;
        let device = &self.shared.device;

        // Descriptor sets: one per dispatch with bindings
        let mut set_count = 0u32;
        let mut descriptor_count = 0u32;
        let mut dispatch_count = 0u32;
        for command in &commands {
            if let Command::Dispatch { kernel, .. } = command {
                dispatch_count += 1;
                if kernel.binding_count > 0 {
                    set_count += 1;
                    descriptor_count += kernel.binding_types.buffer_count(kernel.binding_count);
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
        let mut views = Vec::new();
        let mut set_index = 0;
        for command in &commands {
            if let Command::Dispatch { kernel, buffers, .. } = command {
                if kernel.binding_count > 0 {
                    // Buffers in binding order, an array binding taking one per element.
                    let mut next = buffers.iter();
                    for binding in 0..kernel.binding_count {
                        for element in 0..kernel.binding_types.descriptor_count(binding) {
                            let b = next.next().expect("`dispatch` checked the buffer count");
                            let at = (sets[set_index], binding, element);
                            if let Some(format) = kernel.binding_types.format(binding) {
                                views.push((at, b.texel_view(format)?));
                            } else {
                                let ty = kernel.binding_types.descriptor_type(binding);
                                let info = vk::DescriptorBufferInfo { buffer: b.handle, offset: 0, range: b.vk_size };
                                buffer_infos.push((at, ty, info));
                            }
                        }
                    }
                    set_index += 1;
                }
            }
        }
        let writes: Vec<vk::WriteDescriptorSet> = buffer_infos
            .iter()
            .map(|((set, binding, element), ty, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(*set)
                    .dst_binding(*binding)
                    .dst_array_element(*element)
                    .descriptor_type(*ty)
                    .buffer_info(std::slice::from_ref(info))
            })
            .chain(views.iter().map(|((set, binding, element), view)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(*set)
                    .dst_binding(*binding)
                    .dst_array_element(*element)
                    .descriptor_type(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                    .texel_buffer_view(std::slice::from_ref(view))
            }))
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
                Command::Update { dst, bytes } => {
                    if !bytes.is_empty() {
                        // SAFETY: `cb` is recording; the buffer is live with TRANSFER_DST usage,
                        // and `update` checked the size (a multiple of 4, within the buffer and
                        // Vulkan's 65536 bytes).
                        unsafe { device.cmd_update_buffer(cb, dst.handle, 0, bytes) };
                    }
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
        let mut dispatch_seconds = Vec::with_capacity(dispatch_count as usize);
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
            let kernels = commands.iter().filter_map(|c| match c {
                Command::Dispatch { kernel, .. } => Some(kernel),
                _ => None,
            });
            for (kernel, pair) in kernels.zip(stamps.chunks_exact(2)) {
                let seconds = (pair[1].wrapping_sub(pair[0]) & mask) as f64 * seconds_per_tick;
                dispatch_seconds.push((kernel.name.as_str(), seconds));
            }
        }
        Ok(dispatch_seconds)
    }
}
