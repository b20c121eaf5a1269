//! Rendering on a Vulkan device: photon tracing, the grid build and the camera kernel.

use std::cell::OnceCell;
use std::time::{Duration, Instant};

use super::photons::{caustic_emit_params, emit_params, map_grid, radii, volume_radius, PhotonMaps, PhotonSettings};
use super::prepare::KernelVariant;
use super::{
    parts_per_sample, photon_frame, resolve_band, unit_paths, work_units, Layers, RenderOutput, RenderStats,
    SceneBuffers,
};
use crate::gpu::{BindingTypes, Buffer, GpuContext, GpuError, Kernel};
use crate::layout::constants::{
    BINDING_FRAME, BINDING_LIGHTS, BINDING_MATERIALS, BINDING_MEDIA, BINDING_NODES, BINDING_PRIMITIVES,
    BINDING_SHAPE_DATA, BINDING_TEXTURES, BINDING_TEXTURE_DATA, LAYER_COUNT, NO_TEXTURE, SCAN_BLOCK, SCENE_BINDINGS,
    WORKGROUP_SIZE,
};
use crate::layout::{DispatchRange, EmitParams, GridParams, Medium, Photon};

/// Bytes of accumulation per pixel: one vec4 per layer.
const ACCUMULATION_BYTES_PER_PIXEL: u64 = 16 * LAYER_COUNT as u64;
/// Camera-path parts per submission of the camera kernel.
const PATHS_PER_SUBMIT: u64 = 1 << 18;
/// Photon paths per `emit_photons` dispatch.
const PATHS_PER_DISPATCH: u32 = 1 << 18;
/// First guess of photons stored per path; the buffer grows (and the pass is traced again) when
/// a scene stores more.
const INITIAL_PHOTONS_PER_PATH: u64 = 4;

fn kernel(
    ctx: &GpuContext,
    name: &str,
    bindings: u32,
    binding_types: BindingTypes,
    push_bytes: usize,
    constants: &[u32],
) -> Result<Kernel, GpuError> {
    let spirv = crate::shaders::spirv(name).expect("build.rs embeds every kernel in shaders/");
    ctx.create_specialized_kernel(name, &spirv, bindings, binding_types, push_bytes as u32, constants)
}

/// How the kernels read the scene (shaders/scene_bindings.glsl): as texel buffers, since on
/// lavapipe a texel fetch goes through gallivm's vectorised texture path where a storage-buffer
/// read costs about 15 scalar instructions per lane and word; `frame`, which every lane reads
/// alike, as a uniform buffer, whose uniform reads gallivm makes once for all lanes.
pub const SCENE_BINDING_TYPES: BindingTypes = BindingTypes {
    rgba: 1 << BINDING_NODES
        | 1 << BINDING_PRIMITIVES
        | 1 << BINDING_MATERIALS
        | 1 << BINDING_LIGHTS
        | 1 << BINDING_TEXTURES
        | 1 << BINDING_MEDIA,
    words: 1 << BINDING_TEXTURE_DATA | 1 << BINDING_SHAPE_DATA,
    uniform: 1 << BINDING_FRAME,
};
/// The camera kernel's: also its photon maps and bucket starts (bindings SCENE_BINDINGS + 2..8)
/// as texel buffers and the grid parameters (SCENE_BINDINGS + 1) as a uniform buffer.
const RENDER_BINDING_TYPES: BindingTypes = BindingTypes {
    rgba: SCENE_BINDING_TYPES.rgba | 0b01_0101 << (SCENE_BINDINGS + 2),
    words: SCENE_BINDING_TYPES.words | 0b10_1010 << (SCENE_BINDINGS + 2),
    uniform: SCENE_BINDING_TYPES.uniform | 1 << (SCENE_BINDINGS + 1),
};

/// grid_rank's (shaders/grid_rank.comp): bucket starts (binding 1) as words, the scattered photons
/// (binding 2) as RGBA32UI texels, since every invocation reads its whole bucket.
const GRID_RANK_BINDING_TYPES: BindingTypes = BindingTypes { rgba: 1 << 2, words: 1 << 1, uniform: 0 };

/// Workgroups for a one-dimensional launch, spread over x and y so that neither passes 32768
/// (the kernels rebuild the index with GLOBAL_INDEX and skip the surplus).
fn groups(invocations: u32) -> [u32; 3] {
    const MAX_X: u32 = 1 << 15;
    let total = invocations.div_ceil(WORKGROUP_SIZE).max(1);
    let x = total.min(MAX_X);
    [x, total.div_ceil(x), 1]
}

/// The compute pipelines of a render, each created on first use and then kept: creating them
/// (shader compilation, on lavapipe through LLVM) is the largest fixed cost of a pass.
#[derive(Default)]
pub struct GpuKernels {
    emit_photons: OnceCell<Kernel>,
    grid_count: OnceCell<Kernel>,
    grid_scan: OnceCell<Kernel>,
    grid_scan_add: OnceCell<Kernel>,
    grid_scatter: OnceCell<Kernel>,
    grid_rank: OnceCell<Kernel>,
    render: OnceCell<Kernel>,
    /// Which build of the scene kernels (`SceneBuffers::variant`).
    variant: KernelVariant,
}

impl GpuKernels {
    /// The kernels of one variant (`SceneBuffers::variant`).
    pub fn for_scene(variant: KernelVariant) -> GpuKernels {
        GpuKernels { variant, ..Default::default() }
    }

    fn variant(&self) -> KernelVariant {
        self.variant
    }

    /// `name` in the build this scene needs.
    fn scene_kernel(&self, name: &str) -> String {
        self.variant.kernel_name(name)
    }

    fn get<'k>(
        cell: &'k OnceCell<Kernel>,
        ctx: &GpuContext,
        name: &str,
        bindings: u32,
        texels: BindingTypes,
        push_bytes: usize,
        constants: &[u32],
    ) -> Result<&'k Kernel, GpuError> {
        if let Some(k) = cell.get() {
            return Ok(k);
        }
        let k = kernel(ctx, name, bindings, texels, push_bytes, constants)?;
        Ok(cell.get_or_init(|| k))
    }

    fn emit_photons(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        let name = self.scene_kernel("emit_photons");
        let constants = self.variant.specialization();
        Self::get(
            &self.emit_photons,
            ctx,
            &name,
            SCENE_BINDINGS + 4,
            SCENE_BINDING_TYPES,
            size_of::<EmitParams>(),
            &constants,
        )
    }
    fn grid_count(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        Self::get(&self.grid_count, ctx, "grid_count", 3, BindingTypes::default(), 0, &[])
    }
    fn grid_scan(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        Self::get(&self.grid_scan, ctx, "grid_scan", 2, BindingTypes::default(), 4, &[])
    }
    fn grid_scan_add(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        Self::get(&self.grid_scan_add, ctx, "grid_scan_add", 2, BindingTypes::default(), 4, &[])
    }
    fn grid_scatter(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        Self::get(&self.grid_scatter, ctx, "grid_scatter", 5, BindingTypes::default(), 0, &[])
    }
    fn grid_rank(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        Self::get(&self.grid_rank, ctx, "grid_rank", 4, GRID_RANK_BINDING_TYPES, 0, &[])
    }
    fn render(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        // The integrator's camera kernel; both take the same bindings (render_pt reads no maps).
        let name = self.scene_kernel(if self.variant.path_traced { "render_pt" } else { "render" });
        let constants = self.variant.specialization();
        Self::get(
            &self.render,
            ctx,
            &name,
            SCENE_BINDINGS + 8,
            RENDER_BINDING_TYPES,
            size_of::<DispatchRange>(),
            &constants,
        )
    }

    /// Creates each kernel once on a fresh set and returns (name, seconds) per kernel: what
    /// keeping the kernels saves per pass (`photonix bench --passes`).
    pub fn time_creation(ctx: &GpuContext) -> Result<Vec<(&'static str, f64)>, GpuError> {
        let k = GpuKernels::default();
        let mut out = Vec::new();
        let mut timed = |name: &'static str, f: &dyn Fn() -> Result<(), GpuError>| -> Result<(), GpuError> {
            let t = Instant::now();
            f()?;
            out.push((name, t.elapsed().as_secs_f64()));
            Ok(())
        };
        timed("emit_photons", &|| k.emit_photons(ctx).map(drop))?;
        timed("grid_count", &|| k.grid_count(ctx).map(drop))?;
        timed("grid_scan", &|| k.grid_scan(ctx).map(drop))?;
        timed("grid_scan_add", &|| k.grid_scan_add(ctx).map(drop))?;
        timed("grid_scatter", &|| k.grid_scatter(ctx).map(drop))?;
        timed("grid_rank", &|| k.grid_rank(ctx).map(drop))?;
        timed("render", &|| k.render(ctx).map(drop))?;
        Ok(out)
    }

    /// Creates now every kernel a render with (`photons` true) or without photon maps uses, so
    /// that the cost falls into set-up rather than into the first pass.
    pub fn create_all(&self, ctx: &GpuContext, photons: bool) -> Result<(), GpuError> {
        if photons {
            self.emit_photons(ctx)?;
            self.grid_count(ctx)?;
            self.grid_scan(ctx)?;
            self.grid_scan_add(ctx)?;
            self.grid_scatter(ctx)?;
            self.grid_rank(ctx)?;
        }
        self.render(ctx)?;
        Ok(())
    }
}

/// The scene arrays on the device.
pub struct DeviceScene {
    pub frame: Buffer,
    pub nodes: Buffer,
    pub primitives: Buffer,
    pub materials: Buffer,
    pub lights: Buffer,
    pub textures: Buffer,
    pub texture_data: Buffer,
    pub shape_data: Buffer,
    pub media: Buffer,
    /// Which variant of the scene kernels the scene needs.
    pub variant: KernelVariant,
}

impl DeviceScene {
    pub fn upload(
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<Self, GpuError> {
        let frame = photon_frame(buffers, photons);
        // Every array is one storage binding: refuse, with what it holds, one the device cannot bind.
        let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
        for (what, bytes) in [
            ("the scene's image and pattern textures", std::mem::size_of_val(buffers.texture_data.as_slice())),
            ("the scene's primitives", std::mem::size_of_val(buffers.primitives.as_slice())),
            ("the scene's BVH", std::mem::size_of_val(buffers.nodes.as_slice())),
            ("the scene's shape data (uv)", std::mem::size_of_val(buffers.shape_data.as_slice())),
        ] {
            if bytes as u64 > limit {
                return Err(GpuError::Unsupported(format!(
                    "{what} need {} MiB, more than one storage buffer holds on this device ({} MiB); use smaller images or fewer shapes, or --backend cpu",
                    (bytes as u64).div_ceil(1 << 20),
                    limit >> 20
                )));
            }
        }
        Ok(DeviceScene {
            frame: ctx.upload("frame", std::slice::from_ref(&frame))?,
            nodes: ctx.upload("bvh_nodes", &buffers.nodes)?,
            primitives: ctx.upload("primitives", &buffers.primitives)?,
            materials: ctx.upload("materials", &buffers.materials)?,
            lights: ctx.upload("lights", &buffers.lights)?,
            textures: ctx.upload("textures", &buffers.textures)?,
            texture_data: ctx.upload("texture_data", &buffers.texture_data)?,
            shape_data: ctx.upload("shape_data", &buffers.shape_data)?,
            media: ctx.upload("media", device_media(buffers))?,
            variant: buffers.variant(),
        })
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
        fn replace<T: bytemuck::Pod>(
            ctx: &GpuContext,
            buffer: &mut Buffer,
            data: &[T],
            old: Option<&[T]>,
            written: &mut Vec<&'static str>,
            name: &'static str,
        ) -> Result<u32, GpuError> {
            let bytes = std::mem::size_of_val(data) as u64;
            if bytes == buffer.size()
                && old.is_some_and(|old| bytemuck::cast_slice::<T, u8>(old) == bytemuck::cast_slice::<T, u8>(data))
            {
                return Ok(1);
            }
            written.push(name);
            if bytes == buffer.size() {
                ctx.write(buffer, data)?;
                Ok(1)
            } else {
                *buffer = ctx.upload(buffer.name(), data)?;
                Ok(0)
            }
        }
        let frame = photon_frame(buffers, photons);
        let old_frame = previous.map(|(b, p)| photon_frame(b, p));
        self.variant = buffers.variant();
        let mut written = Vec::new();
        let w = &mut written;
        let kept = replace(
            ctx,
            &mut self.frame,
            std::slice::from_ref(&frame),
            old_frame.as_ref().map(std::slice::from_ref),
            w,
            "frame",
        )? + replace(ctx, &mut self.nodes, &buffers.nodes, previous.map(|(b, _)| &b.nodes[..]), w, "nodes")?
            + replace(
                ctx,
                &mut self.primitives,
                &buffers.primitives,
                previous.map(|(b, _)| &b.primitives[..]),
                w,
                "primitives",
            )?
            + replace(
                ctx,
                &mut self.materials,
                &buffers.materials,
                previous.map(|(b, _)| &b.materials[..]),
                w,
                "materials",
            )?
            + replace(ctx, &mut self.lights, &buffers.lights, previous.map(|(b, _)| &b.lights[..]), w, "lights")?
            + replace(
                ctx,
                &mut self.textures,
                &buffers.textures,
                previous.map(|(b, _)| &b.textures[..]),
                w,
                "textures",
            )?
            + replace(
                ctx,
                &mut self.texture_data,
                &buffers.texture_data,
                previous.map(|(b, _)| &b.texture_data[..]),
                w,
                "texture_data",
            )?
            + replace(
                ctx,
                &mut self.shape_data,
                &buffers.shape_data,
                previous.map(|(b, _)| &b.shape_data[..]),
                w,
                "shape_data",
            )?
            + replace(ctx, &mut self.media, device_media(buffers), previous.map(|(b, _)| device_media(b)), w, "media")?;
        Ok((kept, written))
    }

    /// The scene's buffers in binding order (`BINDING_*`, shaders/scene_bindings.glsl), followed
    /// by a kernel's own buffers.
    pub fn bindings<'a>(&'a self, own: &[&'a Buffer]) -> Vec<&'a Buffer> {
        let scene = [
            &self.frame,
            &self.nodes,
            &self.primitives,
            &self.materials,
            &self.lights,
            &self.textures,
            &self.texture_data,
            &self.shape_data,
            &self.media,
        ];
        debug_assert_eq!(scene.len(), SCENE_BINDINGS as usize);
        scene.into_iter().chain(own.iter().copied()).collect()
    }
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

/// One photon map on the device: photons sorted by bucket and the bucket starts.
pub struct DeviceMap {
    pub grid: GridParams,
    pub photons: Buffer,
    pub starts: Buffer,
}

/// The maps on the device (global, caustic, volume), plus their grid parameters in one buffer
/// for the camera kernel.
pub struct DeviceMaps {
    pub global: DeviceMap,
    pub caustic: DeviceMap,
    pub volume: DeviceMap,
    pub grids: Buffer,
}

impl DeviceMaps {
    /// Reads the maps back (for tests and tools).
    pub fn download(&self, ctx: &GpuContext) -> Result<PhotonMaps, GpuError> {
        let photons = |m: &DeviceMap| -> Result<Vec<Photon>, GpuError> {
            let mut v: Vec<Photon> = ctx.download(&m.photons)?;
            v.truncate(m.grid.photon_count as usize);
            Ok(v)
        };
        let starts = |m: &DeviceMap| -> Result<Vec<u32>, GpuError> {
            let mut v: Vec<u32> = ctx.download(&m.starts)?;
            v.truncate(m.grid.table_mask as usize + 2);
            Ok(v)
        };
        Ok(PhotonMaps {
            grids: [self.global.grid, self.caustic.grid, self.volume.grid],
            global_photons: photons(&self.global)?,
            global_starts: starts(&self.global)?,
            caustic_photons: photons(&self.caustic)?,
            caustic_starts: starts(&self.caustic)?,
            volume_photons: photons(&self.volume)?,
            volume_starts: starts(&self.volume)?,
        })
    }
}

/// Traces one emission pass into buffers of room for `capacity` photons and, in the global
/// pass, `volume_capacity` collisions in media (first guesses); returns the photon buffer and
/// the number stored, then the same for the volume photons.
#[allow(clippy::type_complexity)]
fn emit(
    ctx: &GpuContext,
    kernels: &GpuKernels,
    scene: &DeviceScene,
    params: EmitParams,
    caustic: bool,
    capacity: u64,
    volume_capacity: u64,
) -> Result<((Buffer, u32), (Buffer, u32)), GpuError> {
    let emit_kernel = kernels.emit_photons(ctx)?;
    let photon_bytes = size_of::<Photon>() as u64;
    let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
    let name = if caustic { "caustic_photons" } else { "global_photons" };
    // A pass of no paths (a caustic pass where none can be stored) needs no room.
    let capacity = if params.total_paths == 0 { 1 } else { capacity };
    let mut capacity = capacity.clamp(1, limit / photon_bytes);
    // Only the global pass of a scene with media stores collisions.
    let volume = !caustic && scene.variant.media;
    let mut volume_capacity = if volume { volume_capacity.clamp(1, limit / photon_bytes) } else { 1 };
    loop {
        let photons = ctx.create_buffer(name, capacity * photon_bytes)?;
        let volume_photons = ctx.create_buffer("volume_photons", volume_capacity * photon_bytes)?;
        let unused = ctx.create_buffer("unused_photons", photon_bytes)?;
        let counters = ctx.create_buffer("photon_counters", 16)?;
        let mut begin = 0;
        let per_dispatch =
            super::thread_stop_paths().map_or(PATHS_PER_DISPATCH, |p| p.min(PATHS_PER_DISPATCH as u64) as u32);
        // A stopped trace keeps the photons of the dispatches done; the render then stops
        // before its camera kernel reads them.
        while begin < params.total_paths && !super::stop_requested() {
            let mut p = params;
            p.path_begin = begin;
            p.path_count = per_dispatch.min(params.total_paths - begin);
            p.global_capacity = if caustic { 0 } else { capacity as u32 };
            p.caustic_capacity = if caustic { capacity as u32 } else { 0 };
            p.volume_capacity = if volume { volume_capacity as u32 } else { 0 };
            let (global_buffer, caustic_buffer) = if caustic { (&unused, &photons) } else { (&photons, &unused) };
            ctx.run("emit_photons", |rec| {
                rec.dispatch(
                    emit_kernel,
                    &scene.bindings(&[global_buffer, caustic_buffer, &counters, &volume_photons]),
                    bytemuck::bytes_of(&p),
                    groups(p.path_count),
                )
            })?;
            begin += p.path_count;
        }
        let counts: Vec<u32> = ctx.download(&counters)?;
        // Paths the driver broke off mid-loop (lavapipe's limit of 65535 loop iterations per
        // invocation): their photons are missing, so the maps would be darker than the CPU's.
        if counts[3] > 0 {
            return Err(GpuError::Unsupported(format!(
                "the device broke off {} of {} photon paths at its loop limit (lavapipe stops an invocation after \
                 65535 loop iterations): their rays cross too many overlapping objects or instances, and the image \
                 would miss their light; render with --backend cpu, or lower --photon-depth",
                counts[3], params.total_paths
            )));
        }
        let wanted = counts[caustic as usize] as u64;
        let wanted_volume = if volume { counts[2] as u64 } else { 0 };
        if wanted <= capacity && wanted_volume <= volume_capacity {
            return Ok(((photons, wanted as u32), (volume_photons, wanted_volume as u32)));
        }
        for (what, n) in [(name, wanted), ("volume_photons", wanted_volume)] {
            if n > limit / photon_bytes {
                return Err(GpuError::Unsupported(format!(
                    "the {what} map needs {n} photons ({} MiB), more than one storage buffer holds on this device ({} MiB = {} photons); lower the photon count",
                    (n * photon_bytes) >> 20,
                    limit >> 20,
                    limit / photon_bytes
                )));
            }
        }
        // The pass is deterministic, so tracing it again with room for every photon stores the same set.
        capacity = capacity.max(wanted);
        volume_capacity = volume_capacity.max(wanted_volume);
    }
}

/// Exclusive prefix sum of `values` (`count` entries) in place, by blocks of SCAN_BLOCK and a
/// recursive scan of the block sums.
fn scan(ctx: &GpuContext, kernels: &GpuKernels, values: &Buffer, count: u32) -> Result<(), GpuError> {
    let scan_kernel = kernels.grid_scan(ctx)?;
    let add_kernel = kernels.grid_scan_add(ctx)?;
    let mut levels = Vec::new(); // (buffer of block sums, its length)
    let mut n = count;
    while n > 1 {
        let blocks = n.div_ceil(SCAN_BLOCK);
        levels.push((ctx.create_buffer("scan_block_sums", blocks as u64 * 4)?, blocks, n));
        n = blocks;
    }
    ctx.run("grid_scan", |rec| {
        let mut input = values;
        for (sums, blocks, n) in &levels {
            rec.dispatch(scan_kernel, &[input, sums], bytemuck::bytes_of(n), [*blocks, 1, 1])?;
            input = sums;
        }
        for i in (0..levels.len()).rev() {
            let (sums, _, n) = &levels[i];
            let target = if i == 0 { values } else { &levels[i - 1].0 };
            if levels[i].1 > 1 {
                rec.dispatch(add_kernel, &[target, sums], bytemuck::bytes_of(n), groups(*n))?;
            }
        }
        Ok(())
    })
}

/// Builds the hashed grid over `count` photons: count, scan, scatter, rank inside buckets;
/// `None` when the thread's render was stopped between two of them (a stale pass uses no map,
/// and an edit in the editor waits for one submission, not for the whole build).
fn build_map(
    ctx: &GpuContext,
    kernels: &GpuKernels,
    photons: Buffer,
    grid: GridParams,
    name: &str,
) -> Result<Option<DeviceMap>, GpuError> {
    let buckets = grid.table_mask + 1;
    let grid_buffer = ctx.upload("grid_params", std::slice::from_ref(&grid))?;
    let starts = ctx.create_buffer(&format!("{name}_starts"), (buckets as u64 + 1) * 4)?;
    let count = grid.photon_count;
    let count_kernel = kernels.grid_count(ctx)?;
    ctx.run("grid_count", |rec| rec.dispatch(count_kernel, &[&grid_buffer, &photons, &starts], &[], groups(count)))?;
    if super::stop_requested() {
        return Ok(None);
    }
    scan(ctx, kernels, &starts, buckets + 1)?;
    if super::stop_requested() {
        return Ok(None);
    }
    let fill = ctx.create_buffer("grid_fill", buckets as u64 * 4)?;
    let photon_bytes = (count.max(1) as u64) * size_of::<Photon>() as u64;
    let scattered = ctx.create_buffer(&format!("{name}_scattered"), photon_bytes)?;
    let scatter_kernel = kernels.grid_scatter(ctx)?;
    let rank_kernel = kernels.grid_rank(ctx)?;
    ctx.run("grid_scatter", |rec| {
        rec.dispatch(scatter_kernel, &[&grid_buffer, &photons, &starts, &fill, &scattered], &[], groups(count))
    })?;
    drop(photons);
    if super::stop_requested() {
        return Ok(None);
    }
    let ranked = ctx.create_buffer(&format!("{name}_photons"), photon_bytes)?;
    ctx.run("grid_rank", |rec| {
        rec.dispatch(rank_kernel, &[&grid_buffer, &starts, &scattered, &ranked], &[], groups(count))
    })?;
    Ok(Some(DeviceMap { grid, photons: ranked, starts }))
}

/// Traces pass `pass` of both photon maps and builds their grids on the device, creating the
/// kernels it needs (tests and tools; a [`GpuRenderer`] keeps its kernels across passes).
pub fn build_maps_gpu(
    ctx: &GpuContext,
    scene: &DeviceScene,
    buffers: &SceneBuffers,
    settings: &PhotonSettings,
    pass: u32,
) -> Result<DeviceMaps, GpuError> {
    let mut capacity = [0; 3];
    build_maps(ctx, &GpuKernels::for_scene(scene.variant), scene, buffers, settings, pass, &mut capacity)
}

/// Traces the maps of pass `pass` and builds their grids. `capacity` holds the photon counts
/// (global, caustic, volume) to make room for, and on return the counts this pass stored: the next
/// pass then allocates once instead of tracing again (0 = guess from the path count).
fn build_maps(
    ctx: &GpuContext,
    kernels: &GpuKernels,
    scene: &DeviceScene,
    buffers: &SceneBuffers,
    settings: &PhotonSettings,
    pass: u32,
    capacity: &mut [u64; 3],
) -> Result<DeviceMaps, GpuError> {
    let room = |stored: u64, paths: u32| {
        // 1/16 above the last pass's count: passes store a few thousandths more or fewer.
        if stored == 0 {
            paths as u64 * INITIAL_PHOTONS_PER_PATH
        } else {
            stored + stored / 16 + 64
        }
    };
    let global_room = room(capacity[0], settings.photons);
    let caustic_room = room(capacity[1], settings.caustic_photons);
    let volume_room = room(capacity[2], settings.photons);
    let ((global_photons, global_count), (volume_photons, volume_count)) =
        emit(ctx, kernels, scene, emit_params(settings, pass, false), false, global_room, volume_room)?;
    let ((caustic_photons, caustic_count), _) =
        emit(ctx, kernels, scene, caustic_emit_params(buffers, settings, pass), true, caustic_room, 0)?;
    *capacity = [global_count as u64, caustic_count as u64, volume_count as u64];
    let (r_global, r_caustic) = radii(buffers, settings, global_count, pass);
    let g_global = map_grid(buffers, r_global, global_count, settings.photons);
    let g_caustic = map_grid(buffers, r_caustic, caustic_count, settings.caustic_photons);
    let r_volume = volume_radius(buffers, settings, volume_count, pass);
    let g_volume = map_grid(buffers, r_volume, volume_count, settings.photons);
    // A stopped render uses no map: skip the grid builds (seconds on lavapipe) of a stale pass,
    // or what is left of them.
    if super::stop_requested() {
        return no_maps(ctx);
    }
    let Some(global) = build_map(ctx, kernels, global_photons, g_global, "global")? else { return no_maps(ctx) };
    let Some(caustic) = build_map(ctx, kernels, caustic_photons, g_caustic, "caustic")? else { return no_maps(ctx) };
    let Some(volume) = build_map(ctx, kernels, volume_photons, g_volume, "volume")? else { return no_maps(ctx) };
    let grids = ctx.upload("grids", &[g_global, g_caustic, g_volume])?;
    Ok(DeviceMaps { global, caustic, volume, grids })
}

/// Empty maps for a render without photon mapping: every lookup finds no photon.
fn no_maps(ctx: &GpuContext) -> Result<DeviceMaps, GpuError> {
    let empty = |name: &str| -> Result<DeviceMap, GpuError> {
        let grid = crate::cpu::NO_MAPS.grids[0];
        Ok(DeviceMap { grid, photons: ctx.create_buffer(name, 20)?, starts: ctx.upload("no_starts", &[0u32, 0])? })
    };
    Ok(DeviceMaps {
        global: empty("no_photons")?,
        caustic: empty("no_photons")?,
        volume: empty("no_photons")?,
        grids: ctx.upload("grids", crate::cpu::NO_MAPS.grids)?,
    })
}

/// A renderer that keeps its state from pass to pass: the kernels (compute pipelines), the scene
/// on the device and the accumulation buffer are made once; each pass then only traces its
/// photons, builds its grids and runs the camera kernel. [`GpuRenderer::update_scene`] replaces the
/// scene in place (an editor changing a material rewrites one small buffer).
pub struct GpuRenderer<'a> {
    ctx: &'a GpuContext,
    kernels: GpuKernels,
    buffers: SceneBuffers,
    photons: Option<PhotonSettings>,
    scene: DeviceScene,
    /// Created by the first pass, then reused while the image size stays.
    accumulation: Option<(Buffer, u32)>,
    /// Photons stored by the last pass (global, caustic, volume): the next pass's buffer sizes.
    photon_capacity: [u64; 3],
    /// Wall time of uploading the scene and creating the kernels.
    setup_time: Duration,
    /// The arrays the last `update_scene` wrote (those that changed).
    last_written: Vec<&'static str>,
    /// Set while an `update_scene` runs: one that failed leaves the device's arrays unknown.
    device_mixed: bool,
    /// The kernels of variants used before, most recent last: an edit that switches the variant
    /// (a texture added, then undone) finds the pipelines it had, where lavapipe would spend
    /// seconds compiling them again.
    spare_kernels: Vec<GpuKernels>,
}

/// Variants' kernel sets a renderer keeps besides its current one.
const SPARE_KERNEL_SETS: usize = 3;

impl<'a> GpuRenderer<'a> {
    /// Uploads `buffers` and creates every kernel a render with (or, `photons` = `None`,
    /// without) photon maps needs.
    pub fn new(
        ctx: &'a GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<GpuRenderer<'a>, GpuError> {
        let t = Instant::now();
        let photons = super::effective_photons(buffers, photons);
        let scene = DeviceScene::upload(ctx, buffers, photons)?;
        let kernels = GpuKernels::for_scene(buffers.variant());
        kernels.create_all(ctx, photons.is_some())?;
        Ok(GpuRenderer {
            ctx,
            kernels,
            buffers: buffers.clone(),
            photons: photons.copied(),
            scene,
            accumulation: None,
            photon_capacity: [0; 3],
            setup_time: t.elapsed(),
            last_written: Vec::new(),
            device_mixed: false,
            spare_kernels: Vec::new(),
        })
    }

    /// Wall time spent in [`GpuRenderer::new`] and [`GpuRenderer::update_scene`] so far: the
    /// scene's upload and the kernels' creation.
    pub fn setup_time(&self) -> Duration {
        self.setup_time
    }

    pub fn context(&self) -> &'a GpuContext {
        self.ctx
    }

    /// The kernel variants whose pipelines this renderer holds: its scene's first, then those
    /// it keeps from earlier scenes (the most recent last).
    pub fn kernel_variants(&self) -> Vec<KernelVariant> {
        std::iter::once(&self.kernels).chain(self.spare_kernels.iter().rev()).map(GpuKernels::variant).collect()
    }

    /// The scene arrays the last [`GpuRenderer::update_scene`] wrote to the device: those that
    /// differ from the scene it held ("frame", "nodes", "primitives", "materials", ...).
    pub fn last_written(&self) -> &[&'static str] {
        &self.last_written
    }

    /// Replaces the scene (and the photon settings) without recreating the kernels: arrays equal
    /// to the current ones are left alone, others that keep their size are rewritten in their
    /// buffers. Returns how many of the 9 scene arrays kept their buffers (unchanged ones
    /// count; [`GpuRenderer::last_written`] names those written).
    pub fn update_scene(&mut self, buffers: &SceneBuffers, photons: Option<&PhotonSettings>) -> Result<u32, GpuError> {
        let t = Instant::now();
        let photons = super::effective_photons(buffers, photons);
        // After a failed update the device may hold a mix of the two scenes: compare with nothing.
        let previous = (!self.device_mixed).then_some((&self.buffers, self.photons.as_ref()));
        self.device_mixed = true;
        let (in_place, written) = self.scene.update_changed(self.ctx, buffers, photons, previous)?;
        self.device_mixed = false;
        self.last_written = written;
        if buffers.variant() != self.kernels.variant() {
            let kept = self.spare_kernels.iter().position(|k| k.variant() == buffers.variant());
            let next = match kept {
                Some(i) => self.spare_kernels.remove(i),
                None => GpuKernels::for_scene(buffers.variant()),
            };
            self.spare_kernels.push(std::mem::replace(&mut self.kernels, next));
            if self.spare_kernels.len() > SPARE_KERNEL_SETS {
                self.spare_kernels.remove(0);
            }
            self.kernels.create_all(self.ctx, photons.is_some())?;
        }
        if photons.is_some() {
            self.kernels.create_all(self.ctx, true)?;
        }
        self.buffers = buffers.clone();
        self.photons = photons.copied();
        self.photon_capacity = [0; 3];
        self.setup_time += t.elapsed();
        Ok(in_place)
    }

    /// Renders pass `pass` with `spp` samples per pixel; `progress(done, total)` is called after
    /// each submission of the camera kernel.
    pub fn render_pass(
        &mut self,
        spp: u32,
        pass: u32,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<RenderOutput, GpuError> {
        let ctx = self.ctx;
        let f = photon_frame(&self.buffers, self.photons.as_ref());
        let mut stages = Vec::new();

        // Trace photons and build the grids
        let t = Instant::now();
        let maps = match &self.photons {
            Some(settings) => {
                build_maps(ctx, &self.kernels, &self.scene, &self.buffers, settings, pass, &mut self.photon_capacity)?
            }
            None => no_maps(ctx)?,
        };
        if self.photons.is_some() {
            stages.push(("photons".to_string(), t.elapsed()));
        }

        // The accumulation buffer holds as many rows as one storage binding may address.
        let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
        let row_bytes = f.width as u64 * ACCUMULATION_BYTES_PER_PIXEL;
        let max_rows = (limit / row_bytes).min(f.height as u64) as u32;
        if max_rows == 0 {
            return Err(GpuError::Unsupported(format!(
                "one image row of {} pixels needs {row_bytes} bytes, more than the device's storage buffer limit of {limit} bytes; lower the resolution",
                f.width
            )));
        }
        let max_rows = super::stop_band_rows(f.width, max_rows);
        let bytes = max_rows as u64 * row_bytes;
        if self.accumulation.as_ref().is_none_or(|(b, w)| b.size() != bytes || *w != f.width) {
            self.accumulation = Some((ctx.create_buffer("accumulation", bytes)?, f.width));
        }
        let accumulation = &self.accumulation.as_ref().expect("created just above").0;
        let render_kernel = self.kernels.render(ctx)?;

        // Gather, band by band
        let t = Instant::now();
        let mut layers = Layers::new(f.width, f.height);
        let units = work_units(f.height, spp, parts_per_sample(&f), max_rows, pass);
        let total = units.total_rows();
        let mut units = units.peekable();
        let mut done = 0;
        let mut rays = 0;
        let mut download_time = Duration::ZERO;
        // Consecutive units of one band go into one submission of up to PATHS_PER_SUBMIT paths: few
        // submissions, yet none long enough to trip a GPU watchdog.
        let mut complete = true;
        let mut batch: Vec<DispatchRange> = Vec::new();
        while let Some(first) = units.next() {
            let band = first.row_begin;
            let mut paths = first.row_count as u64 * f.width as u64;
            batch.clear();
            batch.push(first);
            while paths < super::thread_stop_paths().unwrap_or(PATHS_PER_SUBMIT) {
                let Some(unit) = units.next_if(|u| u.row_begin == band) else { break };
                paths += unit.row_count as u64 * f.width as u64;
                batch.push(unit);
            }
            if super::stop_requested() {
                complete = false;
                break;
            }
            if batch[0].sample_index == pass * spp && batch[0].part == 0 {
                ctx.fill_zero(accumulation)?;
            }
            let invocations = batch[0].row_count * f.width;
            ctx.run("render", |rec| {
                for unit in &batch {
                    rec.dispatch(
                        render_kernel,
                        &self.scene.bindings(&[
                            accumulation,
                            &maps.grids,
                            &maps.global.photons,
                            &maps.global.starts,
                            &maps.caustic.photons,
                            &maps.caustic.starts,
                            &maps.volume.photons,
                            &maps.volume.starts,
                        ]),
                        bytemuck::bytes_of(unit),
                        groups(invocations),
                    )?;
                }
                Ok(())
            })?;
            done += batch.iter().map(unit_paths).sum::<u64>();
            progress(done, total);
            if units.peek().is_none_or(|next| next.row_begin != band) {
                let td = Instant::now();
                let sums: Vec<[f32; 4]> = ctx.download(accumulation)?;
                let len = (invocations * LAYER_COUNT) as usize;
                rays += resolve_band(&mut layers, band, &sums[..len], spp);
                download_time += td.elapsed();
            }
        }
        stages.push(("render".to_string(), t.elapsed() - download_time));
        stages.push(("download".to_string(), download_time));
        let stats = RenderStats {
            stages,
            kernel_times: ctx.take_timings(),
            rays,
            samples_per_pixel: spp,
            device: format!("{} ({})", ctx.info().name, ctx.info().driver),
        };
        Ok(RenderOutput { image: layers.combined(), layers, stats, complete })
    }
}

/// Renders pass `pass` on `ctx`, with photon maps when `photons` is given, with a renderer made
/// for this one pass (its set-up time is reported as the `upload` stage); `progress(done, total)`
/// is called after each submission of the camera kernel. Progressive renders keep one
/// [`GpuRenderer`] instead.
pub fn render_gpu(
    ctx: &GpuContext,
    buffers: &SceneBuffers,
    spp: u32,
    photons: Option<&PhotonSettings>,
    pass: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<RenderOutput, GpuError> {
    let mut renderer = GpuRenderer::new(ctx, buffers, photons)?;
    let mut out = renderer.render_pass(spp, pass, progress)?;
    out.stats.stages.insert(0, ("upload".to_string(), renderer.setup_time()));
    Ok(out)
}
