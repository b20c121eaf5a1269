//! The light stage: photon tracing and the grid build of each map, on the device.

use super::kernels::{groups, GpuKernels};
use super::scene::DeviceScene;
use crate::gpu::{Buffer, GpuContext, GpuError, Kernel, Recorder};
use crate::layout::constants::SCAN_BLOCK;
use crate::layout::{EmitParams, GridParams, Photon};
use crate::render::photons::{
    caustic_emit_params, emit_params, map_grid, radii, volume_radius, PhotonMaps, PhotonSettings,
};
use crate::render::SceneBuffers;

/// Photon paths per `emit_photons` dispatch.
const PATHS_PER_DISPATCH: u32 = 1 << 18;
/// First guess of photons stored per path; the buffer grows (and the pass is traced again) when
/// a scene stores more.
const INITIAL_PHOTONS_PER_PATH: u64 = 4;

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
        // The kernel writes the photons below the counts it returns, and nothing reads past them.
        let photons = ctx.create_scratch(name, capacity * photon_bytes)?;
        let volume_photons = ctx.create_scratch("volume_photons", volume_capacity * photon_bytes)?;
        let unused = ctx.create_scratch("unused_photons", photon_bytes)?;
        let counters = ctx.create_scratch("photon_counters", 16)?;
        let mut cleared = false;
        let mut begin = 0;
        let per_dispatch =
            crate::render::thread_stop_paths().map_or(PATHS_PER_DISPATCH, |p| p.min(PATHS_PER_DISPATCH as u64) as u32);
        // A stopped trace keeps the photons of the dispatches done; the render then stops
        // before its camera kernel reads them.
        while begin < params.total_paths && !crate::render::stop_requested() {
            let mut p = params;
            p.path_begin = begin;
            p.path_count = per_dispatch.min(params.total_paths - begin);
            p.global_capacity = if caustic { 0 } else { capacity as u32 };
            p.caustic_capacity = if caustic { capacity as u32 } else { 0 };
            p.volume_capacity = if volume { volume_capacity as u32 } else { 0 };
            let (global_buffer, caustic_buffer) = if caustic { (&unused, &photons) } else { (&photons, &unused) };
            ctx.run("emit_photons", |rec| {
                if !cleared {
                    rec.fill_zero(&counters)?;
                }
                rec.dispatch(
                    emit_kernel,
                    &scene.bindings(&[global_buffer, caustic_buffer, &counters, &volume_photons]),
                    bytemuck::bytes_of(&p),
                    groups(p.path_count),
                )
            })?;
            cleared = true;
            begin += p.path_count;
        }
        if !cleared {
            ctx.fill_zero(&counters)?;
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

/// Records the exclusive prefix sum of `values` (`count` entries) in place, by blocks of
/// SCAN_BLOCK and a recursive scan of the block sums; `levels` holds the block sums' buffers,
/// made by [`scan_levels`] (every entry of them is written before it is read).
fn record_scan<'a>(
    rec: &mut Recorder<'a>,
    (scan, add): (&'a Kernel, &'a Kernel),
    values: &'a Buffer,
    levels: &'a [(Buffer, u32, u32)],
) -> Result<(), GpuError> {
    let mut input = values;
    for (sums, blocks, n) in levels {
        rec.dispatch(scan, &[input, sums], bytemuck::bytes_of(n), [*blocks, 1, 1])?;
        input = sums;
    }
    for i in (0..levels.len()).rev() {
        let (sums, _, n) = &levels[i];
        let target = if i == 0 { values } else { &levels[i - 1].0 };
        if levels[i].1 > 1 {
            rec.dispatch(add, &[target, sums], bytemuck::bytes_of(n), groups(*n))?;
        }
    }
    Ok(())
}

/// The block sums' buffers of a scan of `count` entries: (buffer, blocks, entries scanned).
fn scan_levels(ctx: &GpuContext, count: u32) -> Result<Vec<(Buffer, u32, u32)>, GpuError> {
    let mut levels = Vec::new();
    let mut n = count;
    while n > 1 {
        let blocks = n.div_ceil(SCAN_BLOCK);
        levels.push((ctx.create_scratch("scan_block_sums", blocks as u64 * 4)?, blocks, n));
        n = blocks;
    }
    Ok(levels)
}

/// Builds the hashed grid over `count` photons: count, scan, scatter, rank inside buckets, in
/// two submissions (count and scan, then scatter and rank) whose small parameter blocks and
/// clears are recorded into them: on a real GPU each submission waited for costs about what
/// the stages themselves do. `None` when the thread's render was stopped before one of them (a
/// stale pass uses no map, and an edit in the editor waits for one submission, not for the
/// whole build).
pub(super) fn build_map(
    ctx: &GpuContext,
    kernels: &GpuKernels,
    photons: Buffer,
    grid: GridParams,
    name: &str,
) -> Result<Option<DeviceMap>, GpuError> {
    let buckets = grid.table_mask + 1;
    let grid_buffer = ctx.create_scratch("grid_params", size_of::<GridParams>() as u64)?;
    let starts = ctx.create_scratch(&format!("{name}_starts"), (buckets as u64 + 1) * 4)?;
    let count = grid.photon_count;
    let count_kernel = kernels.grid_count(ctx)?;
    let scan_kernels = (kernels.grid_scan(ctx)?, kernels.grid_scan_add(ctx)?);
    let levels = scan_levels(ctx, buckets + 1)?;
    ctx.run("grid_count", |rec| {
        rec.update(&grid_buffer, std::slice::from_ref(&grid))?;
        rec.fill_zero(&starts)?;
        rec.dispatch(count_kernel, &[&grid_buffer, &photons, &starts], &[], groups(count))?;
        record_scan(rec, scan_kernels, &starts, &levels)
    })?;
    drop(levels);
    if crate::render::stop_requested() {
        return Ok(None);
    }
    let fill = ctx.create_scratch("grid_fill", buckets as u64 * 4)?;
    let photon_bytes = (count.max(1) as u64) * size_of::<Photon>() as u64;
    let scattered = ctx.create_scratch(&format!("{name}_scattered"), photon_bytes)?;
    let ranked = ctx.create_scratch(&format!("{name}_photons"), photon_bytes)?;
    let scatter_kernel = kernels.grid_scatter(ctx)?;
    let rank_kernel = kernels.grid_rank(ctx)?;
    ctx.run("grid_scatter", |rec| {
        rec.fill_zero(&fill)?;
        rec.dispatch(scatter_kernel, &[&grid_buffer, &photons, &starts, &fill, &scattered], &[], groups(count))?;
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
pub(super) fn build_maps(
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
    if crate::render::stop_requested() {
        return no_maps(ctx);
    }
    let Some(global) = build_map(ctx, kernels, global_photons, g_global, "global")? else { return no_maps(ctx) };
    let Some(caustic) = build_map(ctx, kernels, caustic_photons, g_caustic, "caustic")? else { return no_maps(ctx) };
    let Some(volume) = build_map(ctx, kernels, volume_photons, g_volume, "volume")? else { return no_maps(ctx) };
    let grids = ctx.upload("grids", &[g_global, g_caustic, g_volume])?;
    Ok(DeviceMaps { global, caustic, volume, grids })
}

/// Empty maps for a render without photon mapping: every lookup finds no photon.
pub(super) fn no_maps(ctx: &GpuContext) -> Result<DeviceMaps, GpuError> {
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
