//! Named storage buffers and the copies between them and the host.
//!
//! Storage buffers live in `GpuOnly` memory. Data goes through a `CpuToGpu` staging buffer and
//! comes back through a `GpuToCpu` readback buffer, as a discrete GPU needs. Where the
//! device-local memory is also host-visible and coherent (lavapipe's single heap, many integrated
//! GPUs) the copies go straight through the mapping instead, which saves a second copy of every
//! buffer in the one heap; [`GpuContext::set_force_staging`] turns that shortcut off.

use std::sync::atomic::Ordering;
use std::sync::Arc;

use ash::vk;
use bytemuck::Pod;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::context::{GpuContext, Shared};
use super::GpuError;

/// Every Vulkan buffer is a multiple of this many bytes and at least this big, so empty data
/// still makes a valid buffer and `vkCmdFillBuffer` sizes are multiples of 4.
const GRANULE: u64 = 16;

/// A named Vulkan buffer and its memory. Frees both when dropped; it keeps the device alive, so
/// it may outlive its [`GpuContext`].
pub struct Buffer {
    name: String,
    /// Bytes the caller asked for (may be 0).
    size: u64,
    /// Bytes of the Vulkan buffer: `size` rounded up to a multiple of 16, at least 16.
    pub(crate) vk_size: u64,
    pub(crate) handle: vk::Buffer,
    allocation: Option<Allocation>,
    pub(crate) shared: Arc<Shared>,
}

impl Buffer {
    /// The name given at creation, used in messages and validation reports.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The size in bytes the caller asked for (the Vulkan buffer may be up to 16 bytes larger).
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Creates a buffer of `size` bytes with `usage` in `location`, bound to fresh memory.
    pub(crate) fn create(
        shared: &Arc<Shared>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer, GpuError> {
        let vk_size = size.max(GRANULE).div_ceil(GRANULE) * GRANULE;
        let limit = shared.info.max_memory_allocation_size;
        if vk_size > limit {
            return Err(GpuError::BufferTooLarge {
                name: name.to_string(),
                size,
                limit_name: "maxMemoryAllocationSize",
                limit,
            });
        }
        let device = &shared.device;
        let info = vk::BufferCreateInfo::default().size(vk_size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: `info` is a valid create info and the device outlives the buffer (`shared`).
        let handle = unsafe { device.create_buffer(&info, None) }
            .map_err(|e| GpuError::vk_alloc("vkCreateBuffer", name, size, e))?;
        // From here on, `buffer`'s Drop cleans up whatever part was made.
        let mut buffer =
            Buffer { name: name.to_string(), size, vk_size, handle, allocation: None, shared: shared.clone() };
        // SAFETY: `handle` is a live buffer of this device.
        let requirements = unsafe { device.get_buffer_memory_requirements(handle) };
        let allocation = {
            let mut guard = shared.allocator();
            let allocator = guard.as_mut().expect("the allocator lives as long as any Arc of Shared");
            allocator
                .allocate(&AllocationCreateDesc {
                    name,
                    requirements,
                    location,
                    linear: true,
                    allocation_scheme: AllocationScheme::GpuAllocatorManaged,
                })
                .map_err(|e| GpuError::allocator(name, size, e))?
        };
        // SAFETY: the memory range comes from the allocator for exactly these requirements and
        // the buffer has no memory bound yet.
        let bound = unsafe { device.bind_buffer_memory(handle, allocation.memory(), allocation.offset()) };
        buffer.allocation = Some(allocation);
        bound.map_err(|e| GpuError::vk_alloc("vkBindBufferMemory", name, size, e))?;
        shared.set_name(handle, name);
        Ok(buffer)
    }

    /// The host address of the buffer's memory, when it is mapped and coherent.
    fn host_ptr(&self) -> Option<*mut u8> {
        let allocation = self.allocation.as_ref()?;
        let coherent = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        if !allocation.memory_properties().contains(coherent) {
            return None;
        }
        allocation.mapped_ptr().map(|p| p.as_ptr().cast::<u8>())
    }

    /// Copies `bytes` to offset 0 and zeroes the rest up to `zero_to` bytes, through the mapping.
    ///
    /// The caller holds the context's submitter lock, so no GPU work runs meanwhile.
    fn write_mapped(&self, ptr: *mut u8, bytes: &[u8], zero_to: u64) {
        assert!(
            bytes.len() as u64 <= self.vk_size && zero_to <= self.vk_size,
            "callers check sizes against the buffer"
        );
        // SAFETY: `ptr` maps at least `vk_size` bytes of this buffer's memory, nothing else
        // accesses it now (no GPU work is in flight while the submitter lock is held), and the
        // source is a separate host slice.
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr, bytes.len());
            if zero_to > bytes.len() as u64 {
                std::ptr::write_bytes(ptr.add(bytes.len()), 0, (zero_to - bytes.len() as u64) as usize);
            }
        }
    }

    /// Copies the first `out.len()` bytes of the buffer through the mapping.
    fn read_mapped(&self, ptr: *const u8, out: &mut [u8]) {
        assert!(out.len() as u64 <= self.vk_size, "callers check sizes against the buffer");
        // SAFETY: as in `write_mapped`; the GPU's writes were made visible to the host by the
        // barrier at the end of every submission and the fence wait.
        unsafe { std::ptr::copy_nonoverlapping(ptr, out.as_mut_ptr(), out.len()) };
    }
}

impl std::fmt::Debug for Buffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Buffer").field("name", &self.name).field("size", &self.size).finish()
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        let mut guard = self.shared.allocator();
        // SAFETY: every submission that used this buffer was waited for before the call that
        // recorded it returned, and the buffer is destroyed exactly once.
        unsafe { self.shared.device.destroy_buffer(self.handle, None) };
        if let (Some(allocation), Some(allocator)) = (self.allocation.take(), guard.as_mut()) {
            // Freeing can only fail on a bookkeeping bug in the allocator; nothing to do then.
            let _ = allocator.free(allocation);
        }
    }
}

impl GpuContext {
    /// A device-local storage buffer created after checking the device's limits.
    fn create_storage(&self, name: &str, size: u64) -> Result<Buffer, GpuError> {
        let limit = self.shared.info.max_storage_buffer_range;
        if size.max(GRANULE).div_ceil(GRANULE) * GRANULE > limit {
            return Err(GpuError::BufferTooLarge {
                name: name.to_string(),
                size,
                limit_name: "maxStorageBufferRange",
                limit,
            });
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        Buffer::create(&self.shared, name, size, usage, MemoryLocation::GpuOnly)
    }

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
        let buffer = self.create_storage(name, bytes.len() as u64)?;
        self.write_bytes(&buffer, bytes, buffer.vk_size, &format!("upload `{name}`"))?;
        self.shared.check_validation()?;
        Ok(buffer)
    }

    /// Zero-filled device-local storage buffer of `size` bytes.
    pub fn create_buffer(&self, name: &str, size: u64) -> Result<Buffer, GpuError> {
        let buffer = self.create_storage(name, size)?;
        self.zero(&buffer, &format!("create `{name}`"))?;
        self.shared.check_validation()?;
        Ok(buffer)
    }

    /// Overwrites the start of `buffer` with `data`; the rest keeps its contents.
    pub fn write<T: Pod>(&self, buffer: &Buffer, data: &[T]) -> Result<(), GpuError> {
        self.check_same_context(&buffer.shared, &buffer.name)?;
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > buffer.size {
            return Err(GpuError::WriteTooLarge {
                name: buffer.name.clone(),
                len: bytes.len() as u64,
                size: buffer.size,
            });
        }
        self.write_bytes(buffer, bytes, 0, &format!("write `{}`", buffer.name))?;
        self.shared.check_validation()
    }

    /// The whole buffer (`size()` bytes) as `T`s, through a readback buffer.
    pub fn download<T: Pod>(&self, buffer: &Buffer) -> Result<Vec<T>, GpuError> {
        self.check_same_context(&buffer.shared, &buffer.name)?;
        let element_size = size_of::<T>();
        if element_size == 0 {
            return Ok(Vec::new());
        }
        if !buffer.size.is_multiple_of(element_size as u64) {
            return Err(GpuError::ElementSizeMismatch { name: buffer.name.clone(), size: buffer.size, element_size });
        }
        let mut out = vec![T::zeroed(); (buffer.size / element_size as u64) as usize];
        if out.is_empty() {
            return Ok(out);
        }
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        let label = format!("download `{}`", buffer.name);
        if let Some(ptr) = self.direct_ptr(buffer) {
            let _submitter = self.lock_submitter();
            buffer.read_mapped(ptr, dst);
        } else {
            let readback = Buffer::create(
                &self.shared,
                &format!("{} readback", buffer.name),
                buffer.size,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;
            let region = [vk::BufferCopy::default().size(buffer.size)];
            self.one_shot(&label, |device, cb| {
                // SAFETY: both buffers are live, the region lies inside both, and the command
                // buffer is recording.
                unsafe { device.cmd_copy_buffer(cb, buffer.handle, readback.handle, &region) };
            })?;
            let ptr = readback.host_ptr().expect("GpuToCpu memory is host-visible, coherent and mapped");
            readback.read_mapped(ptr, dst);
        }
        self.shared.check_validation()?;
        Ok(out)
    }

    /// Sets every byte of `buffer` to zero.
    pub fn fill_zero(&self, buffer: &Buffer) -> Result<(), GpuError> {
        self.check_same_context(&buffer.shared, &buffer.name)?;
        self.zero(buffer, &format!("fill_zero `{}`", buffer.name))?;
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
        let staging = Buffer::create(
            &self.shared,
            &format!("{} staging", buffer.name),
            copy_size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let ptr = staging.host_ptr().expect("CpuToGpu memory is host-visible, coherent and mapped");
        staging.write_mapped(ptr, bytes, copy_size);
        let region = [vk::BufferCopy::default().size(copy_size)];
        self.one_shot(label, |device, cb| {
            // SAFETY: both buffers are live, the region lies inside both (`copy_size` is at most
            // the target's `vk_size`), and the command buffer is recording.
            unsafe { device.cmd_copy_buffer(cb, staging.handle, buffer.handle, &region) };
        })
    }
}
