//! The scene arrays on the device: uploaded once, updated in place.

use crate::gpu::{Buffer, GpuContext, GpuError};
use crate::layout::constants::{NO_TEXTURE, SCENE_BINDINGS, SCENE_PAGES};
use crate::layout::Medium;
use crate::limits::fmt_bytes;
use crate::render::photons::PhotonSettings;
use crate::render::prepare::KernelVariant;
use crate::render::{photon_frame, SceneBuffers};

/// The scene arrays on the device.
pub struct DeviceScene {
    pub frame: Buffer,
    pub nodes: PagedArray,
    pub primitives: PagedArray,
    pub materials: PagedArray,
    pub lights: PagedArray,
    pub textures: PagedArray,
    pub texture_data: PagedArray,
    pub shape_data: PagedArray,
    pub media: PagedArray,
    /// How the arrays are split into pages.
    pub page: PageSize,
    /// Which variant of the scene kernels the scene needs, with its pages.
    pub variant: KernelVariant,
}

/// The size of one page of a scene array: a power of two of bytes that one texel view of R32UI
/// words (`maxTexelBufferElements`), one storage binding (`maxStorageBufferRange`) and one
/// allocation (`maxMemoryAllocationSize`) all hold, so a page is a shift and a mask in the
/// kernels. 128 MiB on lavapipe (its storage range), 512 MiB on GPUs whose views hold 2^27
/// texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageSize {
    pub bytes: u64,
    /// The device limit that sets it (or the environment variable that lowered it).
    pub limit: &'static str,
}

/// Lowers the page size (bytes, a power of two of at least 16): a test-only way to split the
/// small scenes of the test suite over several pages.
pub const PAGE_BYTES_VAR: &str = "PHOTONIX_GPU_PAGE_BYTES";

impl PageSize {
    /// The device's page size, lowered by `PHOTONIX_GPU_PAGE_BYTES` when that is set.
    pub fn for_device(ctx: &GpuContext) -> Result<PageSize, GpuError> {
        let info = ctx.info();
        let limits = [
            (info.max_storage_buffer_range, "maxStorageBufferRange"),
            (info.max_texel_buffer_elements.saturating_mul(4), "maxTexelBufferElements (R32UI words)"),
            (info.max_memory_allocation_size, "maxMemoryAllocationSize"),
        ];
        let (most, limit) = limits.into_iter().min_by_key(|l| l.0).expect("three limits");
        // The largest power of two within it; the kernels need at least 4 words (an RGBA texel).
        let mut page = PageSize { bytes: 1u64 << most.max(16).ilog2(), limit };
        if let Ok(v) = std::env::var(PAGE_BYTES_VAR) {
            let bytes = PageSize::parse_override(&v)?;
            if bytes < page.bytes {
                page = PageSize { bytes, limit: PAGE_BYTES_VAR };
            }
        }
        Ok(page)
    }

    /// The bytes `PHOTONIX_GPU_PAGE_BYTES` gives, or why they cannot be a page.
    pub fn parse_override(v: &str) -> Result<u64, GpuError> {
        v.trim().parse::<u64>().ok().filter(|b| b.is_power_of_two() && *b >= 16).ok_or_else(|| {
            GpuError::Unsupported(format!("{PAGE_BYTES_VAR}={v:?}: give a power of two of at least 16 bytes"))
        })
    }

    /// log2 of the words in a page (`SCENE_PAGE_WORDS_LOG2` in shaders/scene_bindings.glsl).
    pub fn words_log2(self) -> u32 {
        self.bytes.ilog2() - 2
    }
}

/// One scene array on the device, split into pages of [`PageSize`] bytes (one, for all but the
/// largest arrays), each its own buffer and texel view; the kernels find texel `i` in page
/// `i >> log2` (shaders/scene_fetch.glsl).
pub struct PagedArray {
    name: &'static str,
    /// What the array holds, for messages.
    what: &'static str,
    size: u64,
    pages: Vec<Buffer>,
}

impl PagedArray {
    fn upload(
        ctx: &GpuContext,
        name: &'static str,
        what: &'static str,
        bytes: &[u8],
        page: PageSize,
    ) -> Result<PagedArray, GpuError> {
        let count = (bytes.len() as u64).div_ceil(page.bytes).max(1);
        if count > SCENE_PAGES as u64 {
            return Err(GpuError::Unsupported(format!(
                "{what} need {}, more than the {SCENE_PAGES} pages of {} ({}) this device binds per scene array; \
                 use smaller images or fewer shapes, or --backend cpu",
                fmt_bytes(bytes.len() as u64),
                fmt_bytes(page.bytes),
                page.limit
            )));
        }
        let pages = if bytes.is_empty() {
            vec![ctx.upload(name, bytes)?]
        } else {
            let chunks = bytes.chunks(page.bytes as usize).enumerate();
            chunks.map(|(k, chunk)| ctx.upload(&page_name(name, k), chunk)).collect::<Result<_, _>>()?
        };
        Ok(PagedArray { name, what, size: bytes.len() as u64, pages })
    }

    /// Bytes of the array (its pages together).
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Pages the array takes (at least 1).
    pub fn page_count(&self) -> u32 {
        self.pages.len() as u32
    }

    /// The binding's `SCENE_PAGES` buffers: the pages, then the first again for the pages the
    /// array does not use (every descriptor of an array must be valid; the kernels never read them).
    fn bindings(&self) -> impl Iterator<Item = &Buffer> {
        (0..SCENE_PAGES as usize).map(|k| self.pages.get(k).unwrap_or(&self.pages[0]))
    }

    /// Replaces the contents with `bytes`: written into the pages when the size is the same
    /// (returns true), uploaded anew otherwise.
    fn replace(&mut self, ctx: &GpuContext, bytes: &[u8], page: PageSize) -> Result<bool, GpuError> {
        if bytes.len() as u64 == self.size {
            for (buffer, chunk) in self.pages.iter().zip(bytes.chunks(page.bytes as usize)) {
                ctx.write(buffer, chunk)?;
            }
            return Ok(true);
        }
        *self = PagedArray::upload(ctx, self.name, self.what, bytes, page)?;
        Ok(false)
    }
}

fn page_name(name: &str, k: usize) -> String {
    if k == 0 {
        name.to_string()
    } else {
        format!("{name} page {k}")
    }
}

impl DeviceScene {
    pub fn upload(
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<Self, GpuError> {
        let frame = photon_frame(buffers, photons);
        let page = PageSize::for_device(ctx)?;
        let up = |name, what, bytes| PagedArray::upload(ctx, name, what, bytes, page);
        let mut scene = DeviceScene {
            frame: ctx.upload("frame", std::slice::from_ref(&frame))?,
            nodes: up("bvh_nodes", "the scene's BVH", bytes_of(&buffers.nodes))?,
            primitives: up("primitives", "the scene's primitives", bytes_of(&buffers.primitives))?,
            materials: up("materials", "the scene's materials", bytes_of(&buffers.materials))?,
            lights: up("lights", "the scene's lights", bytes_of(&buffers.lights))?,
            textures: up("textures", "the scene's textures", bytes_of(&buffers.textures))?,
            texture_data: up(
                "texture_data",
                "the scene's image and pattern textures",
                bytes_of(&buffers.texture_data),
            )?,
            shape_data: up("shape_data", "the scene's shape data (normals, uv)", bytes_of(&buffers.shape_data))?,
            media: up("media", "the scene's media", bytes_of(device_media(buffers)))?,
            page,
            variant: buffers.variant(),
        };
        scene.variant = scene.paged_variant(buffers);
        Ok(scene)
    }

    /// `buffers`' variant with the pages its arrays take on the device.
    fn paged_variant(&self, buffers: &SceneBuffers) -> KernelVariant {
        let arrays = self.arrays();
        let pages = arrays.iter().map(|a| a.page_count()).max().unwrap_or(1);
        buffers.variant().with_pages(pages, self.page.words_log2())
    }

    fn arrays(&self) -> [&PagedArray; 8] {
        [
            &self.nodes,
            &self.primitives,
            &self.materials,
            &self.lights,
            &self.textures,
            &self.texture_data,
            &self.shape_data,
            &self.media,
        ]
    }

    /// Replaces the scene's arrays with those of `buffers`: an array of the same byte size is
    /// written into its existing buffer, any other gets a new buffer. Returns how many arrays were
    /// written in place (of 9).
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<u32, GpuError> {
        Ok(self.update_changed(ctx, buffers, photons, None)?.0)
    }

    /// [`DeviceScene::update`], leaving alone each array equal to that of `previous` (the scene
    /// and photon settings the device holds): an editor's change of one material writes the
    /// material array only. Returns how many arrays kept their buffer (of 9; unchanged ones
    /// count) and the names of the arrays written.
    pub fn update_changed(
        &mut self,
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
        previous: Option<(&SceneBuffers, Option<&PhotonSettings>)>,
    ) -> Result<(u32, Vec<&'static str>), GpuError> {
        let page = self.page;
        let mut written = Vec::new();
        let mut kept = 0;
        // The frame: one small uniform buffer.
        let frame = photon_frame(buffers, photons);
        let old_frame = previous.map(|(b, p)| photon_frame(b, p));
        if old_frame.is_some_and(|old| bytemuck::bytes_of(&old) == bytemuck::bytes_of(&frame)) {
            kept += 1;
        } else {
            written.push("frame");
            ctx.write(&self.frame, std::slice::from_ref(&frame))?;
            kept += 1;
        }
        let old = |f: fn(&SceneBuffers) -> &[u8]| previous.map(|(b, _)| f(b));
        let arrays: [(&mut PagedArray, &'static str, ArrayOf); 8] = [
            (&mut self.nodes, "nodes", |b| bytes_of(&b.nodes)),
            (&mut self.primitives, "primitives", |b| bytes_of(&b.primitives)),
            (&mut self.materials, "materials", |b| bytes_of(&b.materials)),
            (&mut self.lights, "lights", |b| bytes_of(&b.lights)),
            (&mut self.textures, "textures", |b| bytes_of(&b.textures)),
            (&mut self.texture_data, "texture_data", |b| bytes_of(&b.texture_data)),
            (&mut self.shape_data, "shape_data", |b| bytes_of(&b.shape_data)),
            (&mut self.media, "media", |b| bytes_of(device_media(b))),
        ];
        for (array, name, of) in arrays {
            let bytes = of(buffers);
            if old(of).is_some_and(|old| old == bytes) && array.size() == bytes.len() as u64 {
                kept += 1;
                continue;
            }
            written.push(name);
            kept += array.replace(ctx, bytes, page)? as u32;
        }
        self.variant = self.paged_variant(buffers);
        Ok((kept, written))
    }

    /// The scene's buffers in binding order (`BINDING_*`, shaders/scene_bindings.glsl), each
    /// array as its `SCENE_PAGES` pages, followed by a kernel's own buffers.
    pub fn bindings<'a>(&'a self, own: &[&'a Buffer]) -> Vec<&'a Buffer> {
        debug_assert_eq!(self.arrays().len() + 1, SCENE_BINDINGS as usize);
        std::iter::once(&self.frame)
            .chain(self.arrays().into_iter().flat_map(PagedArray::bindings))
            .chain(own.iter().copied())
            .collect()
    }
}

/// Where an array's bytes are in a `SceneBuffers`.
type ArrayOf = fn(&SceneBuffers) -> &[u8];

fn bytes_of<T: bytemuck::Pod>(data: &[T]) -> &[u8] {
    bytemuck::cast_slice(data)
}

/// The media as bound: Vulkan has no empty buffers, so a scene without media binds one unused.
fn device_media(buffers: &SceneBuffers) -> &[Medium] {
    const NONE: &[Medium] = &[Medium {
        sigma_a: [0.0; 3],
        phase: 0,
        sigma_s: [0.0; 3],
        g: 0.0,
        emission: [0.0; 3],
        density: NO_TEXTURE,
        bounds_min: [0.0; 3],
        majorant: 0.0,
        bounds_max: [0.0; 3],
        _pad: 0,
    }];
    if buffers.media.is_empty() {
        NONE
    } else {
        &buffers.media
    }
}
