//! The `photonix` command line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use photonix::gpu::{list_devices, GpuContext, GpuOptions};
use photonix::io::{check_output_path, write_image};
use photonix::render::{prepare, render_cpu, Backend, FrameSettings, RenderOutput};
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
        Backend::Cpu => render_cpu(&buffers, spp, &mut progress),
        Backend::Gpu => {
            let ctx = GpuContext::new(&GpuOptions::from_env(args.device.clone()))?;
            photonix::render::gpu::render_gpu(&ctx, &buffers, spp, &mut progress)
                .with_context(|| "rendering failed; no image was written")?
        }
    };
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    out.stats.stages.insert(0, ("prepare".into(), prepare_time));

    let t = std::time::Instant::now();
    write_image(&output, &out.image, args.exposure)?;
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
