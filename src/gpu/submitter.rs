//! The one command buffer every submission goes through, with its fence and its descriptor and
//! timestamp pools. The context holds it behind a mutex, so submissions run one at a time and
//! each returns after the GPU finished it.

use std::sync::Arc;

use ash::vk;

use super::device::Shared;
use super::error::GpuError;

/// The command buffer, fence and pools every submission goes through, one at a time.
pub(super) struct Submitter {
    command_pool: vk::CommandPool,
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    /// Reset at every run; recreated larger when a run needs more.
    pub(super) descriptor_pool: vk::DescriptorPool,
    descriptor_set_capacity: u32,
    descriptor_capacity: u32,
    /// Two timestamps per dispatch; recreated larger when a run needs more.
    pub(super) query_pool: vk::QueryPool,
    query_capacity: u32,
    shared: Arc<Shared>,
}

impl Submitter {
    pub(super) fn new(shared: &Arc<Shared>) -> Result<Submitter, GpuError> {
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

    /// Makes the descriptor pool hold at least `sets` sets and `descriptors` storage, texel and uniform buffers each,
    /// and resets it.
    pub(super) fn ensure_descriptors(&mut self, sets: u32, descriptors: u32) -> Result<(), GpuError> {
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
        // Either kind may take all the descriptors of a batch.
        let sizes = [
            vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_BUFFER, descriptor_count: descriptors },
            vk::DescriptorPoolSize { ty: vk::DescriptorType::UNIFORM_TEXEL_BUFFER, descriptor_count: descriptors },
            vk::DescriptorPoolSize { ty: vk::DescriptorType::UNIFORM_BUFFER, descriptor_count: descriptors },
        ];
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
    pub(super) fn ensure_queries(&mut self, queries: u32) -> Result<(), GpuError> {
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
    pub(super) fn begin(&self, label: &str) -> Result<vk::CommandBuffer, GpuError> {
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

    /// Records the commands of `record` into the command buffer, submits it and waits.
    pub(super) fn one_shot(
        &self,
        label: &str,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<(), GpuError> {
        let cb = self.begin(label)?;
        record(&self.shared.device, cb);
        self.submit_and_wait(label)
    }

    /// Ends recording, submits, and waits for the GPU to finish.
    pub(super) fn submit_and_wait(&self, label: &str) -> Result<(), GpuError> {
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
pub(super) fn memory_barrier(
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
