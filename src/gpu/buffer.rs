//! Named Vulkan buffers with their memory, and host access through their mapping.
//!
//! Storage buffers live in `GpuOnly` memory; staging (`CpuToGpu`) and readback (`GpuToCpu`)
//! buffers are mapped. The copies between them and the host are [`GpuContext`]'s (`upload`,
//! `download`, ...).
//!
//! [`GpuContext`]: super::GpuContext

use std::sync::{Arc, OnceLock};

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::device::Shared;
use super::error::GpuError;

/// Every Vulkan buffer is a multiple of this many bytes and at least this big, so empty data
/// still makes a valid buffer and `vkCmdFillBuffer` sizes are multiples of 4.
const GRANULE: u64 = 16;

/// A named Vulkan buffer and its memory. Frees both when dropped; it keeps the device alive, so
/// it may outlive its [`GpuContext`](super::GpuContext).
pub struct Buffer {
    name: String,
    /// Bytes the caller asked for (may be 0).
    size: u64,
    /// Bytes of the Vulkan buffer: `size` rounded up to a multiple of 16, at least 16.
    pub(super) vk_size: u64,
    pub(super) handle: vk::Buffer,
    allocation: Option<Allocation>,
    /// The RGBA32UI (0) and R32UI (1) views kernels with texel bindings read it through, each
    /// made on first use.
    texel_views: [OnceLock<vk::BufferView>; 2],
    pub(super) shared: Arc<Shared>,
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

    /// A device-local storage buffer of `size` bytes (not cleared), after checking the device's
    /// limits.
    pub(super) fn create_storage(shared: &Arc<Shared>, name: &str, size: u64) -> Result<Buffer, GpuError> {
        let limit = shared.info.max_storage_buffer_range;
        if size.max(GRANULE).div_ceil(GRANULE) * GRANULE > limit {
            return Err(GpuError::BufferTooLarge {
                name: name.to_string(),
                size,
                limit_name: "maxStorageBufferRange",
                limit,
            });
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
            | vk::BufferUsageFlags::UNIFORM_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        Buffer::create(shared, name, size, usage, MemoryLocation::GpuOnly)
    }

    /// Creates a buffer of `size` bytes with `usage` in `location`, bound to fresh memory.
    pub(super) fn create(
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
        let mut buffer = Buffer {
            name: name.to_string(),
            size,
            vk_size,
            handle,
            allocation: None,
            texel_views: [OnceLock::new(), OnceLock::new()],
            shared: shared.clone(),
        };
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

    /// The whole buffer as texels of `format` (RGBA32UI or R32UI), for kernels that bind it as
    /// a uniform texel buffer; made on first use and kept as long as the buffer.
    pub(super) fn texel_view(&self, format: vk::Format) -> Result<vk::BufferView, GpuError> {
        let (cell, texel_bytes) = match format {
            vk::Format::R32G32B32A32_UINT => (&self.texel_views[0], 16),
            vk::Format::R32_UINT => (&self.texel_views[1], 4),
            _ => unreachable!("BindingTypes only names RGBA32UI and R32UI"),
        };
        if let Some(view) = cell.get() {
            return Ok(*view);
        }
        let limit = self.shared.info.max_texel_buffer_elements;
        if self.vk_size / texel_bytes > limit {
            return Err(GpuError::BufferTooLarge {
                name: self.name.clone(),
                size: self.size,
                limit_name: "maxTexelBufferElements times the texel size",
                limit: limit.saturating_mul(texel_bytes),
            });
        }
        let info = vk::BufferViewCreateInfo::default().buffer(self.handle).format(format).offset(0).range(self.vk_size);
        // SAFETY: the buffer is live, was created with UNIFORM_TEXEL_BUFFER usage (storage
        // buffers are), its size is a multiple of 16 bytes and within the limit checked above;
        // both formats are required of every Vulkan device for uniform texel buffers.
        let view = unsafe { self.shared.device.create_buffer_view(&info, None) }
            .map_err(|e| GpuError::vk("vkCreateBufferView", &self.name, e))?;
        if let Err(view) = cell.set(view) {
            // SAFETY: the view was just made and is not used anywhere.
            unsafe { self.shared.device.destroy_buffer_view(view, None) };
        }
        Ok(*cell.get().expect("set above"))
    }

    /// The host address of the buffer's memory, when it is mapped and coherent.
    pub(super) fn host_ptr(&self) -> Option<*mut u8> {
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
    pub(super) fn write_mapped(&self, ptr: *mut u8, bytes: &[u8], zero_to: u64) {
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
    pub(super) fn read_mapped(&self, ptr: *const u8, out: &mut [u8]) {
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
        // recorded it returned, and the buffer is destroyed exactly once, after its view.
        unsafe {
            for cell in &mut self.texel_views {
                if let Some(view) = cell.take() {
                    self.shared.device.destroy_buffer_view(view, None);
                }
            }
            self.shared.device.destroy_buffer(self.handle, None)
        };
        if let (Some(allocation), Some(allocator)) = (self.allocation.take(), guard.as_mut()) {
            // Freeing can only fail on a bookkeeping bug in the allocator; nothing to do then.
            let _ = allocator.free(allocation);
        }
    }
}
