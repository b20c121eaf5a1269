//! `photonix render`: its flags and their checks against the scene's settings, the progressive
//! loop with its progress bar and checkpoints, the output files and the closing summary.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

use super::BackendArg;
use photonix::gpu::{list_devices, GpuContext, GpuOptions};
use photonix::io::{
    check_not_input, check_not_overwriting, check_output_path, contact_sheet, write_image, write_layers_exr,
};
use photonix::limits::{printable_message, MAX_PASSES};
use photonix::render::accumulation::{
    check_same_render, format_ranges, read_accumulation, write_accumulation, Provenance,
};
use photonix::render::memory::{self, available_host_memory, check_fits};
use photonix::render::photons::check_radii;
use photonix::render::progressive::{render_progressive_from, Accumulator, Budget, StopReason};
use photonix::render::{
    auto_backend, prepare, Backend, FrameSettings, PhotonSettings, RenderOutput, RenderStats, Renderer,
};
use photonix::scene::{load_scene, Integrator};

use super::parse::{
    parse_depth, parse_duration, parse_exposure, parse_gather_rays, parse_integrator, parse_pass_range, parse_passes,
    parse_photons, parse_radius, parse_resolution, parse_seed, parse_spp, parse_target_error, IntegratorArg,
};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (TOML, see docs/scene-format.md)
    scene: PathBuf,
    /// Output image; the extension picks the format [default: <scene name>.png]
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Check the scene, every flag, the output path and the memory estimate as a render would,
    /// then stop: nothing is rendered or written, no device is opened (ci/slurm-farm runs this
    /// before it submits anything)
    #[arg(long)]
    check: bool,
    /// Where the kernels run: a real GPU when there is one, else the CPU reference (auto); the
    /// Vulkan device even when it is a CPU such as lavapipe (gpu); the CPU reference (cpu)
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
    /// Samples per pixel in each pass, 1 to 4096 [default: the scene's]
    #[arg(long, value_parser = parse_spp, allow_negative_numbers = true)]
    spp: Option<u32>,
    /// The estimator: ppm (progressive photon mapping), pt (path tracing with multiple
    /// importance sampling), bpt (bidirectional path tracing) or vcm (vertex connection and
    /// merging); auto picks by the scene's contents: bpt where there are media or rough glossy
    /// surfaces, else ppm [default: the scene's, else auto]
    #[arg(long, value_parser = parse_integrator)]
    integrator: Option<IntegratorArg>,
    /// Seed of the random streams, 0 to 4294967295 [default: the scene's]
    #[arg(long, value_parser = parse_seed, allow_negative_numbers = true)]
    seed: Option<u32>,
    /// Image size as WIDTHxHEIGHT [default: the scene's]
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// POV-Ray scenes: the frame number the scene reads (frame_number) [default: the .ini's
    /// Initial_Frame beside the scene, else 0]
    #[arg(long)]
    frame: Option<i64>,
    /// POV-Ray scenes: the clock (+K) [default: the frame's, from the .ini, else 0]
    #[arg(long)]
    clock: Option<f64>,
    /// Most surfaces a camera path visits, 1 to 1024 [default: the scene's]
    #[arg(long, value_parser = parse_depth, allow_negative_numbers = true)]
    max_depth: Option<u32>,
    /// Vulkan device: index or name substring (see `photonix devices`); GPU backend only
    #[arg(long)]
    device: Option<String>,
    /// PNG only (output or contact sheet): scale radiance by 2^EXPOSURE, -64 to 64, before sRGB encoding
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: Option<f32>,
    #[command(flatten)]
    photons: PhotonArgs,
    #[command(flatten)]
    progressive: ProgressiveArgs,
    /// Write a multi-layer EXR (combined, direct, specular, indirect, caustics, and the feature
    /// layers albedo, normal, depth, position; noisy where denoised); needs -o *.exr. With
    /// --pass-range: the accumulation file carries the feature layers too
    #[arg(long)]
    layers: bool,
    /// Denoise the image with Intel Open Image Denoise, guided by albedo and normal layers (the
    /// library is loaded at run time; see docs/denoising.md) [default: the scene's [render] denoise].
    /// With --pass-range the part is not denoised but carries the feature layers for `merge --denoise`
    #[arg(long)]
    denoise: bool,
    /// Also write the four terms side by side as a PNG
    #[arg(long, value_name = "PNG")]
    contact_sheet: Option<PathBuf>,
}

#[derive(clap::Args)]
struct PhotonArgs {
    /// Photon paths for the global map, 1 to 1000000000 [default: the scene's]
    #[arg(long, value_parser = parse_photons, allow_negative_numbers = true)]
    photons: Option<u32>,
    /// Photon paths for the caustic map, 1 to 1000000000 [default: the scene's]
    #[arg(long, value_parser = parse_photons, allow_negative_numbers = true)]
    caustic_photons: Option<u32>,
    /// Lookup radius of the global map, in scene units [default: derived from the scene]
    #[arg(long, value_parser = parse_radius, allow_hyphen_values = true)]
    radius: Option<f32>,
    /// Lookup radius of the caustic map, in scene units [default: half the global radius]
    #[arg(long, value_parser = parse_radius, allow_hyphen_values = true)]
    caustic_radius: Option<f32>,
    /// Final-gather rays per sample, 0 to 1024; 0 reads the global map directly (fast preview)
    #[arg(long, value_parser = parse_gather_rays, allow_negative_numbers = true)]
    gather_rays: Option<u32>,
    /// Most surfaces a photon path visits, 1 to 1024
    #[arg(long, value_parser = parse_depth, allow_negative_numbers = true)]
    photon_depth: Option<u32>,
    /// Direct light and specular paths only: no photon maps
    #[arg(long)]
    no_photons: bool,
}

impl PhotonArgs {
    /// The photon-map flags given, `--no-photons` aside.
    fn given(&self) -> Vec<&'static str> {
        [
            ("--photons", self.photons.is_some()),
            ("--caustic-photons", self.caustic_photons.is_some()),
            ("--radius", self.radius.is_some()),
            ("--caustic-radius", self.caustic_radius.is_some()),
            ("--gather-rays", self.gather_rays.is_some()),
            ("--photon-depth", self.photon_depth.is_some()),
        ]
        .into_iter()
        .filter_map(|(name, on)| on.then_some(name))
        .collect()
    }

    /// The scene's settings with the command line's overrides. Any photon flag turns photon
    /// mapping on where the scene has it off; with --no-photons it is an error, not ignored.
    /// (Each value was range-checked by its parser.) An integrator without photon maps takes
    /// none, and a photon flag is then an error.
    fn apply(&self, scene: Option<PhotonSettings>, integrator: Integrator) -> Result<Option<PhotonSettings>> {
        let given = self.given();
        if !integrator.uses_photons() {
            if let Some(flag) = given.first().copied().or(self.no_photons.then_some("--no-photons")) {
                bail!(
                    "the {} integrator uses no photon maps, so {flag} would be ignored; leave it out, or use --integrator ppm",
                    integrator.name()
                );
            }
            return Ok(None);
        }
        if self.no_photons {
            if !given.is_empty() {
                bail!(
                    "--no-photons renders without photon maps, so {} would be ignored; give one or the other",
                    given.join(", ")
                );
            }
            return Ok(None);
        }
        if scene.is_none() && given.is_empty() {
            return Ok(None);
        }
        let mut p = scene.unwrap_or_default();
        p.photons = self.photons.unwrap_or(p.photons);
        p.caustic_photons = self.caustic_photons.unwrap_or(p.caustic_photons);
        p.radius = self.radius.or(p.radius);
        p.caustic_radius = self.caustic_radius.or(p.caustic_radius);
        p.gather_rays = self.gather_rays.unwrap_or(p.gather_rays);
        p.max_depth = self.photon_depth.unwrap_or(p.max_depth);
        Ok(Some(p))
    }
}

#[derive(clap::Args)]
struct ProgressiveArgs {
    /// Progressive passes, 1 to 1000000 (each traces its own photons with a smaller radius) [default: the scene's]
    #[arg(long, value_parser = parse_passes, allow_negative_numbers = true)]
    passes: Option<u32>,
    /// Stop after the pass that crosses this wall time (e.g. 90s, 2m, 1h; 1ms to 365 days)
    #[arg(long, value_parser = parse_duration, allow_hyphen_values = true)]
    time: Option<std::time::Duration>,
    /// Stop when the estimated relMSE (from odd and even passes) falls below this (0 to 1000)
    #[arg(long, value_parser = parse_target_error, allow_hyphen_values = true)]
    target_error: Option<f64>,
    /// Adaptive sampling: after 8 uniform passes, later passes render the half of the pixels
    /// where one more pass lowers the error most, every 8th pass all of them (docs/progressive.md)
    /// [default: the scene's [render] adaptive]
    #[arg(long)]
    adaptive: bool,
    /// Rewrite the output with the passes so far this often (e.g. 30s; 1ms to 365 days)
    #[arg(long, value_parser = parse_duration, allow_hyphen_values = true)]
    checkpoint_every: Option<std::time::Duration>,
    /// Render exactly passes A..B (B at most 1000000) and write an accumulation file (see docs/progressive.md)
    #[arg(long, value_parser = parse_pass_range)]
    pass_range: Option<(u32, u32)>,
    /// With --pass-range A..B: when the output already holds passes A..K of this same render (an
    /// interrupted run's, or a checkpoint), render only K..B and add them to it
    #[arg(long)]
    resume: bool,
}

impl ProgressiveArgs {
    fn budget(&self, scene_passes: u32) -> Result<Budget> {
        if self.pass_range.is_some() && self.passes.is_some() {
            bail!("--passes and --pass-range both choose passes; give one of them");
        }
        let (first, end) = match (self.pass_range, self.passes) {
            (Some((a, b)), _) => (a, b),
            (None, Some(n)) => (0, n),
            // A time or error budget alone runs until it is met, or to the most passes there are.
            (None, None) if self.time.is_some() || self.target_error.is_some() => (0, MAX_PASSES),
            (None, None) => (0, scene_passes),
        };
        Ok(Budget { first, end, time: self.time, target_error: self.target_error, adaptive: self.adaptive })
    }
}

/// A render stopped by Ctrl-C or SIGTERM before its budget was spent: what it finished was
/// written, but it is not the image asked for, so the process fails (`EXIT_INTERRUPTED`) and a
/// scheduler retries it (ci/slurm-farm's tasks requeue and `--resume`).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Interrupted(pub String);

/// The exit status of an interrupted render: EX_TEMPFAIL of sysexits.h, "a temporary failure;
/// the user is invited to retry".
pub const EXIT_INTERRUPTED: u8 = 75;

/// The passes an interrupted run of the same render already wrote to `output`, for `--resume`:
/// `None` when there is no output yet. Refused: a file that is not an accumulation file of this
/// render (scene, settings, size), or whose passes are not A..K for the range A..B asked.
fn resume_from(
    output: &Path,
    range: (u32, u32),
    provenance: &Provenance,
    width: u32,
    height: u32,
) -> Result<Option<Accumulator>> {
    if !output.exists() {
        return Ok(None);
    }
    let (acc, theirs) = read_accumulation(output).context("--resume reads the output of the interrupted run")?;
    let theirs = theirs.ok_or_else(|| {
        anyhow::anyhow!(
            "{}: --resume needs the record of the render it continues; remove the file to render it anew",
            output.display()
        )
    })?;
    let ours = Accumulator::new(width, height);
    let this_render = Path::new("this render");
    check_same_render((this_render, &ours, provenance), (output, &acc, &theirs))
        .context("--resume continues only an output of the same render; remove the file to render it anew")?;
    match acc.ranges.as_slice() {
        [(a, k)] if *a == range.0 && *k <= range.1 => Ok(Some(acc)),
        _ => bail!(
            "{} holds passes {}, not passes {}..K of the --pass-range {}..{} asked; remove it, or give the range it belongs to",
            output.display(),
            format_ranges(&acc.ranges),
            range.0,
            range.0,
            range.1
        ),
    }
}

pub fn run(args: RenderArgs) -> Result<()> {
    // Check the flags and the output paths, before any long work. A flag that would be ignored is
    // an error: the user meant something by it.
    if args.device.is_some() && matches!(args.backend, BackendArg::Cpu) {
        bail!("--device picks a Vulkan device, but --backend cpu uses none; leave one of them out");
    }
    let pov = photonix::scene::pov::is_pov_path(&args.scene);
    if !pov && (args.frame.is_some() || args.clock.is_some()) {
        bail!("--frame and --clock are for POV-Ray scenes (.pov); {} is not one", args.scene.display());
    }
    let mut scene = if pov && (args.frame.is_some() || args.clock.is_some()) {
        use photonix::scene::pov::{load_pov, options_for, Given};
        let given = Given { frame: args.frame, clock: args.clock, resolution: None };
        load_pov(&args.scene, &options_for(&args.scene, given)?)?
    } else {
        load_scene(&args.scene)?
    };
    if let Some(IntegratorArg(named)) = args.integrator {
        scene.set_integrator(named);
    }
    if !args.photons.given().is_empty() || args.photons.no_photons {
        scene.photon_options_given();
    }
    if let Some(why) = scene.render.integrator_auto {
        note!(
            "integrator {} (automatic: {why}; --integrator or [render] integrator picks another)",
            scene.render.integrator.name()
        );
    }
    for warning in &scene.warnings {
        note!("warning: {warning}");
    }
    let output = args.output.clone().unwrap_or_else(|| PathBuf::from(format!("{}.png", scene.name)));
    let is_exr = matches!(photonix::io::image::format_of(&output), Ok(photonix::io::image::Format::Exr));
    if args.layers && !is_exr {
        bail!("--layers writes a multi-layer EXR; give an output ending in .exr (e.g. -o layers.exr)");
    }
    if args.progressive.pass_range.is_some() && !is_exr {
        bail!("--pass-range writes an accumulation file, which is an EXR; give an output ending in .exr");
    }
    if args.progressive.resume && args.progressive.pass_range.is_none() {
        bail!("--resume continues an accumulation file of a pass range; give --pass-range A..B with it");
    }
    if args.progressive.resume && args.progressive.target_error.is_some() {
        bail!("--target-error needs the error estimate of every pass, which a resumed file does not keep; give one of them");
    }
    let png = |p: &Path| matches!(photonix::io::image::format_of(p), Ok(photonix::io::image::Format::Png));
    if args.exposure.is_some() && !png(&output) && !args.contact_sheet.as_deref().is_some_and(png) {
        bail!(
            "--exposure scales PNG output only, and {} is a linear-radiance EXR; leave it out, or write a .png",
            output.display()
        );
    }
    // Fail on a bad output path now, not after a long render, and never overwrite the inputs.
    check_output_path(&output)?;
    check_not_overwriting(&output, &args.scene, "the scene file")?;
    check_not_input(&output, &scene.inputs)?;
    if let Some(sheet) = &args.contact_sheet {
        check_output_path(sheet)?;
        check_not_overwriting(sheet, &args.scene, "the scene file")?;
        check_not_input(sheet, &scene.inputs)?;
        check_not_overwriting(sheet, &output, "the output image")?;
    }

    let (width, height) = args.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    let settings = FrameSettings {
        width,
        height,
        max_depth: args.max_depth.unwrap_or(scene.render.max_depth),
        seed: args.seed.unwrap_or(scene.render.seed),
    };
    // Every number was checked against its range when parsed (flags) or loaded (the scene).
    let photons = args.photons.apply(scene.photons, scene.render.integrator)?;
    let spp = args.spp.unwrap_or(scene.render.spp);
    let mut budget = args.progressive.budget(scene.render.passes)?;
    budget.adaptive |= scene.render.adaptive;
    let exposure = args.exposure.unwrap_or(0.0);
    // Read (and check) PHOTONIX_VALIDATION whatever the backend: a bad value is refused alike.
    let options = GpuOptions::from_env(args.device.clone())?;
    let (mut backend, mut backend_why) = match args.backend {
        BackendArg::Gpu => (Backend::Gpu, "--backend gpu".to_string()),
        BackendArg::Cpu => (Backend::Cpu, "--backend cpu".to_string()),
        BackendArg::Auto => {
            let (backend, why) = auto_backend(&list_devices(), args.device.is_some());
            (backend, format!("auto: {why}"))
        }
    };

    // Estimate the memory before taking any: host first (the device is not open yet)
    let estimate = |storage_limit| memory::estimate(width, height, photons.as_ref(), storage_limit);
    let host_estimate = estimate((backend == Backend::Gpu).then_some(u64::MAX));
    check_fits(&host_estimate, width, height, photons.as_ref(), available_host_memory(), None)?;

    // Prepare the scene and open the device
    let t = std::time::Instant::now();
    let buffers = prepare(&scene, &settings)?;
    let prepare_time = t.elapsed();
    if let Some(p) = &photons {
        check_radii(&buffers, p)?;
    }
    let provenance = Provenance::new(&buffers, spp, photons.as_ref());
    // --resume: start from the passes the output holds (read before any device is opened)
    let mut start = Accumulator::new(width, height);
    if let (true, Some(range)) = (args.progressive.resume, args.progressive.pass_range) {
        if let Some(acc) = resume_from(&output, range, &provenance, width, height)? {
            let done = acc.ranges[0].1;
            if done == range.1 {
                note!("{} holds passes {}..{} already; nothing to render", output.display(), range.0, range.1);
                return Ok(());
            }
            note!("resuming: {} holds passes {}..{done}; rendering {done}..{}", output.display(), range.0, range.1);
            budget.first = done;
            start = acc;
        }
    }
    if args.check {
        note!(
            "check: {} would render {width}x{height}, passes {}..{} of {spp} samples, to {}; nothing was written",
            args.scene.display(),
            budget.first,
            budget.end,
            output.display()
        );
        return Ok(());
    }
    let ctx = match backend {
        Backend::Gpu => match GpuContext::new(&options) {
            Ok(ctx) => {
                let info = ctx.info();
                let limit = info.max_storage_buffer_range.min(info.max_memory_allocation_size);
                if let Some(p) = &photons {
                    memory::check_photon_buffer(p, limit)?;
                }
                let mut device_estimate = estimate(Some(limit));
                device_estimate.parts.push(memory::scene_part(&buffers));
                check_fits(
                    &device_estimate,
                    width,
                    height,
                    photons.as_ref(),
                    None,
                    Some(info.device_local_heap_bytes),
                )?;
                Some(ctx)
            }
            // Auto chose a GPU that will not open: the CPU backend still renders the image.
            Err(e) if matches!(args.backend, BackendArg::Auto) && args.device.is_none() => {
                note!("warning: {e}; rendering on the CPU backend instead");
                (backend, backend_why) = (Backend::Cpu, "auto: the GPU failed to open".to_string());
                None
            }
            Err(e) => return Err(e.into()),
        },
        Backend::Cpu => None,
    };
    let mut renderer = Renderer::new(ctx.as_ref(), &buffers, photons.as_ref())?;
    // Denoise (never a pass range's part: merge --denoise denoises the sum), loading the
    // library before the render so that a missing one fails now, not after it.
    let denoise = args.denoise || scene.render.denoise;
    let denoiser = if denoise && !budget_is_range(&args) {
        let cuda = ctx.as_ref().is_some_and(|c| photonix::render::denoise::prefers_cuda(&c.info().name));
        Some(std::cell::RefCell::new(photonix::gpu::oidn::Denoiser::open(cuda)?))
    } else {
        None
    };
    if denoise && budget_is_range(&args) {
        note!("--pass-range: the part is not denoised; it carries the feature layers for `photonix merge --denoise`");
    }
    // The feature layers cost a camera ray per sample: only where they are written or denoise.
    renderer.set_features(args.layers || denoise);
    let denoise_time = std::cell::Cell::new(std::time::Duration::ZERO);
    // Ctrl-C and SIGTERM finish the dispatch under way; the finished passes are written.
    let _ = ctrlc::set_handler(|| photonix::render::STOP.store(true, std::sync::atomic::Ordering::Relaxed));

    let write_result = |acc: &Accumulator| -> Result<()> {
        if budget_is_range(&args) {
            write_accumulation(&output, acc, &provenance)?;
            return Ok(());
        }
        let mean = acc.mean();
        let noisy = mean.combined();
        let features = acc.mean_features();
        let denoised = match &denoiser {
            Some(d) => {
                let t = std::time::Instant::now();
                let image = photonix::render::denoise::denoise_image(&mut d.borrow_mut(), &noisy, features.as_ref())?;
                denoise_time.set(denoise_time.get() + t.elapsed());
                Some(image)
            }
            None => None,
        };
        let combined = denoised.as_ref().unwrap_or(&noisy);
        if args.layers {
            let mut named = vec![("combined", combined)];
            if denoised.is_some() {
                named.push(("noisy", &noisy));
            }
            named.extend(mean.named());
            if let Some(features) = &features {
                named.extend(features.named());
            }
            write_layers_exr(&output, &named)?;
        } else {
            write_image(&output, combined, exposure)?;
        }
        Ok(())
    };

    // Render the passes
    let bar = progress_bar(&scene.name);
    let total_passes = budget.end - budget.first;
    let mut stats = RenderStats::default();
    let mut last_checkpoint = std::time::Instant::now();
    let passes_done = std::cell::Cell::new(0u32);
    let paths_per_pass = photons.map_or(0, |p| p.photons as u64 + p.caustic_photons as u64);
    let max_group = renderer.max_pass_group(spp);
    let result = render_progressive_from(
        start,
        &budget,
        max_group,
        |first, most, pixels| -> Result<RenderOutput> {
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
            renderer.set_pixels(pixels.cloned());
            let out = renderer
                .render_passes(spp, first, most, &mut progress)
                .with_context(|| failure_message(&args, passes_done.get(), &output))?;
            add_stats(&mut stats, &out.stats);
            Ok(out)
        },
        |acc, elapsed| -> Result<()> {
            passes_done.set(acc.passes);
            if let Some(bar) = &bar {
                let photon_rate = paths_per_pass as f64 * acc.passes as f64 / elapsed.as_secs_f64().max(1e-9);
                bar.set_message(format!(
                    "{} pass {}/{} {:.2} M photons/s",
                    printable_message(&scene.name),
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
        return Err(Interrupted("interrupted before the first pass finished; no image was written".into()).into());
    }

    // Write the outputs and the summary
    denoise_time.set(std::time::Duration::ZERO);
    let t = std::time::Instant::now();
    write_result(&acc)?;
    if let Some(sheet) = &args.contact_sheet {
        let mean = acc.mean();
        let terms: Vec<&photonix::io::Image> = mean.named().iter().map(|(_, image)| *image).collect();
        write_image(sheet, &contact_sheet(&terms), exposure)?;
    }
    if renderer.gpu().is_some() {
        stats.stages.insert(0, ("setup".into(), renderer.setup_time()));
    }
    stats.stages.insert(0, ("prepare".into(), prepare_time));
    let write_time = t.elapsed().saturating_sub(denoise_time.get());
    if let Some(d) = &denoiser {
        stats.stages.push((format!("denoise ({})", d.borrow().device_type().name()), denoise_time.get()));
    }
    stats.stages.push(("write".into(), write_time));
    stats.samples_per_pixel = spp * acc.passes;
    let why = match reason {
        StopReason::Passes => "all passes done".to_string(),
        StopReason::Time => "time budget reached".to_string(),
        StopReason::TargetError => {
            format!("error estimate {:.2e} below the target", acc.error_estimate().unwrap_or(0.0))
        }
        StopReason::Interrupted => "interrupted".to_string(),
    };
    note!(
        "{} pass{} ({}; passes {}); {}",
        acc.passes,
        if acc.passes == 1 { "" } else { "es" },
        why,
        format_ranges(&acc.ranges),
        summary(&scene.name, &output, &stats, width, height, backend, &backend_why)
    );
    if reason == StopReason::Interrupted {
        let rerun = match args.progressive.pass_range {
            Some((a, b)) => format!(
                "; run the same command with --resume to render the rest of {a}..{b} (ci/slurm-farm's tasks do)"
            ),
            None => String::new(),
        };
        return Err(Interrupted(format!(
            "interrupted: {} holds passes {}, not all that were asked{rerun}",
            output.display(),
            format_ranges(&acc.ranges)
        ))
        .into());
    }
    Ok(())
}

/// A progress bar on stderr, or `None` when stderr is not a terminal (logs, tests).
fn progress_bar(total_label: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(0);
    let style = ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})")
        .expect("the progress template is valid")
        .progress_chars("=> ");
    bar.set_style(style);
    bar.set_message(printable_message(total_label));
    Some(bar)
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

/// The closing lines: image size, samples, backend and device, output path, stage times, ray
/// rate and, on the GPU, the time per kernel.
fn summary(name: &str, output: &Path, s: &RenderStats, width: u32, height: u32, backend: Backend, why: &str) -> String {
    let stages: Vec<String> = s.stages.iter().map(|(n, d)| format!("{n} {:.3} s", d.as_secs_f64())).collect();
    let kernels: Vec<String> =
        s.kernel_times.iter().map(|(n, secs, count)| format!("{n} {secs:.3} s in {count} dispatches")).collect();
    let render_secs = s.stage("render").as_secs_f64().max(1e-9);
    let mut line = format!(
        "{name}: {width}x{height}, {} spp, {} backend ({why}) on {} -> {}\n  {}; {:.2} M rays/s ({} rays)",
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
