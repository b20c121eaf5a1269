//! Rendering a scene on either backend: the GPU kernels or their CPU twins. Both split the image
//! into the same work units (bands of rows x runs of samples), so both report progress alike and
//! no GPU dispatch runs long enough to trip a driver watchdog.

pub mod accumulation;
pub mod adaptive;
pub mod bench;
pub mod denoise;
pub mod gpu;
pub mod instances;
pub mod light_tree;
pub mod media_bounds;
pub mod memory;
pub mod open_edges;
pub mod pack;
pub mod pack_csg;
pub mod photons;
pub mod plastic_coat;
pub mod prepare;
pub mod progressive;
pub mod renderer;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use adaptive::PixelList;

pub use photons::PhotonSettings;
pub use prepare::{prepare, FrameSettings, KernelVariant, PrepareError, SceneBuffers};
pub use renderer::Renderer;

use crate::gpu::{DeviceInfo, GpuError};
use crate::io::Image;
use crate::layout::constants::{
    FEATURE_ALBEDO, FEATURE_COUNT, FEATURE_NORMAL, FEATURE_POSITION, INTEGRATOR_BPT, INTEGRATOR_PPM, INTEGRATOR_PT,
    INTEGRATOR_VCM, LAYER_COUNT, LAYER_DIRECT, NO_PIXEL_LIST,
};
use crate::layout::{DispatchRange, FrameParams};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Gpu,
    Cpu,
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}

/// The backend `--backend auto` picks, and why, from the Vulkan devices the loader lists (or its
/// failure to list any) and whether the user named a `--device`:
/// - a named device, or any real GPU (discrete, integrated or virtual): the kernels on it;
/// - only CPU devices (lavapipe), or no Vulkan at all: the CPU backend. It draws the same random
///   numbers and renders the same image, and on the same cores it is several times faster than
///   the kernels through lavapipe (BENCHMARKS.md, "Backends on a machine without a GPU").
pub fn auto_backend(devices: &Result<Vec<DeviceInfo>, GpuError>, device_requested: bool) -> (Backend, String) {
    if device_requested {
        return (Backend::Gpu, "a --device was named".to_string());
    }
    let devices = match devices {
        Ok(devices) => devices,
        Err(_) => return (Backend::Cpu, "no Vulkan driver found".to_string()),
    };
    let is_gpu = |d: &&DeviceInfo| matches!(d.device_type.as_str(), "discrete GPU" | "integrated GPU" | "virtual GPU");
    // The same preference as the device choice: discrete, then integrated, then virtual.
    let rank =
        |d: &&DeviceInfo| ["discrete GPU", "integrated GPU", "virtual GPU"].iter().position(|t| *t == d.device_type);
    match devices.iter().filter(is_gpu).min_by_key(|d| (rank(d), d.index)) {
        Some(gpu) => (Backend::Gpu, format!("{} {} found", gpu.device_type, gpu.name)),
        None if devices.is_empty() => (Backend::Cpu, "no Vulkan device found".to_string()),
        None => {
            let names: Vec<&str> = devices.iter().map(|d| d.name.as_str()).collect();
            (
                Backend::Cpu,
                format!("no GPU, only {} running on the CPU, where the CPU backend is faster", names.join(", ")),
            )
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Bvh(#[from] crate::accel::BvhError),
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    #[error(transparent)]
    Refused(#[from] Refused),
}

/// A render that would fail or come out wrong, refused before it starts; the message says why
/// and what to change.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Refused(pub String);

/// What a render measured.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Named stages with wall-clock time (prepare, upload, render, download).
    pub stages: Vec<(String, Duration)>,
    /// GPU time per kernel from timestamp queries: (name, seconds, dispatches).
    pub kernel_times: Vec<(String, f64, u32)>,
    /// Rays cast: camera, specular and shadow rays.
    pub rays: u64,
    pub samples_per_pixel: u32,
    pub device: String,
}

impl RenderStats {
    /// A pass's figures on the CPU backend.
    pub fn cpu(stages: Vec<(String, Duration)>, rays: u64, spp: u32) -> RenderStats {
        RenderStats {
            stages,
            rays,
            samples_per_pixel: spp,
            device: format!("CPU reference ({} threads)", rayon::current_num_threads()),
            ..Default::default()
        }
    }

    /// A pass's figures on device `ctx`, with the kernel times its timestamp queries took.
    pub fn device(ctx: &crate::gpu::GpuContext, stages: Vec<(String, Duration)>, rays: u64, spp: u32) -> RenderStats {
        RenderStats {
            stages,
            kernel_times: ctx.take_timings(),
            rays,
            samples_per_pixel: spp,
            device: format!("{} ({})", ctx.info().name, ctx.info().driver),
        }
    }

    pub fn stage(&self, name: &str) -> Duration {
        self.stages.iter().filter(|(n, _)| n == name).map(|(_, d)| *d).sum()
    }
}

/// The four terms of a render; `combined` is their sum.
#[derive(Clone, Debug, PartialEq)]
pub struct Layers {
    pub direct: Image,
    pub specular: Image,
    pub indirect: Image,
    pub caustics: Image,
}

impl Layers {
    pub fn new(width: u32, height: u32) -> Layers {
        let blank = Image::new(width, height);
        Layers { direct: blank.clone(), specular: blank.clone(), indirect: blank.clone(), caustics: blank }
    }

    /// The terms in `LAYER_*` order with their names.
    pub fn named(&self) -> [(&'static str, &Image); 4] {
        [
            ("direct", &self.direct),
            ("specular", &self.specular),
            ("indirect", &self.indirect),
            ("caustics", &self.caustics),
        ]
    }

    pub fn named_mut(&mut self) -> [(&'static str, &mut Image); 4] {
        [
            ("direct", &mut self.direct),
            ("specular", &mut self.specular),
            ("indirect", &mut self.indirect),
            ("caustics", &mut self.caustics),
        ]
    }

    fn layer_mut(&mut self, layer: usize) -> &mut Image {
        match layer {
            0 => &mut self.direct,
            1 => &mut self.specular,
            2 => &mut self.indirect,
            _ => &mut self.caustics,
        }
    }

    pub fn combined(&self) -> Image {
        let mut out = self.direct.clone();
        for (_, layer) in &self.named()[1..] {
            for (o, p) in out.pixels.iter_mut().zip(&layer.pixels) {
                for c in 0..3 {
                    o[c] += p[c];
                }
            }
        }
        out
    }
}

/// The feature layers of a render (src/cpu/render_features.rs): the denoiser's guides and the
/// pipelines' depth and position. Depth fills all three channels.
#[derive(Clone, Debug, PartialEq)]
pub struct Features {
    pub albedo: Image,
    pub normal: Image,
    pub depth: Image,
    pub position: Image,
}

impl Features {
    pub fn new(width: u32, height: u32) -> Features {
        let blank = Image::new(width, height);
        Features { albedo: blank.clone(), normal: blank.clone(), depth: blank.clone(), position: blank }
    }

    /// The layers with their EXR names.
    pub fn named(&self) -> [(&'static str, &Image); 4] {
        [("albedo", &self.albedo), ("normal", &self.normal), ("depth", &self.depth), ("position", &self.position)]
    }

    pub fn named_mut(&mut self) -> [(&'static str, &mut Image); 4] {
        [
            ("albedo", &mut self.albedo),
            ("normal", &mut self.normal),
            ("depth", &mut self.depth),
            ("position", &mut self.position),
        ]
    }

    /// Divides feature sums (`FEATURE_COUNT` vec4 per pixel) by the sample count and copies one
    /// band of them in from row `row_begin`.
    pub fn resolve_band(&mut self, row_begin: u32, sums: &[[f32; 4]], samples: u32) {
        let start = (row_begin * self.albedo.width) as usize;
        let inv = 1.0 / samples.max(1) as f32;
        for (i, pixel) in sums.chunks_exact(FEATURE_COUNT as usize).enumerate() {
            let [a, n, p] =
                [FEATURE_ALBEDO, FEATURE_NORMAL, FEATURE_POSITION].map(|k| pixel[k as usize].map(|c| c * inv));
            self.albedo.pixels[start + i] = [a[0], a[1], a[2]];
            self.normal.pixels[start + i] = [n[0], n[1], n[2]];
            self.position.pixels[start + i] = [p[0], p[1], p[2]];
            self.depth.pixels[start + i] = [p[3]; 3];
        }
    }
}

pub struct RenderOutput {
    pub layers: Layers,
    /// The feature layers (means over the same samples), where the renderer was asked for them
    /// ([`Renderer::set_features`](renderer::Renderer::set_features)).
    pub features: Option<Features>,
    /// The sum of the layers: what `-o` writes.
    pub image: Image,
    pub stats: RenderStats,
    /// False when a stop request cut the render short: the image is then not to be used.
    pub complete: bool,
    /// The consecutive passes the layers are the mean of (1 but where a device rendered several
    /// into one accumulation: see [`Renderer::render_passes`](renderer::Renderer::render_passes)).
    pub passes: u32,
    /// The pixels the passes rendered (`None`: all); the others are zero in the layers.
    pub pixels: Option<Arc<PixelList>>,
}

impl RenderOutput {
    /// The output of `passes` passes with `layers` their mean, of the pixels of `pixels` (all
    /// with `None`), and no feature layers yet.
    pub fn new(
        layers: Layers,
        stats: RenderStats,
        complete: bool,
        passes: u32,
        pixels: Option<Arc<PixelList>>,
    ) -> Self {
        RenderOutput { image: layers.combined(), layers, features: None, stats, complete, passes, pixels }
    }
}

/// The dispatches of pass `pass`, in the order both backends accumulate them: per band of rows,
/// per sample, per part (part 0 plus one part per final-gather ray; see `DispatchRange`). Pass p
/// draws samples p * spp .. (p + 1) * spp, so passes are independent. An iterator, never a list:
/// its memory does not grow with the sample count.
pub fn work_units(height: u32, spp: u32, parts: u32, max_band_rows: u32, pass: u32) -> WorkUnits {
    let band_rows = max_band_rows.clamp(1, height.max(1));
    WorkUnits { height, spp, parts: parts.max(1), band_rows, pass, row: 0, sample: 0, part: 0 }
}

/// The work units of one pass, made one at a time; see `work_units`.
#[derive(Clone, Debug)]
pub struct WorkUnits {
    height: u32,
    spp: u32,
    parts: u32,
    band_rows: u32,
    pass: u32,
    // The next unit.
    row: u32,
    sample: u32,
    part: u32,
}

impl WorkUnits {
    /// Camera-path rows over all units (the progress total): every row, sample and part once.
    pub fn total_rows(&self) -> u64 {
        self.height as u64 * self.spp as u64 * self.parts as u64
    }
}

impl Iterator for WorkUnits {
    type Item = DispatchRange;

    fn next(&mut self) -> Option<DispatchRange> {
        if self.row >= self.height || self.spp == 0 {
            return None;
        }
        let row_count = self.band_rows.min(self.height - self.row);
        // The sample ranges make this fit: pass * spp + sample < MAX_PASSES * MAX_SPP < 2^32.
        let sample_index = self.pass * self.spp + self.sample;
        let unit = DispatchRange {
            row_begin: self.row,
            row_count,
            sample_index,
            part: self.part,
            pixel_list: NO_PIXEL_LIST,
            pixel_count: 0,
        };
        self.part += 1;
        if self.part == self.parts {
            self.part = 0;
            self.sample += 1;
            if self.sample == self.spp {
                self.sample = 0;
                self.row += row_count;
            }
        }
        Some(unit)
    }
}

/// Parts per sample: the camera part, plus one per final-gather ray.
pub fn parts_per_sample(frame: &FrameParams) -> u32 {
    1 + if frame.photon_mapping != 0 { frame.gather_rays } else { 0 }
}

/// Divides accumulated sums (`LAYER_COUNT` vec4 per pixel) by the sample count and copies one
/// band into `layers`; returns the band's ray count.
pub fn resolve_band(layers: &mut Layers, row_begin: u32, accumulation: &[[f32; 4]], spp: u32) -> u64 {
    let start = (row_begin * layers.direct.width) as usize;
    let inv = 1.0 / spp as f32;
    let mut rays = 0u64;
    for (i, pixel) in accumulation.chunks_exact(LAYER_COUNT as usize).enumerate() {
        for (layer, sum) in pixel.iter().enumerate() {
            layers.layer_mut(layer).pixels[start + i] = [sum[0] * inv, sum[1] * inv, sum[2] * inv];
        }
        rays += pixel[LAYER_DIRECT as usize][3] as u64;
    }
    rays
}

/// The photon settings a render of `buffers` uses: none for an integrator without photon maps
/// (`[render] integrator`), whatever the scene or the command line asked for.
pub fn effective_photons<'p>(
    buffers: &SceneBuffers,
    photons: Option<&'p PhotonSettings>,
) -> Option<&'p PhotonSettings> {
    photons.filter(|_| buffers.frame.integrator == INTEGRATOR_PPM)
}

/// The frame constants with photon mapping switched on or off. A path tracer samples every
/// non-delta lobe with the BSDF's own density and light sampling, so no glossy lobe is a path
/// lobe there (`glossy_threshold` 0).
pub fn photon_frame(buffers: &SceneBuffers, photons: Option<&PhotonSettings>) -> FrameParams {
    let photons = effective_photons(buffers, photons);
    let mut frame = buffers.frame;
    frame.photon_mapping = photons.is_some() as u32;
    frame.gather_rays = photons.map_or(0, |p| p.gather_rays);
    if frame.integrator != INTEGRATOR_PPM {
        frame.glossy_threshold = 0.0;
    }
    frame
}

/// Set by a signal handler (Ctrl-C, SIGTERM): renders stop after the dispatch under way and
/// return an incomplete output.
pub static STOP: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// A stop flag of this thread's own, besides `STOP`: a server running renders on threads of
    /// its own (the editor) stops one without stopping the others.
    static THREAD_STOP: std::cell::RefCell<Option<std::sync::Arc<AtomicBool>>> = const { std::cell::RefCell::new(None) };
}

/// Makes renders on the calling thread also stop when `flag` is set (`None`: only `STOP`).
pub fn set_thread_stop_flag(flag: Option<std::sync::Arc<AtomicBool>>) {
    THREAD_STOP.with(|f| *f.borrow_mut() = flag);
}

thread_local! {
    /// At most this many paths (photon or camera) between two looks at the stop flags on this
    /// thread; `None` leaves each backend its own, larger, submissions.
    static THREAD_STOP_PATHS: std::cell::Cell<Option<u64>> = const { std::cell::Cell::new(None) };
}

/// Makes renders on the calling thread look at the stop flags at least every `paths` paths,
/// photon tracing included: an interactive preview (the editor) must drop a stale pass within
/// a fraction of a second, which whole passes on lavapipe or the CPU take seconds to reach. The
/// image is the same; only the submissions are smaller.
pub fn set_thread_stop_paths(paths: Option<u64>) {
    THREAD_STOP_PATHS.with(|p| p.set(paths.map(|p| p.max(1))));
}

/// The calling thread's `set_thread_stop_paths`.
pub fn thread_stop_paths() -> Option<u64> {
    THREAD_STOP_PATHS.with(|p| p.get())
}

/// Rows of a band of `width`-pixel rows (at most `rows`) holding at most the thread's
/// stop-check paths, for a render that looks at the stop flags between bands.
pub fn stop_band_rows(width: u32, rows: u32) -> u32 {
    thread_stop_paths().map_or(rows, |paths| rows.min((paths / width.max(1) as u64).max(1) as u32)).max(1)
}

pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed) || THREAD_STOP.with(|f| f.borrow().as_ref().is_some_and(|f| f.load(Ordering::Relaxed)))
}

/// Renders pass `pass` on the CPU reference, with photon maps when `photons` is given;
/// `progress(done, total)` is called after each work unit.
pub fn render_cpu(
    buffers: &SceneBuffers,
    spp: u32,
    photons: Option<&PhotonSettings>,
    pass: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> RenderOutput {
    render_cpu_keeping(buffers, spp, photons, pass, None, &mut Default::default(), progress)
}

/// `render_cpu` of the pixels of `pixels` (all with `None`), keeping the bidirectional
/// integrators' light-stage buffers in `stage` between passes (a `Renderer` holds one).
pub fn render_cpu_keeping(
    buffers: &SceneBuffers,
    spp: u32,
    photons: Option<&PhotonSettings>,
    pass: u32,
    pixels: Option<&Arc<PixelList>>,
    stage: &mut crate::cpu::vcm::LightStage,
    progress: &mut dyn FnMut(u64, u64),
) -> RenderOutput {
    let mut stages = Vec::new();
    let t = Instant::now();
    let photons = effective_photons(buffers, photons);
    let maps = photons.map(|settings| photons::build_indices_cpu(buffers, settings, pass));
    if maps.is_some() {
        stages.push(("photons".to_string(), t.elapsed()));
    }
    let frame = photon_frame(buffers, photons);
    let mut view = buffers.view();
    view.frame = &frame;
    if let Some(maps) = &maps {
        view.maps = maps.view();
    }
    if let Some(list) = pixels {
        view.pixel_list = &list.pixels;
    }

    if frame.integrator == INTEGRATOR_BPT || frame.integrator == INTEGRATOR_VCM {
        let mut out = render_vcm_cpu(buffers, &view, spp, pass, pixels.map(|l| &**l), stage, stages, progress);
        out.pixels = pixels.cloned();
        return out;
    }
    let t = Instant::now();
    let mut layers = Layers::new(frame.width, frame.height);
    let band_rows = stop_band_rows(frame.width, frame.height);
    let units = work_units(frame.height, spp, parts_per_sample(&frame), band_rows, pass);
    let total = units.total_rows();
    let mut done = 0;
    let mut accumulation = vec![[0.0f32; 4]; (frame.width * frame.height * LAYER_COUNT) as usize];
    let mut complete = true;
    for unit in units {
        if stop_requested() {
            complete = false;
            break;
        }
        let unit = adaptive::restrict(unit, pixels.map(|l| &**l));
        let band = &mut accumulation[(unit.row_begin * frame.width * LAYER_COUNT) as usize..];
        if frame.integrator == INTEGRATOR_PT {
            crate::cpu::render_pt::render_pt(&view, &unit, band);
        } else {
            crate::cpu::render::render(&view, &unit, band);
        }
        done += unit_paths(&unit);
        progress(done, total);
    }
    let rays = resolve_band(&mut layers, 0, &accumulation, spp);
    stages.push(("render".to_string(), t.elapsed()));
    let stats = RenderStats::cpu(stages, rays, spp);
    RenderOutput::new(layers, stats, complete, 1, pixels.cloned())
}

/// A pass of the bidirectional integrators on the CPU: per sample, the light stage, then the
/// camera stage band by band (a sample's bands all read its light sub-paths), of the pixels of
/// `pixels` (`view.pixel_list`) or all.
#[allow(clippy::too_many_arguments)]
fn render_vcm_cpu(
    buffers: &SceneBuffers,
    view: &crate::cpu::SceneView,
    spp: u32,
    pass: u32,
    pixels: Option<&PixelList>,
    stage: &mut crate::cpu::vcm::LightStage,
    mut stages: Vec<(String, Duration)>,
    progress: &mut dyn FnMut(u64, u64),
) -> RenderOutput {
    let frame = *view.frame;
    let mut layers = Layers::new(frame.width, frame.height);
    let band_rows = stop_band_rows(frame.width, frame.height);
    let total = frame.height as u64 * spp as u64;
    let mut done = 0;
    let mut accumulation = vec![[0.0f32; 4]; (frame.width * frame.height * LAYER_COUNT) as usize];
    let mut complete = true;
    let (mut light_time, mut camera_time) = (Duration::ZERO, Duration::ZERO);
    let view_distance = crate::cpu::vcm::view_distance(view, buffers.bounding_radius);
    let base_radius = crate::cpu::vcm::vcm_base_radius(&frame, buffers.surface_area, view_distance);
    'samples: for sample in 0..spp {
        let sample_index = pass * spp + sample;
        let t = Instant::now();
        let params = crate::cpu::vcm::vcm_params(&frame, base_radius, sample_index);
        crate::cpu::vcm::light_stage(view, &params, stage);
        light_time += t.elapsed();
        let t = Instant::now();
        for unit in work_units(frame.height, 1, 1, band_rows, sample_index) {
            if stop_requested() {
                complete = false;
                break 'samples;
            }
            let unit = adaptive::restrict(unit, pixels);
            let band = &mut accumulation[(unit.row_begin * frame.width * LAYER_COUNT) as usize..];
            crate::cpu::vcm::render_vcm(view, &params, stage, &unit, band);
            done += unit_paths(&unit);
            progress(done, total);
        }
        camera_time += t.elapsed();
    }
    let rays = resolve_band(&mut layers, 0, &accumulation, spp);
    stages.push(("light paths".to_string(), light_time));
    stages.push(("render".to_string(), camera_time));
    let stats = RenderStats::cpu(stages, rays, spp);
    RenderOutput::new(layers, stats, complete, 1, None)
}

/// The feature layers of passes `first..first + passes` (`spp` samples each) on the CPU backend,
/// averaged over their samples; `None` when a stop request cut them short.
pub fn render_features_cpu(
    buffers: &SceneBuffers,
    photons: Option<&PhotonSettings>,
    spp: u32,
    first: u32,
    passes: u32,
) -> Option<Features> {
    let frame = photon_frame(buffers, photons);
    let mut view = buffers.view();
    view.frame = &frame;
    let band_rows = stop_band_rows(frame.width, frame.height);
    let mut sums = vec![[0.0f32; 4]; (frame.width * frame.height * FEATURE_COUNT) as usize];
    for pass in first..first + passes {
        for unit in work_units(frame.height, spp, 1, band_rows, pass) {
            if stop_requested() {
                return None;
            }
            let band = &mut sums[(unit.row_begin * frame.width * FEATURE_COUNT) as usize..];
            crate::cpu::render_features::render_features(&view, &unit, band);
        }
    }
    let mut features = Features::new(frame.width, frame.height);
    features.resolve_band(0, &sums, spp * passes);
    Some(features)
}

fn unit_paths(unit: &DispatchRange) -> u64 {
    unit.row_count as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(index: usize, name: &str, device_type: &str) -> DeviceInfo {
        DeviceInfo {
            index,
            name: name.to_string(),
            device_type: device_type.to_string(),
            driver: String::new(),
            api_version: "1.3.0".to_string(),
            max_storage_buffer_range: 1 << 27,
            max_texel_buffer_elements: 1 << 27,
            max_memory_allocation_size: 1 << 31,
            max_compute_workgroup_invocations: 1024,
            max_compute_workgroup_count: [65535; 3],
            max_push_constants_size: 128,
            subgroup_size: 8,
            timestamp_period_ns: 1.0,
            device_local_heap_bytes: 1 << 31,
            features: Vec::new(),
        }
    }

    #[test]
    fn auto_backend_prefers_a_real_gpu_and_else_the_cpu() {
        let lavapipe = device(0, "llvmpipe (LLVM 15.0.6, 256 bits)", "CPU");
        let (backend, why) = auto_backend(&Ok(vec![lavapipe.clone()]), false);
        assert_eq!(backend, Backend::Cpu);
        assert!(why.contains("llvmpipe") && why.contains("CPU backend is faster"), "{why}");

        let gpus = vec![lavapipe.clone(), device(1, "Intel UHD", "integrated GPU"), device(2, "RTX", "discrete GPU")];
        let (backend, why) = auto_backend(&Ok(gpus), false);
        assert_eq!(backend, Backend::Gpu);
        assert!(why.contains("discrete GPU RTX"), "{why}");

        assert_eq!(auto_backend(&Err(GpuError::NoDriver), false).0, Backend::Cpu);
        assert_eq!(auto_backend(&Ok(Vec::new()), false).0, Backend::Cpu);
        // A named device means the kernels, even on lavapipe.
        assert_eq!(auto_backend(&Ok(vec![lavapipe]), true).0, Backend::Gpu);
    }

    /// The order the list used to have, built eagerly, for comparison.
    fn listed(height: u32, spp: u32, parts: u32, band_rows: u32, pass: u32) -> Vec<DispatchRange> {
        let mut units = Vec::new();
        let mut row = 0;
        while row < height {
            let rows = band_rows.min(height - row);
            for sample in 0..spp {
                for part in 0..parts {
                    units.push(DispatchRange {
                        row_begin: row,
                        row_count: rows,
                        sample_index: pass * spp + sample,
                        part,
                        pixel_list: NO_PIXEL_LIST,
                        pixel_count: 0,
                    });
                }
            }
            row += rows;
        }
        units
    }

    #[test]
    fn work_units_come_in_band_sample_part_order() {
        for (height, spp, parts, band, pass) in
            [(16, 3, 2, 5, 0), (7, 1, 1, 100, 4), (1, 4, 9, 1, 2), (10, 2, 1, 10, 1)]
        {
            let units = work_units(height, spp, parts, band, pass);
            let rows: u64 = units.clone().map(|u| u.row_count as u64).sum();
            assert_eq!(rows, units.total_rows());
            assert_eq!(units.collect::<Vec<_>>(), listed(height, spp, parts, band.clamp(1, height), pass));
        }
    }

    #[test]
    fn work_units_take_no_memory_per_sample() {
        // 4096 samples of 1000 parts: four million units, made one at a time.
        let units = work_units(1, 4096, 1000, 1, 999_999);
        assert!(size_of_val(&units) < 64);
        assert_eq!(units.total_rows(), 4_096_000);
        let last = units.last().unwrap();
        assert_eq!((last.sample_index, last.part), (999_999 * 4096 + 4095, 999));
    }
}
