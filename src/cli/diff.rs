//! `photonix diff`: compares a render with a reference (relMSE, RMSE, per-channel mean ratio)
//! and optionally writes an error heatmap.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use photonix::io::metrics::{downsample, error_heatmap, mean_ratio, rel_mse, rmse};
use photonix::io::{check_not_overwriting, check_output_path, read_exr, write_image, Image};
use photonix::render::accumulation::{read_accumulation, AccumulationError};

#[derive(clap::Args)]
pub struct DiffArgs {
    /// The image to check (EXR, linear radiance; an accumulation file counts as its mean image)
    test: PathBuf,
    /// The reference (EXR, linear radiance); a larger reference is box-filtered down when the
    /// sizes divide evenly
    reference: PathBuf,
    /// Write a false-colour image of per-pixel relMSE (log scale, 1e-4 black to 1 white)
    #[arg(long, value_name = "PNG")]
    heatmap: Option<PathBuf>,
}

pub fn run(args: DiffArgs) -> Result<()> {
    if let Some(h) = &args.heatmap {
        check_output_path(h)?;
        check_not_overwriting(h, &args.test, "the test image")?;
        check_not_overwriting(h, &args.reference, "the reference image")?;
    }
    let test = read_image(&args.test)?;
    let mut reference = read_image(&args.reference)?;
    if (test.width, test.height) != (reference.width, reference.height) {
        let factor = reference.width / test.width.max(1);
        let scaled = |side: u32| side as u64 * factor as u64;
        if factor < 2 || scaled(test.width) != reference.width as u64 || scaled(test.height) != reference.height as u64
        {
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
    out!("relMSE {}", four_digits(rel_mse(&test, &reference)));
    out!("RMSE   {}", four_digits(rmse(&test, &reference)));
    out!("mean ratio (test/reference) R {:.4} G {:.4} B {:.4}", ratio[0], ratio[1], ratio[2]);
    if let Some(h) = &args.heatmap {
        write_image(h, &error_heatmap(&test, &reference), 0.0)?;
    }
    Ok(())
}

/// Small errors keep four significant digits (converged renders reach 1e-5 and below).
fn four_digits(x: f64) -> String {
    if x == 0.0 || x >= 1e-2 {
        format!("{x:.6}")
    } else {
        format!("{x:.3e}")
    }
}

/// An EXR as linear radiance. An accumulation file holds sums over its passes, not radiance: it is
/// read as its mean image (what `photonix merge` would write), and a note says so.
fn read_image(path: &Path) -> Result<Image> {
    match read_accumulation(path) {
        Ok((acc, _)) => {
            note!(
                "note: {} is an accumulation file of {} passes; comparing its mean image",
                path.display(),
                acc.passes
            );
            Ok(acc.mean().combined())
        }
        Err(AccumulationError::NotAccumulation { .. }) => Ok(read_exr(path)?),
        Err(e) => Err(e.into()),
    }
}
