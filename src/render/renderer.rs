//! One renderer that every front-end drives (the command line, the Python package, benches):
//! the backend chosen once, its state kept across passes, the integrator and photon settings
//! applied in one place (`effective_photons`), and a stop signal of its own.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

use super::adaptive::PixelList;
use super::gpu::GpuRenderer;
use super::{effective_photons, render_cpu_keeping, set_thread_stop_flag, PhotonSettings, RenderOutput, SceneBuffers};
use crate::cpu::vcm::LightStage;
use crate::gpu::{GpuContext, GpuError};

/// The most passes a GPU renders into one output (see [`Renderer::max_pass_group`]).
pub const MAX_PASS_GROUP: u32 = 64;

/// A render in progress on one backend: the GPU kernels when made with a device context, else
/// the CPU backend. Passes may come in any order (pass ranges); each is the same image whichever
/// renderer draws it.
pub struct Renderer<'a> {
    buffers: SceneBuffers,
    photons: Option<PhotonSettings>,
    gpu: Option<GpuRenderer<'a>>,
    /// The CPU backend's light-stage buffers (bpt and vcm), kept across passes.
    light_stage: LightStage,
    stop: Option<Arc<AtomicBool>>,
    /// Render the feature layers too (`set_features`).
    features: bool,
    /// The pixels the next passes render (`set_pixels`; `None`: all).
    pixels: Option<Arc<PixelList>>,
}

impl<'a> Renderer<'a> {
    /// A renderer of `buffers` with photon maps where the scene's integrator reads them; on `ctx`
    /// (uploading the scene and creating the kernels now) or, with `None`, on the CPU backend.
    pub fn new(
        ctx: Option<&'a GpuContext>,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<Renderer<'a>, GpuError> {
        let photons = effective_photons(buffers, photons).copied();
        let gpu = ctx.map(|ctx| GpuRenderer::new(ctx, buffers, photons.as_ref())).transpose()?;
        Ok(Renderer {
            buffers: buffers.clone(),
            photons,
            gpu,
            light_stage: LightStage::default(),
            stop: None,
            features: false,
            pixels: None,
        })
    }

    /// Makes passes stop (returning an incomplete output after the dispatch under way) when
    /// `flag` is set, besides the process-wide `render::STOP`.
    pub fn set_stop_flag(&mut self, flag: Option<Arc<AtomicBool>>) {
        self.stop = flag;
    }

    /// Makes every output carry the feature layers of its samples (albedo, normal, depth,
    /// position: `RenderOutput::features`), rendered by a kernel of their own after the image's,
    /// so the image is the same bits with or without them.
    pub fn set_features(&mut self, on: bool) {
        self.features = on;
    }

    /// Makes the next passes render only the pixels of `pixels` (adaptive sampling; `None`:
    /// every pixel). Their outputs say which (`RenderOutput::pixels`); the feature layers still
    /// cover every pixel.
    pub fn set_pixels(&mut self, pixels: Option<Arc<PixelList>>) {
        self.pixels = pixels;
    }

    /// Renders pass `pass` with `spp` samples per pixel; `progress(done, total)` is called as work
    /// units finish.
    pub fn render_pass(
        &mut self,
        spp: u32,
        pass: u32,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<RenderOutput, GpuError> {
        self.render_passes(spp, pass, 1, progress)
    }

    /// Renders up to `passes` consecutive passes from `first` (`spp` samples each) and returns
    /// their mean; its `passes` says how many it holds. A device renders several into one
    /// accumulation and reads it back once; the CPU backend renders one, so its sums over passes
    /// stay the same bits whichever way passes are grouped (pass ranges, `merge`).
    pub fn render_passes(
        &mut self,
        spp: u32,
        first: u32,
        passes: u32,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<RenderOutput, GpuError> {
        if self.stop.is_some() {
            set_thread_stop_flag(self.stop.clone());
        }
        let mut out = match &mut self.gpu {
            Some(gpu) => gpu.render_passes(spp, first, passes, self.pixels.as_ref(), progress),
            None => Ok(render_cpu_keeping(
                &self.buffers,
                spp,
                self.photons.as_ref(),
                first,
                self.pixels.as_ref(),
                &mut self.light_stage,
                progress,
            )),
        };
        let mut failed = None;
        if let Some(out) = out.as_mut().ok().filter(|o| self.features && o.complete) {
            let t = std::time::Instant::now();
            let features = match &mut self.gpu {
                Some(gpu) => gpu.render_features(spp, first, out.passes.max(1)),
                None => Ok(super::render_features_cpu(&self.buffers, self.photons.as_ref(), spp, first, 1)),
            };
            match features {
                Ok(Some(features)) => {
                    out.features = Some(features);
                    out.stats.stages.push(("features".to_string(), t.elapsed()));
                }
                Ok(None) => out.complete = false,
                Err(e) => failed = Some(e),
            }
        }
        if let Some(e) = failed {
            out = Err(e);
        }
        if self.stop.is_some() {
            set_thread_stop_flag(None);
        }
        out
    }

    /// The most passes one output of [`Renderer::render_passes`] should hold at `spp` samples per
    /// pass: 1 on the CPU backend and on a CPU device (lavapipe), where a pass's host work is
    /// small beside its kernels; on a GPU as many as make up about 2^24 camera samples, up to
    /// [`MAX_PASS_GROUP`]: a small pass there spends more time in its readback and on the host
    /// than in its kernels.
    pub fn max_pass_group(&self, spp: u32) -> u32 {
        match &self.gpu {
            Some(gpu) if gpu.context().info().device_type != "CPU" => {
                let samples = self.buffers.frame.width as u64 * self.buffers.frame.height as u64 * spp.max(1) as u64;
                ((1u64 << 24) / samples.max(1)).clamp(1, MAX_PASS_GROUP as u64) as u32
            }
            _ => 1,
        }
    }

    /// Replaces the scene and the photon settings, keeping the backend's state: on a device the
    /// kernels stay and only the arrays that changed are written (`last_written` names them).
    pub fn update_scene(&mut self, buffers: &SceneBuffers, photons: Option<&PhotonSettings>) -> Result<(), GpuError> {
        let photons = effective_photons(buffers, photons).copied();
        if let Some(gpu) = &mut self.gpu {
            gpu.update_scene(buffers, photons.as_ref())?;
        }
        self.buffers = buffers.clone();
        self.photons = photons;
        Ok(())
    }

    /// The scene arrays the last `update_scene` wrote to the device (none on the CPU backend).
    pub fn last_written(&self) -> &[&'static str] {
        self.gpu.as_ref().map_or(&[], GpuRenderer::last_written)
    }

    /// The GPU renderer, when this one runs on a device.
    pub fn gpu(&self) -> Option<&GpuRenderer<'a>> {
        self.gpu.as_ref()
    }

    /// Wall time of uploading the scene and creating the kernels (zero on the CPU backend).
    pub fn setup_time(&self) -> Duration {
        self.gpu.as_ref().map_or(Duration::ZERO, GpuRenderer::setup_time)
    }

    /// The photon settings the passes use (`None` for an integrator without photon maps).
    pub fn photons(&self) -> Option<&PhotonSettings> {
        self.photons.as_ref()
    }
}
