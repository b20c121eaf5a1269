//! One renderer that every front-end drives (the command line, the Python package, benches):
//! the backend chosen once, its state kept across passes, the integrator and photon settings
//! applied in one place (`effective_photons`), and a stop signal of its own.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

use super::gpu::GpuRenderer;
use super::{effective_photons, render_cpu_keeping, set_thread_stop_flag, PhotonSettings, RenderOutput, SceneBuffers};
use crate::cpu::vcm::LightStage;
use crate::gpu::{GpuContext, GpuError};

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
        Ok(Renderer { buffers: buffers.clone(), photons, gpu, light_stage: LightStage::default(), stop: None })
    }

    /// Makes passes stop (returning an incomplete output after the dispatch under way) when
    /// `flag` is set, besides the process-wide `render::STOP`.
    pub fn set_stop_flag(&mut self, flag: Option<Arc<AtomicBool>>) {
        self.stop = flag;
    }

    /// Renders pass `pass` with `spp` samples per pixel; `progress(done, total)` is called as work
    /// units finish.
    pub fn render_pass(
        &mut self,
        spp: u32,
        pass: u32,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<RenderOutput, GpuError> {
        if self.stop.is_some() {
            set_thread_stop_flag(self.stop.clone());
        }
        let out = match &mut self.gpu {
            Some(gpu) => gpu.render_pass(spp, pass, progress),
            None => {
                Ok(render_cpu_keeping(&self.buffers, spp, self.photons.as_ref(), pass, &mut self.light_stage, progress))
            }
        };
        if self.stop.is_some() {
            set_thread_stop_flag(None);
        }
        out
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
