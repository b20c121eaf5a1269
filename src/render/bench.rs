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
            Some(ctx) => super::gpu::render_gpu(ctx, b, spp, None, &mut |_, _| {})?,
            None => render_cpu(b, spp, None, &mut |_, _| {}),
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
