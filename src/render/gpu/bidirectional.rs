//! The bidirectional integrators (`bpt`, `vcm`) on the device: per sample, the light stage
//! (vcm_light: light sub-paths, their vertex slots, their points and the light-tracing splats),
//! the grid over the points, then the camera stage (render_vcm) band by band. The same
//! algorithm and random numbers as `cpu::vcm`.

use std::time::{Duration, Instant};

use super::camera::ACCUMULATION_BYTES_PER_PIXEL;
use super::kernels::{groups, GpuKernels};
use super::maps::build_map;
use super::scene::DeviceScene;
use crate::cpu::pixel_list::dispatch_pixels;
use crate::cpu::vcm::{light_path_count, vcm_params, vertex_grid};
use crate::gpu::{Buffer, GpuContext, GpuError};
use crate::layout::constants::{LAYER_COUNT, VCM_CAMERA_STATE_WORDS, VCM_LIGHT_STATE_WORDS, VCM_PICK_BLOCK};
use crate::layout::{DispatchRange, GridParams, LightMaterial, LightVertex, Photon, VcmParams};
use crate::render::adaptive::{restrict, PixelList};
use crate::render::{resolve_band, stop_band_rows, unit_paths, work_units, Layers, RenderOutput, RenderStats};
use crate::render::{stop_requested, SceneBuffers};

// render_vcm reads a block's counts as one RGBA32UI texel.
const _: () = assert!(VCM_PICK_BLOCK == 4, "render_vcm.comp reads VCM_PICK_BLOCK counts as one texel");

/// Light paths per vcm_light dispatch.
const PATHS_PER_DISPATCH: u32 = 1 << 16;
/// Bytes of light-tracing splats per pixel: per layer, three 64-bit fixed-point channels.
const SPLAT_BYTES_PER_PIXEL: u64 = LAYER_COUNT as u64 * 3 * 8;
/// Light and camera paths per invocation of vcm_light and render_vcm on CPU devices (lavapipe),
/// one after another: its SIMD groups of 8 lanes run a loop turn while any lane goes on, and a
/// run of paths per lane evens out their lengths (BENCHMARKS.md, "Paths in runs"). Real GPUs
/// take one each: they want the invocations.
const CPU_PATHS_PER_INVOCATION: u32 = 32;

/// The device buffers of a bidirectional render, kept from pass to pass while the frame's sizes
/// stay: allocating and clearing them each pass cost more than the pass's kernels on a real GPU.
pub(super) struct BidirectionalBuffers {
    /// (pixels, light paths, vertex slots) they were made for.
    sizes: (u64, u64, u64),
    accumulation: Buffer,
    splats: Buffer,
    counter: Buffer,
    vertices: Buffer,
    /// Each light path's count of vertices (in its first slots): what connections draw by.
    path_counts: Buffer,
    materials: Buffer,
    params: Buffer,
    grid: Buffer,
    /// render_vcm's count of invocations the driver broke off (lavapipe's loop limit).
    broken_off: Buffer,
    /// Either kernel's count of invocations that stopped after `steps_per_dispatch` vertices.
    suspended: Buffer,
}

/// How the bidirectional kernels split their paths: `per` paths to an invocation, and at most
/// `steps` vertices per invocation and dispatch (0: no bound). Lowered for good when the
/// driver's loop limit breaks runs off: first the paths, a quarter at a time down to 1; then
/// the vertices, from `FIRST_STEP_BOUND` a quarter at a time down to 1.
pub(super) struct Runs<'a> {
    pub per: &'a mut u32,
    pub steps: &'a mut u32,
}

/// The first bound on vertices per dispatch once single paths break off: a whole path of a
/// room's depth rarely needs more, and every four fewer cost another round of dispatches.
const FIRST_STEP_BOUND: u32 = 16;

/// Paths per invocation of vcm_light and render_vcm on this device: `CPU_PATHS_PER_INVOCATION`
/// on CPU devices, 1 on GPUs.
pub(super) fn default_paths_per_invocation(ctx: &GpuContext) -> u32 {
    if ctx.info().device_type == "CPU" {
        CPU_PATHS_PER_INVOCATION
    } else {
        1
    }
}

impl BidirectionalBuffers {
    fn new(ctx: &GpuContext, sizes: (u64, u64, u64)) -> Result<BidirectionalBuffers, GpuError> {
        let (pixels, paths, slots) = sizes;
        Ok(BidirectionalBuffers {
            sizes,
            // Cleared by each pass's first batch, as the splats and the counter by each sample's.
            accumulation: ctx.create_scratch("vcm_accumulation", pixels * ACCUMULATION_BYTES_PER_PIXEL)?,
            splats: ctx.create_scratch("vcm_splats", pixels * SPLAT_BYTES_PER_PIXEL)?,
            counter: ctx.create_scratch("vcm_point_count", 16)?,
            // vcm_light writes every path's count and its slots below it each sample, and
            // nothing reads a slot beyond a count, so these are never cleared.
            vertices: ctx.create_buffer("light_vertices", slots * size_of::<LightVertex>() as u64)?,
            // Whole blocks of VCM_PICK_BLOCK: the paths beyond the last stay at count 0.
            path_counts: ctx.create_buffer("light_path_counts", paths.next_multiple_of(VCM_PICK_BLOCK as u64) * 4)?,
            materials: ctx.create_buffer("light_materials", slots * size_of::<LightMaterial>() as u64)?,
            params: ctx.create_scratch("vcm_params", size_of::<VcmParams>() as u64)?,
            grid: ctx.create_scratch("vcm_grid", size_of::<GridParams>() as u64)?,
            broken_off: ctx.create_scratch("vcm_broken_off", 16)?,
            suspended: ctx.create_scratch("vcm_suspended", 16)?,
        })
    }
}

/// What a bidirectional render runs on: the device, the kernels, the scene there and here.
#[derive(Clone, Copy)]
pub(super) struct On<'a> {
    pub ctx: &'a GpuContext,
    pub kernels: &'a GpuKernels,
    pub scene: &'a DeviceScene,
    pub buffers: &'a SceneBuffers,
    /// The pixels the passes render (`None`: all) and the buffer the camera kernel reads them from.
    pub pixels: Option<&'a PixelList>,
    pub pixel_buffer: &'a Buffer,
}

/// Renders passes `first .. first + passes` (`spp` samples each) of a bidirectional integrator on
/// the device into one accumulation, read back once: the output is their mean. The buffers are
/// those in `kept` (made or remade there when the frame's sizes changed); `runs` says how the
/// kernels split their paths, lowered for good when the driver's loop limit breaks some off.
pub(super) fn render_pass_bidirectional(
    on: On,
    kept: &mut Option<BidirectionalBuffers>,
    runs: Runs,
    spp: u32,
    first: u32,
    passes: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<RenderOutput, GpuError> {
    let On { ctx, buffers, .. } = on;
    let f = buffers.frame;
    let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
    let pixels = f.width as u64 * f.height as u64;
    let accumulation_bytes = pixels * ACCUMULATION_BYTES_PER_PIXEL;
    let splat_bytes = pixels * SPLAT_BYTES_PER_PIXEL;
    if accumulation_bytes > limit || splat_bytes > limit {
        return Err(GpuError::Unsupported(format!(
            "the {} integrator keeps the whole image on the device ({} MiB), more than one storage buffer holds \
             ({} MiB); lower the resolution or render with --backend cpu",
            if f.integrator == crate::layout::constants::INTEGRATOR_BPT { "bpt" } else { "vcm" },
            accumulation_bytes.max(splat_bytes) >> 20,
            limit >> 20
        )));
    }
    let slots = light_path_count(&f) as u64 * f.max_depth.max(1) as u64;
    let sizes = (pixels, light_path_count(&f) as u64, slots);
    if kept.as_ref().is_none_or(|k| k.sizes != sizes) {
        *kept = None;
        *kept = Some(BidirectionalBuffers::new(ctx, sizes)?);
    }
    let b = kept.as_ref().expect("made just above");
    let Runs { per, steps } = runs;
    loop {
        let broken_off = match render_samples(on, b, *per, *steps, spp, first, passes, progress)? {
            Samples::Rendered(output) => return Ok(*output),
            Samples::BrokenOff(n) => n,
        };
        // The passes are deterministic: rendered again with shorter runs, they are what the
        // first try would have been without the limit. Fewer paths per invocation first (a
        // SIMD group's lanes stay busier with more), then fewer vertices per dispatch: a
        // path's rays through a large BVH can pass the limit alone, a vertex's rarely.
        if *per > 1 {
            *per = (*per / 4).max(1);
            continue;
        }
        if *steps != 1 {
            *steps = if *steps == 0 { FIRST_STEP_BOUND } else { (*steps / 4).max(1) };
            continue;
        }
        return Err(GpuError::Unsupported(format!(
            "the device broke off {broken_off} runs of light or camera paths at its loop limit (lavapipe stops an invocation after \
             65535 loop iterations) even at one path vertex per invocation: a ray crosses too many overlapping objects \
             or instances, and the image would miss their light; render with --backend cpu"
        )));
    }
}

/// What `render_samples` made: the passes, or how many invocations of a stage the driver broke
/// off (the stage's results are then incomplete, and the passes were given up).
enum Samples {
    Rendered(Box<RenderOutput>),
    BrokenOff(u32),
}

/// The samples of `render_pass_bidirectional` with its buffers `b`, `per` paths to an invocation
/// of either stage and at most `steps` vertices per invocation and dispatch (0: no bound).
#[allow(clippy::too_many_arguments)]
fn render_samples(
    on: On,
    b: &BidirectionalBuffers,
    per: u32,
    steps: u32,
    spp: u32,
    first: u32,
    passes: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Samples, GpuError> {
    let On { ctx, kernels, scene, buffers, pixels: list, pixel_buffer } = on;
    let f = buffers.frame;
    let pixels = f.width as u64 * f.height as u64;
    let light_kernel = kernels.vcm_light(ctx)?;
    let camera_kernel = kernels.render_vcm(ctx)?;
    let slots = light_path_count(&f) as u64 * f.max_depth.max(1) as u64;
    let mut band_rows = stop_band_rows(f.width, f.height);
    if steps > 0 {
        // The camera runs of a band wait in one storage buffer between dispatches.
        let row_bytes = (f.width as u64 * VCM_CAMERA_STATE_WORDS as u64 * 4).div_ceil(per as u64);
        band_rows = band_rows.min((ctx.info().max_storage_buffer_range / row_bytes).max(1) as u32);
    }
    let total = f.height as u64 * spp as u64 * passes as u64;
    let mut done = 0;
    let mut complete = true;
    let (mut light_time, mut camera_time) = (Duration::ZERO, Duration::ZERO);
    let view_distance = crate::cpu::vcm::view_distance(&buffers.view(), buffers.bounding_radius);
    let base_radius = crate::cpu::vcm::vcm_base_radius(&f, buffers.surface_area, view_distance);
    // Where each invocation's run waits between dispatches, when their vertices are bounded.
    let run_states = |name: &str, lanes: u64, words: u32| {
        let bytes = if steps == 0 { 16 } else { lanes * words as u64 * 4 };
        ctx.create_scratch(name, bytes)
    };
    let light_states = run_states("vcm_light_runs", PATHS_PER_DISPATCH.div_ceil(per) as u64, VCM_LIGHT_STATE_WORDS)?;
    let camera_states = run_states(
        "vcm_camera_runs",
        (band_rows as u64 * f.width as u64).div_ceil(per as u64),
        VCM_CAMERA_STATE_WORDS,
    )?;
    let samples = (first * spp..(first + passes) * spp).enumerate();
    'samples: for (sample, sample_index) in samples {
        let t = Instant::now();
        let mut params = vcm_params(&f, base_radius, sample_index);
        params.paths_per_invocation = per;
        params.steps_per_dispatch = steps;
        // The grid build takes the points' buffer; vcm_light writes the points below the count
        // it returns, and nothing reads past them.
        let points = ctx.create_scratch("vcm_points", slots.max(1) * size_of::<Photon>() as u64)?;
        let mut begin = 0;
        while begin < params.light_paths {
            if stop_requested() {
                complete = false;
                break 'samples;
            }
            params.path_begin = begin;
            params.path_count = PATHS_PER_DISPATCH.min(params.light_paths - begin);
            // Dispatched again, resuming the runs that stopped, until none stops.
            params.resume = 0;
            loop {
                ctx.run("vcm_light", |rec| {
                    // The clears go into the sample's first batch rather than submissions of their own.
                    if begin == 0 && params.resume == 0 {
                        if sample == 0 {
                            rec.fill_zero(&b.accumulation)?;
                            rec.fill_zero(&b.broken_off)?;
                        }
                        rec.fill_zero(&b.splats)?;
                        rec.fill_zero(&b.counter)?;
                    }
                    if steps > 0 {
                        rec.fill_zero(&b.suspended)?;
                    }
                    rec.dispatch(
                        light_kernel,
                        &scene.bindings(&[
                            &b.vertices,
                            &b.splats,
                            &points,
                            &b.counter,
                            &b.path_counts,
                            &b.materials,
                            &light_states,
                            &b.suspended,
                        ]),
                        bytemuck::bytes_of(&params),
                        groups(params.path_count.div_ceil(per)),
                    )
                })?;
                if steps == 0 || ctx.download::<u32>(&b.suspended)?[0] == 0 {
                    break;
                }
                params.resume = 1;
            }
            params.resume = 0;
            begin += params.path_count;
        }
        params.path_begin = 0;
        params.path_count = params.light_paths;
        let [count, light_broken_off] = ctx.download::<u32>(&b.counter)?[..2] else {
            unreachable!("the counter holds four words")
        };
        if light_broken_off > 0 {
            return Ok(Samples::BrokenOff(light_broken_off));
        }
        let grid = vertex_grid(&params, count);
        let Some(map) = build_map(ctx, kernels, points, grid, "vcm")? else {
            complete = false;
            break;
        };
        light_time += t.elapsed();
        let t = Instant::now();
        let mut first = true;
        for unit in work_units(f.height, 1, 1, band_rows, sample_index) {
            if stop_requested() {
                complete = false;
                break 'samples;
            }
            let unit = restrict(DispatchRange { part: 0, ..unit }, list);
            // Dispatched again, resuming the runs that stopped, until none stops.
            params.resume = 0;
            loop {
                ctx.run("render_vcm", |rec| {
                    if first || steps > 0 {
                        rec.update(&b.params, std::slice::from_ref(&params))?;
                    }
                    if first {
                        rec.update(&b.grid, std::slice::from_ref(&grid))?;
                    }
                    if steps > 0 {
                        rec.fill_zero(&b.suspended)?;
                    }
                    rec.dispatch(
                        camera_kernel,
                        &scene.bindings(&[
                            &b.accumulation,
                            &b.params,
                            &b.grid,
                            &b.vertices,
                            &map.photons,
                            &map.starts,
                            &b.splats,
                            &b.path_counts,
                            &b.materials,
                            &b.broken_off,
                            &camera_states,
                            &b.suspended,
                            pixel_buffer,
                        ]),
                        bytemuck::bytes_of(&unit),
                        groups(dispatch_pixels(f.width, &unit).div_ceil(params.paths_per_invocation).max(1)),
                    )
                })?;
                first = false;
                if steps == 0 || ctx.download::<u32>(&b.suspended)?[0] == 0 {
                    break;
                }
                params.resume = 1;
            }
            done += unit_paths(&unit);
            progress(done, total);
        }
        camera_time += t.elapsed();
    }
    let t = Instant::now();
    let mut layers = Layers::new(f.width, f.height);
    let sums: Vec<[f32; 4]> = ctx.download(&b.accumulation)?;
    let rays = resolve_band(&mut layers, 0, &sums[..(pixels * LAYER_COUNT as u64) as usize], spp * passes);
    let stages = vec![
        ("light paths".to_string(), light_time),
        ("render".to_string(), camera_time),
        ("download".to_string(), t.elapsed()),
    ];
    let stats = RenderStats::device(ctx, stages, rays, spp * passes);
    match ctx.download::<u32>(&b.broken_off)?[0] {
        0 => Ok(Samples::Rendered(Box::new(RenderOutput::new(layers, stats, complete, passes, None)))),
        broken_off => Ok(Samples::BrokenOff(broken_off)),
    }
}
