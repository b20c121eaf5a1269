//! The `photonix` command line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use photonix::gpu::{list_devices, GpuContext, GpuOptions};
use photonix::io::{check_output_path, contact_sheet, write_image, write_layers_exr};
use photonix::render::accumulation::{format_ranges, merge, write_accumulation};
use photonix::render::bench::{bench, bench_photons};
use photonix::render::progressive::{render_progressive, Accumulator, Budget, StopReason};
use photonix::render::{prepare, render_cpu, Backend, FrameSettings, PhotonSettings, RenderOutput, RenderStats};
use photonix::scene::load_scene;

/// `println!` that ignores a closed stdout (`photonix diff ... | head -1`) instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

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
    /// Combine accumulation files of disjoint pass ranges into one image
    Merge(MergeArgs),
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
    #[command(flatten)]
    progressive: ProgressiveArgs,
    /// Write a multi-layer EXR (direct, specular, indirect, caustics, combined); needs -o *.exr
    #[arg(long)]
    layers: bool,
    /// Also write the four terms side by side as a PNG
    #[arg(long, value_name = "PNG")]
    contact_sheet: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ProgressiveArgs {
    /// Progressive passes (each traces its own photons with a smaller radius) [default: the scene's]
    #[arg(long)]
    passes: Option<u32>,
    /// Stop after the pass that crosses this wall time (e.g. 90s, 2m, 1h)
    #[arg(long, value_parser = parse_duration, allow_hyphen_values = true)]
    time: Option<std::time::Duration>,
    /// Stop when the estimated relMSE (from odd and even passes) falls below this
    #[arg(long, allow_hyphen_values = true)]
    target_error: Option<f64>,
    /// Rewrite the output with the passes so far this often (e.g. 30s)
    #[arg(long, value_parser = parse_duration, allow_hyphen_values = true)]
    checkpoint_every: Option<std::time::Duration>,
    /// Render exactly passes A..B and write an accumulation file (see docs/progressive.md)
    #[arg(long, value_parser = parse_pass_range)]
    pass_range: Option<(u32, u32)>,
}

impl ProgressiveArgs {
    fn budget(&self, scene_passes: u32) -> Result<Budget> {
        if let Some(e) = self.target_error {
            if !(e.is_finite() && e > 0.0) {
                bail!("--target-error is {e}; give a positive relMSE such as 0.01");
            }
        }
        if self.pass_range.is_some() && self.passes.is_some() {
            bail!("--passes and --pass-range both choose passes; give one of them");
        }
        let (first, end) = match (self.pass_range, self.passes) {
            (Some((a, b)), _) => (a, b),
            (None, Some(0)) => bail!("--passes must be at least 1"),
            (None, Some(n)) => (0, n),
            // A time or error budget alone runs until it is met.
            (None, None) if self.time.is_some() || self.target_error.is_some() => (0, u32::MAX),
            (None, None) => (0, scene_passes),
        };
        Ok(Budget { first, end, time: self.time, target_error: self.target_error })
    }
}

/// `90s`, `2m`, `1.5h`, `250ms` or a number of seconds; must be positive.
fn parse_duration(s: &str) -> Result<std::time::Duration, String> {
    let t = s.trim();
    let (number, unit) = match t.find(|c: char| c.is_ascii_alphabetic()) {
        Some(i) => t.split_at(i),
        None => (t, "s"),
    };
    let scale = match unit {
        "ms" => 1e-3,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => return Err(format!("`{s}` has an unknown unit `{unit}`; use ms, s, m or h (e.g. 90s)")),
    };
    let value: f64 = number.trim().parse().map_err(|_| format!("`{s}` is not a duration such as 90s or 2m"))?;
    let seconds = value * scale;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("`{s}` is not a positive duration; give e.g. 90s"));
    }
    Ok(std::time::Duration::from_secs_f64(seconds))
}

/// `A..B` with A < B: passes A, A+1, ..., B-1.
fn parse_pass_range(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not a pass range A..B of whole numbers with A < B (e.g. 0..32)");
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    if a >= b {
        return Err(bad());
    }
    Ok((a, b))
}

#[derive(clap::Args)]
struct MergeArgs {
    /// Accumulation files written by `render --pass-range`
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// The merged image (.exr or .png), or with --accumulation a merged accumulation file
    #[arg(short, long)]
    output: PathBuf,
    /// Write an accumulation file (sums and pass count) instead of the final image
    #[arg(long)]
    accumulation: bool,
    /// PNG only: scale radiance by 2^EXPOSURE before sRGB encoding
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
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
        Command::Merge(args) => run_merge(args),
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
        out!("{}", device.describe());
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
    out!("relMSE {:.6}", rel_mse(&test, &reference));
    out!("RMSE   {:.6}", rmse(&test, &reference));
    out!("mean ratio (test/reference) R {:.4} G {:.4} B {:.4}", ratio[0], ratio[1], ratio[2]);
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
    out!("scene {} at {width}x{height}, {} spp per timed frame", args.scene.display(), args.spp);
    let ctx = GpuContext::new(&GpuOptions::from_env(args.device.clone()))?;
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
    let is_exr = matches!(photonix::io::image::format_of(&output), Ok(photonix::io::image::Format::Exr));
    if args.layers && !is_exr {
        bail!("--layers writes a multi-layer EXR; give an output ending in .exr (e.g. -o layers.exr)");
    }
    if args.progressive.pass_range.is_some() && !is_exr {
        bail!("--pass-range writes an accumulation file, which is an EXR; give an output ending in .exr");
    }
    // Fail on a bad output path now, not after a long render.
    check_output_path(&output)?;
    if let Some(sheet) = &args.contact_sheet {
        check_output_path(sheet)?;
    }

    let (width, height) = args.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    let settings = FrameSettings {
        width,
        height,
        max_depth: args.max_depth.unwrap_or(scene.render.max_depth),
        seed: args.seed.unwrap_or(scene.render.seed),
    };
    let photons = args.photons.apply(scene.photons)?;
    let spp = args.spp.unwrap_or(scene.render.spp);
    if spp == 0 {
        bail!("--spp must be at least 1");
    }
    if settings.max_depth == 0 {
        bail!("--max-depth must be at least 1");
    }
    let budget = args.progressive.budget(scene.render.passes)?;

    let t = std::time::Instant::now();
    let buffers = prepare(&scene, &settings)?;
    let prepare_time = t.elapsed();
    let backend = match args.backend {
        BackendArg::Gpu => Backend::Gpu,
        BackendArg::Cpu => Backend::Cpu,
    };
    let ctx = match backend {
        Backend::Gpu => Some(GpuContext::new(&GpuOptions::from_env(args.device.clone()))?),
        Backend::Cpu => None,
    };
    // Ctrl-C and SIGTERM finish the dispatch under way; the finished passes are written.
    let _ = ctrlc::set_handler(|| photonix::render::STOP.store(true, std::sync::atomic::Ordering::Relaxed));

    let write_result = |acc: &Accumulator| -> Result<()> {
        if budget_is_range(&args) {
            write_accumulation(&output, acc)?;
            return Ok(());
        }
        let mean = acc.mean();
        let combined = mean.combined();
        if args.layers {
            let mut named = vec![("combined", &combined)];
            named.extend(mean.named());
            write_layers_exr(&output, &named)?;
        } else {
            write_image(&output, &combined, args.exposure)?;
        }
        Ok(())
    };

    let bar = progress_bar(&scene.name);
    let total_passes = budget.end - budget.first;
    let mut stats = RenderStats::default();
    let mut last_checkpoint = std::time::Instant::now();
    let passes_done = std::cell::Cell::new(0u32);
    let paths_per_pass = photons.map_or(0, |p| p.photons as u64 + p.caustic_photons as u64);
    let result = render_progressive(
        width,
        height,
        &budget,
        |pass| -> Result<RenderOutput> {
            let mut progress = |done: u64, total: u64| {
                if let Some(bar) = &bar {
                    let (length, position) = match budget.time {
                        Some(t) => (t.as_millis() as u64, stats_elapsed(&stats).as_millis() as u64),
                        None => {
                            (total_passes as u64 * 1000, passes_done.get() as u64 * 1000 + done * 1000 / total.max(1))
                        }
                    };
                    bar.set_length(length);
                    bar.set_position(position.min(length));
                }
            };
            let out = match &ctx {
                None => render_cpu(&buffers, spp, photons.as_ref(), pass, &mut progress),
                Some(ctx) => {
                    photonix::render::gpu::render_gpu(ctx, &buffers, spp, photons.as_ref(), pass, &mut progress)
                        .with_context(|| failure_message(&args, passes_done.get(), &output))?
                }
            };
            add_stats(&mut stats, &out.stats);
            Ok(out)
        },
        |acc, elapsed| -> Result<()> {
            passes_done.set(acc.passes);
            if let Some(bar) = &bar {
                let photon_rate = paths_per_pass as f64 * acc.passes as f64 / elapsed.as_secs_f64().max(1e-9);
                bar.set_message(format!(
                    "{} pass {}/{} {:.2} M photons/s",
                    scene.name,
                    acc.passes,
                    total_passes,
                    photon_rate / 1e6
                ));
            }
            if args.progressive.checkpoint_every.is_some_and(|every| last_checkpoint.elapsed() >= every) {
                write_result(acc)?;
                last_checkpoint = std::time::Instant::now();
            }
            Ok(())
        },
    );
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let (acc, reason) = result?;
    if acc.passes == 0 {
        bail!("interrupted before the first pass finished; no image was written");
    }
    let t = std::time::Instant::now();
    write_result(&acc)?;
    if let Some(sheet) = &args.contact_sheet {
        let mean = acc.mean();
        let terms: Vec<&photonix::io::Image> = mean.named().iter().map(|(_, image)| *image).collect();
        write_image(sheet, &contact_sheet(&terms), args.exposure)?;
    }
    stats.stages.insert(0, ("prepare".into(), prepare_time));
    stats.stages.push(("write".into(), t.elapsed()));
    stats.samples_per_pixel = spp * acc.passes;
    let why = match reason {
        StopReason::Passes => "all passes done".to_string(),
        StopReason::Time => "time budget reached".to_string(),
        StopReason::TargetError => {
            format!("error estimate {:.2e} below the target", acc.error_estimate().unwrap_or(0.0))
        }
        StopReason::Interrupted => "interrupted".to_string(),
    };
    eprintln!(
        "{} pass{} ({}; passes {}); {}",
        acc.passes,
        if acc.passes == 1 { "" } else { "es" },
        why,
        format_ranges(&acc.ranges),
        summary(&scene.name, &output, &stats, width, height, backend)
    );
    Ok(())
}

fn budget_is_range(args: &RenderArgs) -> bool {
    args.progressive.pass_range.is_some()
}

fn failure_message(args: &RenderArgs, passes_done: u32, output: &Path) -> String {
    if args.progressive.checkpoint_every.is_some() && output.exists() {
        format!("rendering failed after {passes_done} passes; the last checkpoint stays in {}", output.display())
    } else {
        "rendering failed; no image was written".to_string()
    }
}

fn stats_elapsed(stats: &RenderStats) -> std::time::Duration {
    stats.stages.iter().map(|(_, d)| *d).sum()
}

/// Adds one pass's stage times, kernel times and rays to the running totals.
fn add_stats(total: &mut RenderStats, pass: &RenderStats) {
    for (name, d) in &pass.stages {
        match total.stages.iter_mut().find(|(n, _)| n == name) {
            Some((_, t)) => *t += *d,
            None => total.stages.push((name.clone(), *d)),
        }
    }
    for (name, secs, count) in &pass.kernel_times {
        match total.kernel_times.iter_mut().find(|(n, _, _)| n == name) {
            Some((_, s, c)) => {
                *s += secs;
                *c += count;
            }
            None => total.kernel_times.push((name.clone(), *secs, *count)),
        }
    }
    total.rays += pass.rays;
    total.device.clone_from(&pass.device);
}

fn run_merge(args: MergeArgs) -> Result<()> {
    check_output_path(&args.output)?;
    let acc = merge(&args.inputs)?;
    if args.accumulation {
        write_accumulation(&args.output, &acc)?;
    } else {
        write_image(&args.output, &acc.mean().combined(), args.exposure)?;
    }
    eprintln!("merged {} passes ({}) -> {}", acc.passes, format_ranges(&acc.ranges), args.output.display());
    Ok(())
}

fn summary(name: &str, output: &Path, s: &RenderStats, width: u32, height: u32, backend: Backend) -> String {
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
