//! Rendering with the `render` kernel on a Vulkan device.

use std::time::Instant;

use super::{resolve_band, unit_paths, work_units, RenderOutput, RenderStats, SceneBuffers};
use crate::gpu::{GpuContext, GpuError};
use crate::io::Image;
use crate::layout::constants::WORKGROUP_SIZE;
use crate::layout::DispatchRange;

/// Bytes of accumulation per pixel: one vec4.
const ACCUMULATION_BYTES_PER_PIXEL: u64 = 16;

/// Renders on `ctx`; `progress(done, total)` is called after each dispatch.
pub fn render_gpu(
    ctx: &GpuContext,
    buffers: &SceneBuffers,
    spp: u32,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<RenderOutput, GpuError> {
    let f = buffers.frame;
    let mut stages = Vec::new();

    // Upload
    let t = Instant::now();
    let frame = ctx.upload("frame", std::slice::from_ref(&f))?;
    let nodes = ctx.upload("bvh_nodes", &buffers.nodes)?;
    let primitives = ctx.upload("primitives", &buffers.primitives)?;
    let materials = ctx.upload("materials", &buffers.materials)?;
    let lights = ctx.upload("lights", &buffers.lights)?;
    let spirv = crate::shaders::spirv("render").expect("build.rs embeds the render kernel");
    let kernel = ctx.create_kernel("render", &spirv, 6, size_of::<DispatchRange>() as u32)?;
    stages.push(("upload".to_string(), t.elapsed()));

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
    let accumulation = ctx.create_buffer("accumulation", max_rows as u64 * row_bytes)?;

    // Render, band by band
    let t = Instant::now();
    let mut image = Image::new(f.width, f.height);
    let units = work_units(f.width, f.height, spp, max_rows);
    let total: u64 = units.iter().map(unit_paths).sum();
    let mut done = 0;
    let mut rays = 0;
    let mut download_time = std::time::Duration::ZERO;
    for (i, unit) in units.iter().enumerate() {
        if unit.sample_begin == 0 {
            ctx.fill_zero(&accumulation)?;
        }
        let invocations = unit.row_count * f.width;
        let groups = invocations.div_ceil(WORKGROUP_SIZE);
        ctx.run("render", |rec| {
            rec.dispatch(
                &kernel,
                &[&frame, &nodes, &primitives, &materials, &lights, &accumulation],
                bytemuck::bytes_of(unit),
                [groups, 1, 1],
            )
        })?;
        done += unit_paths(unit);
        progress(done, total);
        let band_done = units.get(i + 1).is_none_or(|next| next.row_begin != unit.row_begin);
        if band_done {
            let td = Instant::now();
            let sums: Vec<[f32; 4]> = ctx.download(&accumulation)?;
            rays += resolve_band(&mut image, unit.row_begin, &sums[..invocations as usize], spp);
            download_time += td.elapsed();
        }
    }
    stages.push(("render".to_string(), t.elapsed() - download_time));
    stages.push(("download".to_string(), download_time));
    let stats = RenderStats {
        stages,
        kernel_times: ctx.take_timings(),
        rays,
        samples_per_pixel: spp,
        device: format!("{} ({})", ctx.info().name, ctx.info().driver),
    };
    Ok(RenderOutput { image, stats })
}
