//! `photonix merge`: combines the accumulation files of disjoint pass ranges (written by
//! `render --pass-range`) into one image or one accumulation file.

use std::path::PathBuf;

use anyhow::Result;

use photonix::io::{check_output_path, write_image};
use photonix::render::accumulation::{format_ranges, merge, write_accumulation};

#[derive(clap::Args)]
pub struct MergeArgs {
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

pub fn run(args: MergeArgs) -> Result<()> {
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
