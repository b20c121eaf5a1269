//! Rendering a scene on either backend: the GPU kernels or their CPU twins. Both split the image
//! into the same work units (bands of rows x runs of samples), so both report progress alike and
//! no GPU dispatch runs long enough to trip a driver watchdog.

pub mod bench;
pub mod gpu;
pub mod prepare;

use std::time::{Duration, Instant};

pub use prepare::{prepare, FrameSettings, SceneBuffers};

use crate::io::Image;
use crate::layout::DispatchRange;

/// Camera paths per dispatch: about 0.1 s of work on lavapipe, far below any GPU watchdog.
const PATHS_PER_DISPATCH: u64 = 1 << 18;

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

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Bvh(#[from] crate::accel::BvhError),
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
}

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
    pub fn stage(&self, name: &str) -> Duration {
        self.stages.iter().filter(|(n, _)| n == name).map(|(_, d)| *d).sum()
    }
}

pub struct RenderOutput {
    pub image: Image,
    pub stats: RenderStats,
}

/// One unit of work: a band of rows and a run of samples, as one dispatch renders it.
pub fn work_units(width: u32, height: u32, spp: u32, max_band_rows: u32) -> Vec<DispatchRange> {
    let band_rows = max_band_rows.clamp(1, height.max(1));
    let mut units = Vec::new();
    let mut row = 0;
    while row < height {
        let rows = band_rows.min(height - row);
        let pixels = rows as u64 * width as u64;
        let samples_per_unit = (PATHS_PER_DISPATCH / pixels.max(1)).clamp(1, spp.max(1) as u64) as u32;
        let mut sample = 0;
        while sample < spp {
            let count = samples_per_unit.min(spp - sample);
            units.push(DispatchRange { row_begin: row, row_count: rows, sample_begin: sample, sample_count: count });
            sample += count;
        }
        row += rows;
    }
    units
}

/// Divides accumulated sums by the sample count and copies one band into `image`; returns the
/// band's ray count.
pub fn resolve_band(image: &mut Image, row_begin: u32, accumulation: &[[f32; 4]], spp: u32) -> u64 {
    let start = (row_begin * image.width) as usize;
    let inv = 1.0 / spp as f32;
    let mut rays = 0u64;
    for (dst, src) in image.pixels[start..].iter_mut().zip(accumulation) {
        *dst = [src[0] * inv, src[1] * inv, src[2] * inv];
        rays += src[3] as u64;
    }
    rays
}

/// Renders on the CPU reference; `progress(done, total)` is called after each work unit.
pub fn render_cpu(buffers: &SceneBuffers, spp: u32, progress: &mut dyn FnMut(u64, u64)) -> RenderOutput {
    let f = buffers.frame;
    let mut image = Image::new(f.width, f.height);
    let start = Instant::now();
    let units = work_units(f.width, f.height, spp, f.height);
    let total: u64 = units.iter().map(unit_paths).sum();
    let mut done = 0;
    let mut rays = 0;
    let mut accumulation = vec![[0.0f32; 4]; (f.width * f.height) as usize];
    let view = buffers.view();
    for unit in &units {
        let band = &mut accumulation[(unit.row_begin * f.width) as usize..];
        crate::cpu::render::render(&view, unit, band);
        done += unit_paths(unit);
        progress(done, total);
    }
    rays += resolve_band(&mut image, 0, &accumulation, spp);
    let device = format!("CPU reference ({} threads)", rayon::current_num_threads());
    let stats = RenderStats {
        stages: vec![("render".into(), start.elapsed())],
        rays,
        samples_per_pixel: spp,
        device,
        ..Default::default()
    };
    RenderOutput { image, stats }
}

fn unit_paths(unit: &DispatchRange) -> u64 {
    unit.row_count as u64 * unit.sample_count as u64
}
