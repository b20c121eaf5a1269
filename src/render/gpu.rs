//! Rendering on a Vulkan device: photon tracing, the grid build and the camera kernel.

use std::time::{Duration, Instant};

use super::photons::{emit_params, map_grid, radii, PhotonMaps, PhotonSettings};
use super::{
    parts_per_sample, photon_frame, resolve_band, unit_paths, work_units, Layers, RenderOutput, RenderStats,
    SceneBuffers,
};
use crate::gpu::{Buffer, GpuContext, GpuError, Kernel};
use crate::layout::constants::{LAYER_COUNT, SCAN_BLOCK, SCENE_BINDINGS, WORKGROUP_SIZE};
use crate::layout::{DispatchRange, EmitParams, GridParams, Photon};

/// Bytes of accumulation per pixel: one vec4 per layer.
const ACCUMULATION_BYTES_PER_PIXEL: u64 = 16 * LAYER_COUNT as u64;
/// Camera-path parts per submission of the camera kernel.
const PATHS_PER_SUBMIT: u64 = 1 << 18;
/// Photon paths per `emit_photons` dispatch.
const PATHS_PER_DISPATCH: u32 = 1 << 18;
/// First guess of photons stored per path; the buffer grows (and the pass is traced again) when
/// a scene stores more.
const INITIAL_PHOTONS_PER_PATH: u64 = 4;

fn kernel(ctx: &GpuContext, name: &str, bindings: u32, push_bytes: usize) -> Result<Kernel, GpuError> {
    let spirv = crate::shaders::spirv(name).expect("build.rs embeds every kernel in shaders/");
    ctx.create_kernel(name, &spirv, bindings, push_bytes as u32)
}

/// Workgroups for a one-dimensional launch, spread over x and y so that neither passes 32768
/// (the kernels rebuild the index with GLOBAL_INDEX and skip the surplus).
fn groups(invocations: u32) -> [u32; 3] {
    const MAX_X: u32 = 1 << 15;
    let total = invocations.div_ceil(WORKGROUP_SIZE).max(1);
    let x = total.min(MAX_X);
    [x, total.div_ceil(x), 1]
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
}

impl DeviceScene {
    pub fn upload(
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<Self, GpuError> {
        let frame = photon_frame(buffers, photons);
        Ok(DeviceScene {
            frame: ctx.upload("frame", std::slice::from_ref(&frame))?,
            nodes: ctx.upload("bvh_nodes", &buffers.nodes)?,
            primitives: ctx.upload("primitives", &buffers.primitives)?,
            materials: ctx.upload("materials", &buffers.materials)?,
            lights: ctx.upload("lights", &buffers.lights)?,
            textures: ctx.upload("textures", &buffers.textures)?,
            texture_data: ctx.upload("texture_data", &buffers.texture_data)?,
            shape_data: ctx.upload("shape_data", &buffers.shape_data)?,
        })
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
        ];
        debug_assert_eq!(scene.len(), SCENE_BINDINGS as usize);
        scene.into_iter().chain(own.iter().copied()).collect()
    }
}

/// One photon map on the device: photons sorted by bucket and the bucket starts.
pub struct DeviceMap {
    pub grid: GridParams,
    pub photons: Buffer,
    pub starts: Buffer,
}

/// Both maps on the device, plus their grid parameters in one buffer for the camera kernel.
pub struct DeviceMaps {
    pub global: DeviceMap,
    pub caustic: DeviceMap,
    pub grids: Buffer,
}

impl DeviceMaps {
    /// Reads both maps back (for tests and tools).
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
            grids: [self.global.grid, self.caustic.grid],
            global_photons: photons(&self.global)?,
            global_starts: starts(&self.global)?,
            caustic_photons: photons(&self.caustic)?,
            caustic_starts: starts(&self.caustic)?,
        })
    }
}

/// Traces one emission pass; returns the photon buffer holding `count` photons.
fn emit(ctx: &GpuContext, scene: &DeviceScene, params: EmitParams, caustic: bool) -> Result<(Buffer, u32), GpuError> {
    let emit_kernel = kernel(ctx, "emit_photons", SCENE_BINDINGS + 3, size_of::<EmitParams>())?;
    let photon_bytes = size_of::<Photon>() as u64;
    let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
    let name = if caustic { "caustic_photons" } else { "global_photons" };
    let mut capacity = (params.total_paths as u64 * INITIAL_PHOTONS_PER_PATH).clamp(1, limit / photon_bytes);
    loop {
        let photons = ctx.create_buffer(name, capacity * photon_bytes)?;
        let unused = ctx.create_buffer("unused_photons", photon_bytes)?;
        let counters = ctx.create_buffer("photon_counters", 8)?;
        let mut begin = 0;
        while begin < params.total_paths {
            let mut p = params;
            p.path_begin = begin;
            p.path_count = PATHS_PER_DISPATCH.min(params.total_paths - begin);
            p.global_capacity = if caustic { 0 } else { capacity as u32 };
            p.caustic_capacity = if caustic { capacity as u32 } else { 0 };
            let (global_buffer, caustic_buffer) = if caustic { (&unused, &photons) } else { (&photons, &unused) };
            ctx.run("emit_photons", |rec| {
                rec.dispatch(
                    &emit_kernel,
                    &scene.bindings(&[global_buffer, caustic_buffer, &counters]),
                    bytemuck::bytes_of(&p),
                    groups(p.path_count),
                )
            })?;
            begin += p.path_count;
        }
        let counts: Vec<u32> = ctx.download(&counters)?;
        let wanted = counts[caustic as usize] as u64;
        if wanted <= capacity {
            return Ok((photons, wanted as u32));
        }
        if wanted > limit / photon_bytes {
            return Err(GpuError::Unsupported(format!(
                "the {name} map needs {wanted} photons ({} MiB), more than one storage buffer holds on this device ({} MiB = {} photons); lower the photon count",
                (wanted * photon_bytes) >> 20,
                limit >> 20,
                limit / photon_bytes
            )));
        }
        // The pass is deterministic, so tracing it again with room for every photon stores the same set.
        capacity = wanted;
    }
}

/// Exclusive prefix sum of `values` (`count` entries) in place, by blocks of SCAN_BLOCK and a
/// recursive scan of the block sums.
fn scan(ctx: &GpuContext, values: &Buffer, count: u32) -> Result<(), GpuError> {
    let scan_kernel = kernel(ctx, "grid_scan", 2, 4)?;
    let add_kernel = kernel(ctx, "grid_scan_add", 2, 4)?;
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
            rec.dispatch(&scan_kernel, &[input, sums], bytemuck::bytes_of(n), [*blocks, 1, 1])?;
            input = sums;
        }
        for i in (0..levels.len()).rev() {
            let (sums, _, n) = &levels[i];
            let target = if i == 0 { values } else { &levels[i - 1].0 };
            if levels[i].1 > 1 {
                rec.dispatch(&add_kernel, &[target, sums], bytemuck::bytes_of(n), groups(*n))?;
            }
        }
        Ok(())
    })
}

/// Builds the hashed grid over `count` photons: count, scan, scatter, rank inside buckets.
fn build_map(ctx: &GpuContext, photons: Buffer, grid: GridParams, name: &str) -> Result<DeviceMap, GpuError> {
    let buckets = grid.table_mask + 1;
    let grid_buffer = ctx.upload("grid_params", std::slice::from_ref(&grid))?;
    let starts = ctx.create_buffer(&format!("{name}_starts"), (buckets as u64 + 1) * 4)?;
    let count = grid.photon_count;
    let count_kernel = kernel(ctx, "grid_count", 3, 0)?;
    ctx.run("grid_count", |rec| rec.dispatch(&count_kernel, &[&grid_buffer, &photons, &starts], &[], groups(count)))?;
    scan(ctx, &starts, buckets + 1)?;
    let fill = ctx.create_buffer("grid_fill", buckets as u64 * 4)?;
    let photon_bytes = (count.max(1) as u64) * size_of::<Photon>() as u64;
    let scattered = ctx.create_buffer(&format!("{name}_scattered"), photon_bytes)?;
    let scatter_kernel = kernel(ctx, "grid_scatter", 5, 0)?;
    let rank_kernel = kernel(ctx, "grid_rank", 4, 0)?;
    ctx.run("grid_scatter", |rec| {
        rec.dispatch(&scatter_kernel, &[&grid_buffer, &photons, &starts, &fill, &scattered], &[], groups(count))
    })?;
    drop(photons);
    let ranked = ctx.create_buffer(&format!("{name}_photons"), photon_bytes)?;
    ctx.run("grid_rank", |rec| {
        rec.dispatch(&rank_kernel, &[&grid_buffer, &starts, &scattered, &ranked], &[], groups(count))
    })?;
    Ok(DeviceMap { grid, photons: ranked, starts })
}

/// Traces pass `pass` of both photon maps and builds their grids on the device.
pub fn build_maps_gpu(
    ctx: &GpuContext,
    scene: &DeviceScene,
    buffers: &SceneBuffers,
    settings: &PhotonSettings,
    pass: u32,
) -> Result<DeviceMaps, GpuError> {
    let (global_photons, global_count) = emit(ctx, scene, emit_params(settings, pass, false), false)?;
    let (caustic_photons, caustic_count) = emit(ctx, scene, emit_params(settings, pass, true), true)?;
    let (r_global, r_caustic) = radii(buffers, settings, global_count, pass);
    let g_global = map_grid(buffers, r_global, global_count, settings.photons);
    let g_caustic = map_grid(buffers, r_caustic, caustic_count, settings.caustic_photons);
    let global = build_map(ctx, global_photons, g_global, "global")?;
    let caustic = build_map(ctx, caustic_photons, g_caustic, "caustic")?;
    let grids = ctx.upload("grids", &[g_global, g_caustic])?;
    Ok(DeviceMaps { global, caustic, grids })
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
        grids: ctx.upload("grids", crate::cpu::NO_MAPS.grids)?,
    })
}

/// Renders pass `pass` on `ctx`, with photon maps when `photons` is given; `progress(done,
/// total)` is called after each submission of the camera kernel.
pub fn render_gpu(
    ctx: &GpuContext,
    buffers: &SceneBuffers,
    spp: u32,
    photons: Option<&PhotonSettings>,
    pass: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<RenderOutput, GpuError> {
    let f = photon_frame(buffers, photons);
    let mut stages = Vec::new();

    // Upload
    let t = Instant::now();
    let scene = DeviceScene::upload(ctx, buffers, photons)?;
    let render_kernel = kernel(ctx, "render", SCENE_BINDINGS + 6, size_of::<DispatchRange>())?;
    stages.push(("upload".to_string(), t.elapsed()));

    // Trace photons and build the grids
    let t = Instant::now();
    let maps = match photons {
        Some(settings) => build_maps_gpu(ctx, &scene, buffers, settings, pass)?,
        None => no_maps(ctx)?,
    };
    if photons.is_some() {
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
    let accumulation = ctx.create_buffer("accumulation", max_rows as u64 * row_bytes)?;

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
        while paths < PATHS_PER_SUBMIT {
            let Some(unit) = units.next_if(|u| u.row_begin == band) else { break };
            paths += unit.row_count as u64 * f.width as u64;
            batch.push(unit);
        }
        if super::stop_requested() {
            complete = false;
            break;
        }
        if batch[0].sample_index == pass * spp && batch[0].part == 0 {
            ctx.fill_zero(&accumulation)?;
        }
        let invocations = batch[0].row_count * f.width;
        ctx.run("render", |rec| {
            for unit in &batch {
                rec.dispatch(
                    &render_kernel,
                    &scene.bindings(&[
                        &accumulation,
                        &maps.grids,
                        &maps.global.photons,
                        &maps.global.starts,
                        &maps.caustic.photons,
                        &maps.caustic.starts,
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
            let sums: Vec<[f32; 4]> = ctx.download(&accumulation)?;
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
