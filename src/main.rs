//! The `photonix` command line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use photonix::gpu::{list_devices, GpuContext, GpuOptions};
use photonix::io::{check_output_path, contact_sheet, write_image, write_layers_exr};
use photonix::render::bench::{bench, bench_photons};
use photonix::render::{prepare, render_cpu, Backend, FrameSettings, PhotonSettings, RenderOutput};
use photonix::scene::load_scene;

#[derive(Parser)]
#[command(name = "photonix", version, about = "Physically based photon mapping on Vulkan compute shaders")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum BackendArg {
    Gpu,
    Cpu,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to an image (.exr linear radiance, .png sRGB)
    Render(RenderArgs),
    /// List the Vulkan devices and the limits that matter to Photonix
    Devices,
    /// Measure primary and shadow rays per second on the GPU and the CPU reference
    Bench(BenchArgs),
    /// Compare a render with a reference: relMSE, RMSE, per-channel mean ratio, error image
    Diff(DiffArgs),
}

#[derive(clap::Args)]
struct DiffArgs {
    /// The image to check (EXR, linear radiance)
    test: PathBuf,
    /// The reference (EXR, linear radiance); a larger reference is box-filtered down when the
    /// sizes divide evenly
    reference: PathBuf,
    /// Write a false-colour image of per-pixel relMSE (log scale, 1e-4 black to 1 white)
    #[arg(long, value_name = "PNG")]
    heatmap: Option<PathBuf>,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scene to measure
    #[arg(default_value = "scenes/cornell-box.toml")]
    scene: PathBuf,
    /// Samples per pixel of each timed frame
    #[arg(long, default_value_t = 16)]
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
    /// Also time photon tracing and the grid build at these photon path counts (comma-separated)
    #[arg(long, value_delimiter = ',')]
    photon_paths: Vec<u32>,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (TOML, see docs/scene-format.md)
    scene: PathBuf,
    /// Output image; the extension picks the format [default: <scene name>.png]
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Where the kernels run: the Vulkan device, or the CPU reference
    #[arg(long, value_enum, default_value = "gpu")]
    backend: BackendArg,
    /// Samples per pixel [default: the scene's]
    #[arg(long)]
    spp: Option<u32>,
    /// Seed of the random streams [default: the scene's]
    #[arg(long)]
    seed: Option<u32>,
    /// Image size as WIDTHxHEIGHT [default: the scene's]
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Most surfaces a camera path visits [default: the scene's]
    #[arg(long)]
    max_depth: Option<u32>,
    /// Vulkan device: index or name substring (see `photonix devices`)
    #[arg(long)]
    device: Option<String>,
    /// PNG only: scale radiance by 2^EXPOSURE before sRGB encoding
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    #[command(flatten)]
    photons: PhotonArgs,
    /// Write a multi-layer EXR (direct, specular, indirect, caustics, combined); needs -o *.exr
    #[arg(long)]
    layers: bool,
    /// Also write the four terms side by side as a PNG
    #[arg(long, value_name = "PNG")]
    contact_sheet: Option<PathBuf>,
}

#[derive(clap::Args)]
struct PhotonArgs {
    /// Photon paths for the global map [default: the scene's]
    #[arg(long)]
    photons: Option<u32>,
    /// Photon paths for the caustic map [default: the scene's]
    #[arg(long)]
    caustic_photons: Option<u32>,
    /// Lookup radius of the global map, in scene units [default: derived from the scene]
    #[arg(long, allow_negative_numbers = true)]
    radius: Option<f32>,
    /// Lookup radius of the caustic map, in scene units [default: half the global radius]
    #[arg(long, allow_negative_numbers = true)]
    caustic_radius: Option<f32>,
    /// Final-gather rays per sample; 0 reads the global map directly (fast preview)
    #[arg(long)]
    gather_rays: Option<u32>,
    /// Most surfaces a photon path visits
    #[arg(long)]
    photon_depth: Option<u32>,
    /// Direct light and specular paths only: no photon maps
    #[arg(long)]
    no_photons: bool,
}

impl PhotonArgs {
    /// The scene's settings with the command line's overrides, checked.
    fn apply(&self, scene: Option<PhotonSettings>) -> Result<Option<PhotonSettings>> {
        if self.no_photons {
            return Ok(None);
        }
        let mut p = scene.unwrap_or_default();
        let overridden = self.photons.is_some() || self.caustic_photons.is_some() || self.radius.is_some();
        if scene.is_none() && !overridden {
            return Ok(None);
        }
        if let Some(n) = self.photons {
            p.photons = n;
        }
        if let Some(n) = self.caustic_photons {
            p.caustic_photons = n;
        }
        if p.photons == 0 || p.caustic_photons == 0 {
            bail!("--photons and --caustic-photons must be at least 1; use --no-photons to render without photon maps");
        }
        for (name, value) in [("--radius", self.radius), ("--caustic-radius", self.caustic_radius)] {
            if let Some(r) = value {
                if !(r.is_finite() && r > 0.0) {
                    bail!("{name} is {r}; give a positive radius in scene units, or leave it out to derive one");
                }
            }
        }
        p.radius = self.radius.or(p.radius);
        p.caustic_radius = self.caustic_radius.or(p.caustic_radius);
        p.gather_rays = self.gather_rays.unwrap_or(p.gather_rays);
        if let Some(d) = self.photon_depth {
            if d == 0 {
                bail!("--photon-depth must be at least 1");
            }
            p.max_depth = d;
        }
        Ok(Some(p))
    }
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT (e.g. 640x480)"))?;
    let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| n > 0 && n <= 65536);
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{s}` is not WIDTHxHEIGHT with sizes from 1 to 65536 (e.g. 640x480)")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Devices => run_devices(),
        Command::Bench(args) => run_bench(args),
        Command::Diff(args) => run_diff(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run_devices() -> Result<()> {
    for device in list_devices()? {
        println!("{}", device.describe());
    }
    Ok(())
}

fn run_diff(args: DiffArgs) -> Result<()> {
    use photonix::io::metrics::{downsample, error_heatmap, mean_ratio, rel_mse, rmse};
    if let Some(h) = &args.heatmap {
        check_output_path(h)?;
    }
    let test = photonix::io::read_exr(&args.test)?;
    let mut reference = photonix::io::read_exr(&args.reference)?;
    if (test.width, test.height) != (reference.width, reference.height) {
        let factor = reference.width / test.width.max(1);
        if factor < 2 || test.width * factor != reference.width || test.height * factor != reference.height {
            bail!(
                "{} is {}x{} but {} is {}x{}; render at the reference's size or an integer fraction of it",
                args.test.display(),
                test.width,
                test.height,
                args.reference.display(),
                reference.width,
                reference.height
            );
        }
        reference = downsample(&reference, factor);
    }
    let ratio = mean_ratio(&test, &reference);
    println!("relMSE {:.6}", rel_mse(&test, &reference));
    println!("RMSE   {:.6}", rmse(&test, &reference));
    println!("mean ratio (test/reference) R {:.4} G {:.4} B {:.4}", ratio[0], ratio[1], ratio[2]);
    if let Some(h) = &args.heatmap {
        write_image(h, &error_heatmap(&test, &reference), 0.0)?;
    }
    Ok(())
}

fn run_bench(args: BenchArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let (width, height) = args.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    let settings = FrameSettings { width, height, max_depth: 1, seed: scene.render.seed };
    let buffers = prepare(&scene, &settings)?;
    println!("scene {} at {width}x{height}, {} spp per timed frame", args.scene.display(), args.spp);
    let ctx = GpuContext::new(&GpuOptions::from_env(args.device.clone()))?;
    let mut results = vec![bench(Some(&ctx), &buffers, args.spp)?];
    if !args.gpu_only {
        results.push(bench(None, &buffers, args.spp)?);
    }
    println!("| backend | device | primary rays/s | shadow rays/s |");
    println!("| --- | --- | --- | --- |");
    for r in &results {
        println!(
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
    if !args.photon_paths.is_empty() {
        println!();
        println!(
            "| backend | photon paths | stored photons | trace s | paths/s | grid build s | grid s per M photons |"
        );
        println!("| --- | --- | --- | --- | --- | --- | --- |");
    }
    for &paths in &args.photon_paths {
        let contexts: Vec<Option<&GpuContext>> = if args.gpu_only { vec![Some(&ctx)] } else { vec![Some(&ctx), None] };
        for c in contexts {
            match bench_photons(c, &buffers, paths) {
                Ok(b) => println!(
                    "| {} | {} | {} | {:.3} | {:.2} M | {:.3} | {:.3} |",
                    b.backend.name(),
                    b.paths,
                    b.stored,
                    b.trace_seconds,
                    b.paths as f64 / b.trace_seconds / 1e6,
                    b.grid_seconds,
                    b.grid_seconds / (b.stored as f64 / 1e6),
                ),
                Err(e) => println!("| {} | {paths} | - | - | - | - | {e} |", if c.is_some() { "gpu" } else { "cpu" }),
            }
        }
    }
    Ok(())
}

fn progress_bar(total_label: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(0);
    let style = ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})")
        .expect("the progress template is valid")
        .progress_chars("=> ");
    bar.set_style(style);
    bar.set_message(total_label.to_string());
    Some(bar)
}

fn run_render(args: RenderArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let output = args.output.clone().unwrap_or_else(|| PathBuf::from(format!("{}.png", scene.name)));
    // Fail on a bad output path now, not after a long render.
    check_output_path(&output)?;

    let (width, height) = args.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    let settings = FrameSettings {
        width,
        height,
        max_depth: args.max_depth.unwrap_or(scene.render.max_depth),
        seed: args.seed.unwrap_or(scene.render.seed),
    };
    let photons = args.photons.apply(scene.photons)?;
    if args.layers && !matches!(photonix::io::image::format_of(&output), Ok(photonix::io::image::Format::Exr)) {
        bail!("--layers writes a multi-layer EXR; give an output ending in .exr (e.g. -o layers.exr)");
    }
    if let Some(sheet) = &args.contact_sheet {
        check_output_path(sheet)?;
    }
    let spp = args.spp.unwrap_or(scene.render.spp);
    if spp == 0 {
        bail!("--spp must be at least 1");
    }
    if settings.max_depth == 0 {
        bail!("--max-depth must be at least 1");
    }

    let t = std::time::Instant::now();
    let buffers = prepare(&scene, &settings)?;
    let prepare_time = t.elapsed();

    let bar = progress_bar(&scene.name);
    let mut progress = |done: u64, total: u64| {
        if let Some(bar) = &bar {
            bar.set_length(total);
            bar.set_position(done);
        }
    };
    let backend = match args.backend {
        BackendArg::Gpu => Backend::Gpu,
        BackendArg::Cpu => Backend::Cpu,
    };
    let mut out: RenderOutput = match backend {
        Backend::Cpu => render_cpu(&buffers, spp, photons.as_ref(), &mut progress),
        Backend::Gpu => {
            let ctx = GpuContext::new(&GpuOptions::from_env(args.device.clone()))?;
            photonix::render::gpu::render_gpu(&ctx, &buffers, spp, photons.as_ref(), &mut progress)
                .with_context(|| "rendering failed; no image was written")?
        }
    };
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    out.stats.stages.insert(0, ("prepare".into(), prepare_time));

    let t = std::time::Instant::now();
    if args.layers {
        let mut named = vec![("combined", &out.image)];
        named.extend(out.layers.named());
        write_layers_exr(&output, &named)?;
    } else {
        write_image(&output, &out.image, args.exposure)?;
    }
    if let Some(sheet) = &args.contact_sheet {
        let terms: Vec<&photonix::io::Image> = out.layers.named().iter().map(|(_, image)| *image).collect();
        write_image(sheet, &contact_sheet(&terms), args.exposure)?;
    }
    out.stats.stages.push(("write".into(), t.elapsed()));
    eprintln!("{}", summary(&scene.name, &output, &out, width, height, backend));
    Ok(())
}

fn summary(name: &str, output: &Path, out: &RenderOutput, width: u32, height: u32, backend: Backend) -> String {
    let s = &out.stats;
    let stages: Vec<String> = s.stages.iter().map(|(n, d)| format!("{n} {:.3} s", d.as_secs_f64())).collect();
    let kernels: Vec<String> =
        s.kernel_times.iter().map(|(n, secs, count)| format!("{n} {secs:.3} s in {count} dispatches")).collect();
    let render_secs = s.stage("render").as_secs_f64().max(1e-9);
    let mut line = format!(
        "{name}: {width}x{height}, {} spp, {} backend on {} -> {}\n  {}; {:.2} M rays/s ({} rays)",
        s.samples_per_pixel,
        backend.name(),
        s.device,
        output.display(),
        stages.join(", "),
        s.rays as f64 / render_secs / 1e6,
        s.rays,
    );
    if !kernels.is_empty() {
        line += &format!("\n  gpu time: {}", kernels.join(", "));
    }
    line
}
