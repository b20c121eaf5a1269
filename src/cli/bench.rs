//! `photonix bench`: primary and shadow rays per second on the GPU and the CPU reference, and
//! optionally photon tracing and grid build times, as Markdown tables.

use std::path::PathBuf;

use anyhow::Result;

use photonix::gpu::{GpuContext, GpuOptions};
use photonix::render::bench::{bench, bench_photons, bench_setup};
use photonix::render::memory;
use photonix::render::{prepare, FrameSettings};
use photonix::scene::load_scene;

use super::parse::{parse_photons, parse_resolution, parse_spp};

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene to measure
    #[arg(default_value = "scenes/cornell-box.toml")]
    scene: PathBuf,
    /// Samples per pixel of each timed frame, 1 to 4096
    #[arg(long, default_value = "16", value_parser = parse_spp, allow_negative_numbers = true)]
    spp: u32,
    /// Image size as WIDTHxHEIGHT [default: the scene's]
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Vulkan device: index or name substring
    #[arg(long)]
    device: Option<String>,
    /// Skip the CPU reference
    #[arg(long)]
    gpu_only: bool,
    /// Also time photon tracing and the grid build at these photon path counts (comma-separated, each 1 to 1000000000)
    #[arg(long, value_delimiter = ',', value_parser = parse_photons)]
    photon_paths: Vec<u32>,
    /// Instead of ray rates: time this many progressive passes (the scene's settings) with a
    /// renderer made per pass and with one kept across passes
    #[arg(long)]
    passes: Option<u32>,
}

pub fn run(args: BenchArgs) -> Result<()> {
    if let Some(passes) = args.passes {
        return run_passes(&args, passes);
    }
    let scene = load_scene(&args.scene)?;
    let (width, height) = args.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    // The CPU reference renders the frame too: it must fit in memory.
    let estimate = memory::estimate(width, height, None, None);
    memory::check_fits(&estimate, width, height, None, memory::available_host_memory(), None)?;
    let settings = FrameSettings { width, height, max_depth: 1, seed: scene.render.seed };
    let buffers = prepare(&scene, &settings)?;
    out!("scene {} at {width}x{height}, {} spp per timed frame", args.scene.display(), args.spp);
    let ctx = GpuContext::new(&GpuOptions::from_env(args.device.clone())?)?;

    // Rays per second
    let mut results = vec![bench(Some(&ctx), &buffers, args.spp)?];
    if !args.gpu_only {
        results.push(bench(None, &buffers, args.spp)?);
    }
    out!("| backend | device | primary rays/s | shadow rays/s |");
    out!("| --- | --- | --- | --- |");
    for r in &results {
        out!(
            "| {} | {} | {:.2} M ({} rays in {:.3} s) | {:.2} M ({} rays in {:.3} s) |",
            r.backend.name(),
            r.device,
            r.primary_rays_per_second() / 1e6,
            r.primary_rays,
            r.primary_seconds,
            r.shadow_rays_per_second() / 1e6,
            r.shadow_rays,
            r.shadow_seconds,
        );
    }

    // Photon tracing and grid build
    if !args.photon_paths.is_empty() {
        out!("");
        out!("| backend | photon paths | stored photons | trace s | paths/s | grid build s | grid s per M photons |");
        out!("| --- | --- | --- | --- | --- | --- | --- |");
    }
    for &paths in &args.photon_paths {
        let contexts: Vec<Option<&GpuContext>> = if args.gpu_only { vec![Some(&ctx)] } else { vec![Some(&ctx), None] };
        for c in contexts {
            match bench_photons(c, &buffers, paths) {
                Ok(b) => out!(
                    "| {} | {} | {} | {:.3} | {:.2} M | {:.3} | {:.3} |",
                    b.backend.name(),
                    b.paths,
                    b.stored,
                    b.trace_seconds,
                    b.paths as f64 / b.trace_seconds / 1e6,
                    b.grid_seconds,
                    b.grid_seconds / (b.stored as f64 / 1e6),
                ),
                Err(e) => out!("| {} | {paths} | - | - | - | - | {e} |", if c.is_some() { "gpu" } else { "cpu" }),
            }
        }
    }
    Ok(())
}

/// `--passes N`: the per-pass cost of set-up (scene upload, kernel creation) that a renderer kept
/// across passes saves.
fn run_passes(args: &BenchArgs, passes: u32) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let (width, height) = args.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    let settings = FrameSettings { width, height, max_depth: scene.render.max_depth, seed: scene.render.seed };
    let buffers = prepare(&scene, &settings)?;
    let ctx = GpuContext::new(&GpuOptions::from_env(args.device.clone())?)?;
    let spp = scene.render.spp;
    out!(
        "scene {} at {width}x{height}, {spp} spp per pass, {passes} passes, on {}",
        args.scene.display(),
        ctx.info().name
    );
    let b = bench_setup(&ctx, &buffers, scene.photons.as_ref(), spp, passes)?;
    let kernels: f64 = b.kernel_seconds.iter().map(|(_, s)| s).sum();
    let each: Vec<String> = b.kernel_seconds.iter().map(|(n, s)| format!("{n} {s:.3}")).collect();
    out!("scene upload {:.3} s; kernel creation {kernels:.3} s ({})", b.upload_seconds, each.join(", "));
    let list = |v: &[f64]| v.iter().map(|s| format!("{s:.2}")).collect::<Vec<_>>().join(", ");
    let fresh: f64 = b.fresh_pass_seconds.iter().sum();
    let kept: f64 = b.kept_pass_seconds.iter().sum::<f64>() + b.kept_setup_seconds;
    out!("renderer per pass: {fresh:.2} s ({})", list(&b.fresh_pass_seconds));
    out!("renderer kept:     {kept:.2} s (set-up {:.2}, then {})", b.kept_setup_seconds, list(&b.kept_pass_seconds));
    out!("saved per pass: {:.3} s", (fresh - kept) / passes.max(1) as f64);
    Ok(())
}
