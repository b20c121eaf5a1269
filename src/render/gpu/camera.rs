//! The camera stage, and the renderer that keeps its state from pass to pass.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::kernels::{groups, GpuKernels};
use super::maps::{build_maps, no_maps};
use super::scene::DeviceScene;
use crate::gpu::{Buffer, GpuContext, GpuError};
use crate::layout::constants::LAYER_COUNT;
use crate::layout::DispatchRange;
use crate::render::adaptive::{restrict, PixelList};
use crate::render::photons::PhotonSettings;
use crate::render::prepare::KernelVariant;
use crate::render::{
    parts_per_sample, photon_frame, resolve_band, unit_paths, work_units, Layers, RenderOutput, RenderStats,
    SceneBuffers,
};

/// Bytes of accumulation per pixel: one vec4 per layer.
pub(super) const ACCUMULATION_BYTES_PER_PIXEL: u64 = 16 * LAYER_COUNT as u64;
/// Camera-path parts per submission of the camera kernel.
const PATHS_PER_SUBMIT: u64 = 1 << 18;

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
    /// The feature sums (`render_features`), likewise: made only where features are asked for.
    features: Option<(Buffer, u32)>,
    /// The bidirectional integrators' buffers, likewise.
    bidirectional: Option<super::bidirectional::BidirectionalBuffers>,
    /// The pixel list of adaptive sampling's passes on the device, while it stays the same.
    pixel_list: Option<(Arc<PixelList>, Buffer)>,
    /// What the pixel list's binding holds when every pixel is rendered.
    no_pixel_list: Buffer,
    /// Light and camera paths per invocation of vcm_light and render_vcm
    /// (`set_paths_per_invocation`).
    paths_per_invocation: u32,
    /// Vertices per invocation and dispatch of vcm_light and render_vcm, 0 for no bound
    /// (`set_steps_per_dispatch`).
    steps_per_dispatch: u32,
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
        let photons = crate::render::effective_photons(buffers, photons);
        let scene = DeviceScene::upload(ctx, buffers, photons)?;
        let kernels = GpuKernels::for_scene(scene.variant);
        kernels.create_all(ctx, photons.is_some())?;
        Ok(GpuRenderer {
            ctx,
            kernels,
            buffers: buffers.clone(),
            photons: photons.copied(),
            scene,
            accumulation: None,
            features: None,
            bidirectional: None,
            pixel_list: None,
            no_pixel_list: ctx.upload("no_pixel_list", &[0u32])?,
            paths_per_invocation: super::bidirectional::default_paths_per_invocation(ctx),
            steps_per_dispatch: 0,
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

    /// How many paths each invocation of the bidirectional integrators' light and camera kernels
    /// traces one after another (at least 1): by default 32 on CPU devices such as lavapipe,
    /// whose SIMD lanes this keeps busy, and 1 on GPUs. The images are the same whatever the
    /// number; a render that runs into lavapipe's loop limit lowers it (a quarter at a time).
    pub fn set_paths_per_invocation(&mut self, paths: u32) {
        self.paths_per_invocation = paths.max(1);
    }

    /// Paths per invocation of the bidirectional integrators' light and camera kernels now.
    pub fn paths_per_invocation(&self) -> u32 {
        self.paths_per_invocation
    }

    /// How many path vertices each invocation of the bidirectional integrators' kernels traces
    /// per dispatch before it stores its run for the next dispatch to resume (0: no bound, the
    /// default). The images are the same whatever the number; a render that runs into lavapipe's
    /// loop limit a path per invocation sets it (then lowers it, down to 1).
    pub fn set_steps_per_dispatch(&mut self, steps: u32) {
        self.steps_per_dispatch = steps;
    }

    /// Vertices per invocation and dispatch of the bidirectional integrators' kernels now.
    pub fn steps_per_dispatch(&self) -> u32 {
        self.steps_per_dispatch
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
        let photons = crate::render::effective_photons(buffers, photons);
        // After a failed update the device may hold a mix of the two scenes: compare with nothing.
        let previous = (!self.device_mixed).then_some((&self.buffers, self.photons.as_ref()));
        self.device_mixed = true;
        let (in_place, written) = self.scene.update_changed(self.ctx, buffers, photons, previous)?;
        self.device_mixed = false;
        self.last_written = written;
        let variant = self.scene.variant;
        if variant != self.kernels.variant() {
            let kept = self.spare_kernels.iter().position(|k| k.variant() == variant);
            let next = match kept {
                Some(i) => self.spare_kernels.remove(i),
                None => GpuKernels::for_scene(variant),
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
        self.render_passes(spp, pass, 1, None, progress)
    }

    /// Renders up to `passes` consecutive passes from `first` into one accumulation on the
    /// device and reads it back once; the output is their mean and says how many it holds
    /// (`passes`, or 1 where the image is rendered band by band: the accumulation then holds
    /// one band at a time). On a real GPU a small pass's readback and the host's work on it cost
    /// more than its kernels; several passes share them.
    pub fn render_passes(
        &mut self,
        spp: u32,
        first: u32,
        passes: u32,
        pixels: Option<&Arc<PixelList>>,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<RenderOutput, GpuError> {
        let ctx = self.ctx;
        let passes = passes.max(1);
        if let Some(list) = pixels.filter(|l| self.pixel_list.as_ref().is_none_or(|(kept, _)| !Arc::ptr_eq(kept, l))) {
            self.pixel_list = None;
            self.pixel_list = Some((list.clone(), ctx.upload("pixel_list", &list.pixels)?));
        }
        let pixel_buffer = match (&self.pixel_list, pixels) {
            (Some((_, buffer)), Some(_)) => buffer,
            _ => &self.no_pixel_list,
        };
        let list = pixels.map(|l| &**l);
        if self.kernels.variant().bidirectional {
            let on = super::bidirectional::On {
                ctx,
                kernels: &self.kernels,
                scene: &self.scene,
                buffers: &self.buffers,
                pixels: list,
                pixel_buffer,
            };
            let kept = &mut self.bidirectional;
            let runs =
                super::bidirectional::Runs { per: &mut self.paths_per_invocation, steps: &mut self.steps_per_dispatch };
            let mut out =
                super::bidirectional::render_pass_bidirectional(on, kept, runs, spp, first, passes, progress)?;
            out.pixels = pixels.cloned();
            return Ok(out);
        }
        let f = photon_frame(&self.buffers, self.photons.as_ref());
        let mut stages = Vec::new();

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
        let max_rows = crate::render::stop_band_rows(f.width, max_rows);
        let passes = if max_rows >= f.height { passes } else { 1 };
        let bytes = max_rows as u64 * row_bytes;
        if self.accumulation.as_ref().is_none_or(|(b, w)| b.size() != bytes || *w != f.width) {
            self.accumulation = Some((ctx.create_buffer("accumulation", bytes)?, f.width));
        }
        let render_kernel = self.kernels.render(ctx)?;
        let mut layers = Layers::new(f.width, f.height);
        let mut rays = 0;
        let mut download_time = Duration::ZERO;
        let (mut photon_time, mut render_time) = (Duration::ZERO, Duration::ZERO);
        let mut done = 0;
        let mut complete = true;
        'passes: for pass in first..first + passes {
            // Trace photons and build the grids
            let t = Instant::now();
            let maps = match &self.photons {
                Some(settings) => build_maps(
                    ctx,
                    &self.kernels,
                    &self.scene,
                    &self.buffers,
                    settings,
                    pass,
                    &mut self.photon_capacity,
                )?,
                None => no_maps(ctx)?,
            };
            photon_time += t.elapsed();
            let accumulation = &self.accumulation.as_ref().expect("created just above").0;

            // Gather, band by band
            let t = Instant::now();
            let download_before = download_time;
            let units = work_units(f.height, spp, parts_per_sample(&f), max_rows, pass);
            let total = units.total_rows() * passes as u64;
            let mut units = units.peekable();
            // Consecutive units of one band go into one submission of up to PATHS_PER_SUBMIT
            // paths: few submissions, yet none long enough to trip a GPU watchdog.
            let mut batch: Vec<DispatchRange> = Vec::new();
            while let Some(first_unit) = units.next() {
                let first_unit = restrict(first_unit, list);
                let band = first_unit.row_begin;
                let mut paths = first_unit.row_count as u64 * f.width as u64;
                batch.clear();
                batch.push(first_unit);
                while paths < crate::render::thread_stop_paths().unwrap_or(PATHS_PER_SUBMIT) {
                    let Some(unit) = units.next_if(|u| u.row_begin == band) else { break };
                    paths += unit.row_count as u64 * f.width as u64;
                    batch.push(restrict(unit, list));
                }
                if crate::render::stop_requested() {
                    complete = false;
                    break 'passes;
                }
                // A band's accumulation is cleared at its first unit of the first pass and read
                // back after its last unit of the last pass (with one band when passes > 1).
                let clear = pass == first && batch[0].sample_index == pass * spp && batch[0].part == 0;
                let band_pixels = batch[0].row_count * f.width;
                let dispatched = crate::cpu::pixel_list::dispatch_pixels(f.width, &batch[0]);
                ctx.run("render", |rec| {
                    if clear {
                        rec.fill_zero(accumulation)?;
                    }
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
                                pixel_buffer,
                            ]),
                            bytemuck::bytes_of(unit),
                            groups(dispatched.max(1)),
                        )?;
                    }
                    Ok(())
                })?;
                done += batch.iter().map(unit_paths).sum::<u64>();
                progress(done, total);
                if pass + 1 == first + passes && units.peek().is_none_or(|next| next.row_begin != band) {
                    let td = Instant::now();
                    let sums: Vec<[f32; 4]> = ctx.download(accumulation)?;
                    let len = (band_pixels * LAYER_COUNT) as usize;
                    rays += resolve_band(&mut layers, band, &sums[..len], spp * passes);
                    download_time += td.elapsed();
                }
            }
            render_time += t.elapsed() - (download_time - download_before);
        }
        if self.photons.is_some() {
            stages.push(("photons".to_string(), photon_time));
        }
        stages.push(("render".to_string(), render_time));
        stages.push(("download".to_string(), download_time));
        let stats = RenderStats::device(ctx, stages, rays, spp * passes);
        Ok(RenderOutput::new(layers, stats, complete, passes, pixels.cloned()))
    }
}

impl GpuRenderer<'_> {
    /// The feature layers of passes `first..first + passes` (`spp` samples each), averaged over
    /// their samples, band by band as the camera kernel goes; `None` when a stop request cut them
    /// short. The same sums as `render::render_features_cpu`, sample for sample.
    pub fn render_features(
        &mut self,
        spp: u32,
        first: u32,
        passes: u32,
    ) -> Result<Option<crate::render::Features>, GpuError> {
        use crate::layout::constants::FEATURE_COUNT;
        let ctx = self.ctx;
        let f = photon_frame(&self.buffers, self.photons.as_ref());
        let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
        let row_bytes = f.width as u64 * 16 * FEATURE_COUNT as u64;
        let max_rows = (limit / row_bytes).min(f.height as u64) as u32;
        if max_rows == 0 {
            return Err(GpuError::Unsupported(format!(
                "one row of feature layers of {} pixels needs {row_bytes} bytes, more than the device's storage buffer limit of {limit} bytes; lower the resolution",
                f.width
            )));
        }
        let max_rows = crate::render::stop_band_rows(f.width, max_rows);
        let bytes = max_rows as u64 * row_bytes;
        if self.features.as_ref().is_none_or(|(b, w)| b.size() != bytes || *w != f.width) {
            self.features = Some((ctx.create_buffer("features", bytes)?, f.width));
        }
        let buffer = &self.features.as_ref().expect("created just above").0;
        let kernel = self.kernels.render_features(ctx)?;
        let mut features = crate::render::Features::new(f.width, f.height);
        let mut band = 0;
        while band < f.height {
            let rows = max_rows.min(f.height - band);
            // Every sample of every pass of this band, one submission per band of samples.
            let units: Vec<DispatchRange> = (first..first + passes)
                .flat_map(|pass| (0..spp).map(move |s| pass * spp + s))
                .map(|sample_index| DispatchRange {
                    row_begin: band,
                    row_count: rows,
                    sample_index,
                    part: 0,
                    pixel_list: crate::layout::constants::NO_PIXEL_LIST,
                    pixel_count: 0,
                })
                .collect();
            let per_submit = (PATHS_PER_SUBMIT / (rows as u64 * f.width as u64)).max(1) as usize;
            for (k, chunk) in units.chunks(per_submit).enumerate() {
                if crate::render::stop_requested() {
                    return Ok(None);
                }
                ctx.run("render_features", |rec| {
                    if k == 0 {
                        rec.fill_zero(buffer)?;
                    }
                    for unit in chunk {
                        rec.dispatch(
                            kernel,
                            &self.scene.bindings(&[buffer]),
                            bytemuck::bytes_of(unit),
                            groups(rows * f.width),
                        )?;
                    }
                    Ok(())
                })?;
            }
            let sums: Vec<[f32; 4]> = ctx.download(buffer)?;
            features.resolve_band(band, &sums[..(rows * f.width * FEATURE_COUNT) as usize], spp * passes);
            band += rows;
        }
        Ok(Some(features))
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
