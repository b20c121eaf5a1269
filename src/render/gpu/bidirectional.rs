//! The bidirectional integrators (`bpt`, `vcm`) on the device: per sample, the light stage
//! (vcm_light: light sub-paths, their vertex slots, their points and the light-tracing splats),
//! the grid over the points, then the camera stage (render_vcm) band by band. The same
//! algorithm and random numbers as `cpu::vcm`.

use std::time::{Duration, Instant};

use super::kernels::{groups, GpuKernels};
use super::maps::build_map;
use super::scene::DeviceScene;
use crate::cpu::vcm::{light_path_count, vcm_params, vertex_grid};
use crate::gpu::{GpuContext, GpuError};
use crate::layout::constants::LAYER_COUNT;
use crate::layout::{DispatchRange, LightMaterial, LightVertex, Photon};
use crate::render::{resolve_band, stop_band_rows, unit_paths, work_units, Layers, RenderOutput, RenderStats};
use crate::render::{stop_requested, SceneBuffers};

/// Light paths per vcm_light dispatch.
const PATHS_PER_DISPATCH: u32 = 1 << 16;

/// Renders pass `pass` (`spp` samples) of a bidirectional integrator on the device.
pub(super) fn render_pass_bidirectional(
    ctx: &GpuContext,
    kernels: &GpuKernels,
    scene: &DeviceScene,
    buffers: &SceneBuffers,
    spp: u32,
    pass: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<RenderOutput, GpuError> {
    let f = buffers.frame;
    let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
    let pixels = f.width as u64 * f.height as u64;
    let accumulation_bytes = pixels * 16 * LAYER_COUNT as u64;
    let splat_bytes = pixels * LAYER_COUNT as u64 * 3 * 8;
    if accumulation_bytes > limit || splat_bytes > limit {
        return Err(GpuError::Unsupported(format!(
            "the {} integrator keeps the whole image on the device ({} MiB), more than one storage buffer holds \
             ({} MiB); lower the resolution or render with --backend cpu",
            if f.integrator == crate::layout::constants::INTEGRATOR_BPT { "bpt" } else { "vcm" },
            accumulation_bytes.max(splat_bytes) >> 20,
            limit >> 20
        )));
    }
    let light_kernel = kernels.vcm_light(ctx)?;
    let camera_kernel = kernels.render_vcm(ctx)?;
    let accumulation = ctx.create_buffer("vcm_accumulation", accumulation_bytes)?;
    ctx.fill_zero(&accumulation)?;
    let splats = ctx.create_buffer("vcm_splats", splat_bytes)?;
    let counter = ctx.create_buffer("vcm_point_count", 16)?;
    let slots = light_path_count(&f) as u64 * f.max_depth.max(1) as u64;
    let vertices = ctx.create_buffer("light_vertices", slots * size_of::<LightVertex>() as u64)?;
    // Each path's end (vcm_light writes every path's end and its slots up to it each sample, so
    // neither buffer is cleared between samples).
    let path_ends = ctx.create_buffer("light_path_ends", light_path_count(&f) as u64 * 4)?;
    let materials = ctx.create_buffer("light_materials", slots * size_of::<LightMaterial>() as u64)?;
    let band_rows = stop_band_rows(f.width, f.height);
    let total = f.height as u64 * spp as u64;
    let mut done = 0;
    let mut complete = true;
    let (mut light_time, mut camera_time) = (Duration::ZERO, Duration::ZERO);
    let view_distance = crate::cpu::vcm::view_distance(&buffers.view(), buffers.bounding_radius);
    let base_radius = crate::cpu::vcm::vcm_base_radius(&f, buffers.surface_area, view_distance);
    'samples: for sample in 0..spp {
        let sample_index = pass * spp + sample;
        let t = Instant::now();
        let mut params = vcm_params(&f, base_radius, sample_index);
        // The grid build takes the points' buffer; the vertex slots stay for the pass.
        let points = ctx.create_buffer("vcm_points", slots.max(1) * size_of::<Photon>() as u64)?;
        ctx.fill_zero(&splats)?;
        ctx.fill_zero(&counter)?;
        let mut begin = 0;
        while begin < params.light_paths {
            if stop_requested() {
                complete = false;
                break 'samples;
            }
            params.path_begin = begin;
            params.path_count = PATHS_PER_DISPATCH.min(params.light_paths - begin);
            ctx.run("vcm_light", |rec| {
                rec.dispatch(
                    light_kernel,
                    &scene.bindings(&[&vertices, &splats, &points, &counter, &path_ends, &materials]),
                    bytemuck::bytes_of(&params),
                    groups(params.path_count),
                )
            })?;
            begin += params.path_count;
        }
        params.path_begin = 0;
        params.path_count = params.light_paths;
        let count = ctx.download::<u32>(&counter)?[0];
        let grid = vertex_grid(&params, count);
        let Some(map) = build_map(ctx, kernels, points, grid, "vcm")? else {
            complete = false;
            break;
        };
        let params_buffer = ctx.upload("vcm_params", std::slice::from_ref(&params))?;
        let grid_buffer = ctx.upload("vcm_grid", std::slice::from_ref(&grid))?;
        light_time += t.elapsed();
        let t = Instant::now();
        for unit in work_units(f.height, 1, 1, band_rows, sample_index) {
            if stop_requested() {
                complete = false;
                break 'samples;
            }
            let unit = DispatchRange { part: 0, ..unit };
            ctx.run("render_vcm", |rec| {
                rec.dispatch(
                    camera_kernel,
                    &scene.bindings(&[
                        &accumulation,
                        &params_buffer,
                        &grid_buffer,
                        &vertices,
                        &map.photons,
                        &map.starts,
                        &splats,
                        &path_ends,
                        &materials,
                    ]),
                    bytemuck::bytes_of(&unit),
                    groups(unit.row_count * f.width),
                )
            })?;
            done += unit_paths(&unit);
            progress(done, total);
        }
        camera_time += t.elapsed();
    }
    let t = Instant::now();
    let mut layers = Layers::new(f.width, f.height);
    let sums: Vec<[f32; 4]> = ctx.download(&accumulation)?;
    let rays = resolve_band(&mut layers, 0, &sums[..(pixels * LAYER_COUNT as u64) as usize], spp);
    let stages = vec![
        ("light paths".to_string(), light_time),
        ("render".to_string(), camera_time),
        ("download".to_string(), t.elapsed()),
    ];
    let stats = RenderStats::device(ctx, stages, rays, spp);
    Ok(RenderOutput { image: layers.combined(), layers, stats, complete })
}
