//! `photonix bench`: ray throughput of each backend on one scene.
//! Primary rays are timed with the lights switched off (a diffuse hit then casts nothing more);
//! shadow rays are timed as the extra time of the same frame with one shadow ray per hit.

use super::{render_cpu, Backend, RenderError, SceneBuffers};
use crate::gpu::GpuContext;

/// Throughput of one backend.
#[derive(Clone, Debug)]
pub struct BenchResult {
    pub backend: Backend,
    pub device: String,
    pub primary_rays: u64,
    pub primary_seconds: f64,
    pub shadow_rays: u64,
    pub shadow_seconds: f64,
}

impl BenchResult {
    pub fn primary_rays_per_second(&self) -> f64 {
        self.primary_rays as f64 / self.primary_seconds
    }

    pub fn shadow_rays_per_second(&self) -> f64 {
        self.shadow_rays as f64 / self.shadow_seconds
    }
}

/// Renders `buffers` twice with `max_depth = 1` (no lights, then lights) and returns the rates.
/// `ctx` is `None` for the CPU reference.
pub fn bench(ctx: Option<&GpuContext>, buffers: &SceneBuffers, spp: u32) -> Result<BenchResult, RenderError> {
    let mut dark = buffers.clone();
    dark.frame.max_depth = 1;
    dark.frame.light_count = 0;
    let mut lit = dark.clone();
    lit.frame.light_count = buffers.frame.light_count;
    let run = |b: &SceneBuffers| -> Result<(u64, f64, String), RenderError> {
        let out = match ctx {
            Some(ctx) => super::gpu::render_gpu(ctx, b, spp, None, 0, &mut |_, _| {})?,
            None => render_cpu(b, spp, None, 0, &mut |_, _| {}),
        };
        // The render stage only: uploads and pipeline creation are not ray throughput.
        Ok((out.stats.rays, out.stats.stage("render").as_secs_f64(), out.stats.device))
    };
    // A warm-up frame so that pipeline creation and first-touch costs stay out of the figures.
    run(&dark)?;
    let (primary_rays, primary_seconds, device) = run(&dark)?;
    let (all_rays, lit_seconds, _) = run(&lit)?;
    Ok(BenchResult {
        backend: if ctx.is_some() { Backend::Gpu } else { Backend::Cpu },
        device,
        primary_rays,
        primary_seconds,
        shadow_rays: all_rays - primary_rays,
        shadow_seconds: (lit_seconds - primary_seconds).max(1e-9),
    })
}

/// Photon tracing and grid building at one photon count.
#[derive(Clone, Debug)]
pub struct PhotonBench {
    pub backend: Backend,
    pub paths: u32,
    /// Photons stored in the global map.
    pub stored: u32,
    pub trace_seconds: f64,
    pub grid_seconds: f64,
}

/// Traces `paths` global photon paths and builds their grid, timing the two stages (GPU time from
/// timestamp queries on the device, wall time on the CPU).
pub fn bench_photons(ctx: Option<&GpuContext>, buffers: &SceneBuffers, paths: u32) -> Result<PhotonBench, RenderError> {
    use super::photons::{emit_params, map_grid, radii, PhotonSettings};
    let settings = PhotonSettings { photons: paths, caustic_photons: 1, ..PhotonSettings::default() };
    match ctx {
        Some(ctx) => {
            let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
            super::memory::check_photon_buffer(&settings, limit)?;
            let scene = super::gpu::DeviceScene::upload(ctx, buffers, Some(&settings))?;
            ctx.take_timings();
            let maps = super::gpu::build_maps_gpu(ctx, &scene, buffers, &settings, 0)?;
            let timings = ctx.take_timings();
            let sum = |pred: &dyn Fn(&str) -> bool| -> f64 {
                timings.iter().filter(|(n, _, _)| pred(n)).map(|(_, s, _)| s).sum()
            };
            Ok(PhotonBench {
                backend: Backend::Gpu,
                paths,
                stored: maps.global.grid.photon_count,
                trace_seconds: sum(&|n| n == "emit_photons"),
                // Both maps' grids are built; the caustic map of 1 path is negligible.
                grid_seconds: sum(&|n| n.starts_with("grid_")),
            })
        }
        None => {
            let e = super::memory::estimate(1, 1, Some(&settings), None);
            super::memory::check_fits(&e, 1, 1, Some(&settings), super::memory::available_host_memory(), None)?;
            let view = buffers.view();
            let t = std::time::Instant::now();
            let photons = crate::cpu::emit_photons::emit_photons(&view, &emit_params(&settings, 0, false)).global;
            let trace_seconds = t.elapsed().as_secs_f64();
            let (radius, _) = radii(buffers, &settings, photons.len() as u32, 0);
            let grid = map_grid(buffers, radius, photons.len() as u32, paths);
            let t = std::time::Instant::now();
            let built = crate::cpu::grid_build::build_grid(&photons, &grid);
            let grid_seconds = t.elapsed().as_secs_f64();
            drop(built);
            Ok(PhotonBench { backend: Backend::Cpu, paths, stored: photons.len() as u32, trace_seconds, grid_seconds })
        }
    }
}

/// What keeping a [`GpuRenderer`](super::gpu::GpuRenderer) across passes saves.
#[derive(Clone, Debug)]
pub struct SetupBench {
    /// Seconds to upload the scene's arrays.
    pub upload_seconds: f64,
    /// Seconds to create each kernel once.
    pub kernel_seconds: Vec<(&'static str, f64)>,
    /// Wall seconds of each pass with a renderer made for that pass alone (upload and kernels
    /// every pass, as before the renderer kept its state).
    pub fresh_pass_seconds: Vec<f64>,
    /// Wall seconds of each pass of one renderer kept across passes, and its set-up.
    pub kept_pass_seconds: Vec<f64>,
    pub kept_setup_seconds: f64,
}

/// Renders `passes` passes twice on `ctx`: once with a new renderer per pass and once with one
/// renderer kept across them; the images are the same, the difference is the set-up.
pub fn bench_setup(
    ctx: &GpuContext,
    buffers: &SceneBuffers,
    photons: Option<&super::PhotonSettings>,
    spp: u32,
    passes: u32,
) -> Result<SetupBench, RenderError> {
    use super::gpu::{DeviceScene, GpuKernels, GpuRenderer};
    use std::time::Instant;
    let t = Instant::now();
    drop(DeviceScene::upload(ctx, buffers, photons)?);
    let upload_seconds = t.elapsed().as_secs_f64();
    let kernel_seconds = GpuKernels::time_creation(ctx)?;
    let mut fresh_pass_seconds = Vec::new();
    for pass in 0..passes {
        let t = Instant::now();
        super::gpu::render_gpu(ctx, buffers, spp, photons, pass, &mut |_, _| {})?;
        fresh_pass_seconds.push(t.elapsed().as_secs_f64());
    }
    let t = Instant::now();
    let mut renderer = GpuRenderer::new(ctx, buffers, photons)?;
    let kept_setup_seconds = t.elapsed().as_secs_f64();
    let mut kept_pass_seconds = Vec::new();
    for pass in 0..passes {
        let t = Instant::now();
        renderer.render_pass(spp, pass, &mut |_, _| {})?;
        kept_pass_seconds.push(t.elapsed().as_secs_f64());
    }
    ctx.take_timings();
    Ok(SetupBench { upload_seconds, kernel_seconds, fresh_pass_seconds, kept_pass_seconds, kept_setup_seconds })
}
