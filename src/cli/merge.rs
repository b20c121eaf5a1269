//! `photonix merge`: combines the accumulation files of disjoint pass ranges (written by
//! `render --pass-range`) into one image or one accumulation file.

use std::path::PathBuf;

use anyhow::{bail, Result};

use photonix::gpu::oidn::Denoiser;
use photonix::io::image::{format_of, Format};
use photonix::io::{check_not_overwriting, check_output_path, write_image};
use photonix::render::accumulation::{format_ranges, merge, missing_passes, write_accumulation};
use photonix::render::denoise::denoise_image;

use super::parse::{parse_exposure, parse_passes};

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Accumulation files written by `render --pass-range`
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// The merged image (.exr or .png), or with --accumulation a merged accumulation file (.exr)
    #[arg(short, long)]
    output: PathBuf,
    /// Write an accumulation file (sums and pass count) instead of the final image
    #[arg(long)]
    accumulation: bool,
    /// PNG only: scale radiance by 2^EXPOSURE, -64 to 64, before sRGB encoding
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: Option<f32>,
    /// The parts must hold exactly passes 0..PASSES (1 to 1000000): a render farm's check that
    /// no task's part is missing or short; otherwise nothing is written
    #[arg(long, value_parser = parse_passes, allow_negative_numbers = true)]
    passes: Option<u32>,
    /// Denoise the merged image with Intel Open Image Denoise, guided by the parts' feature
    /// layers where every part carries them (`render --pass-range A..B --denoise` or --layers);
    /// the sum is denoised, never a part (see docs/denoising.md)
    #[arg(long)]
    denoise: bool,
}

pub fn run(args: MergeArgs) -> Result<()> {
    // Refuse what would be wrong or ignored before reading anything.
    check_output_path(&args.output)?;
    let is_exr = format_of(&args.output)? == Format::Exr;
    if args.accumulation && !is_exr {
        bail!(
            "--accumulation writes an accumulation file, which is an EXR; give an output ending in .exr, or leave out \
             --accumulation to write the final image as {}",
            args.output.display()
        );
    }
    if args.exposure.is_some() && is_exr {
        bail!(
            "--exposure scales PNG output only, and {} is an EXR; leave it out, or write a .png",
            args.output.display()
        );
    }
    if args.denoise && args.accumulation {
        bail!(
            "--accumulation writes sums for a later merge, and only a final image is denoised; leave out one of \
             --denoise and --accumulation"
        );
    }
    for (i, input) in args.inputs.iter().enumerate() {
        check_not_overwriting(&args.output, input, &format!("input {} of the merge", i + 1))?;
    }
    let (acc, provenance) = merge(&args.inputs)?;
    // Missing passes: those of 0..--passes, or, for a final image, the gaps between the parts'
    // ranges (a part lost or cut short). Nothing is written then: an image short of passes looks
    // like a finished one.
    let end = acc.ranges.iter().map(|r| r.1).max().unwrap_or(0);
    let missing = match args.passes {
        Some(n) => missing_passes(&acc.ranges, 0, n),
        None if !args.accumulation => {
            missing_passes(&acc.ranges, acc.ranges.iter().map(|r| r.0).min().unwrap_or(0), end)
        }
        None => Vec::new(),
    };
    if !missing.is_empty() {
        bail!(
            "the parts hold passes {} but passes {} are missing{}; nothing was written (render the missing passes with \
             `photonix render --pass-range A..B` and merge again)",
            format_ranges(&acc.ranges),
            format_ranges(&missing),
            args.passes.map_or(String::new(), |n| format!(" of 0..{n}"))
        );
    }
    if let Some(n) = args.passes.filter(|&n| end > n) {
        bail!(
            "the parts hold passes {}, beyond the {n} passes of --passes {n}; nothing was written",
            format_ranges(&acc.ranges)
        );
    }
    if args.accumulation {
        write_accumulation(&args.output, &acc, &provenance)?;
        note!("merged {} passes ({}) -> {}", acc.passes, format_ranges(&acc.ranges), args.output.display());
        return Ok(());
    }
    let mut image = acc.mean().combined();
    let mut how = String::new();
    if args.denoise {
        // The CPU device: merge runs where the parts are gathered, with no renderer's GPU.
        let mut denoiser = Denoiser::open(false)?;
        let features = acc.mean_features();
        if features.is_none() {
            note!(
                "warning: not every part carries feature layers (render them with --denoise or --layers); denoising \
                 without albedo and normal guides"
            );
        }
        let t = std::time::Instant::now();
        image = denoise_image(&mut denoiser, &image, features.as_ref())?;
        how = format!(", denoised in {:.3} s ({})", t.elapsed().as_secs_f64(), denoiser.device_type().name());
    }
    write_image(&args.output, &image, args.exposure.unwrap_or(0.0))?;
    note!("merged {} passes ({}){how} -> {}", acc.passes, format_ranges(&acc.ranges), args.output.display());
    Ok(())
}
