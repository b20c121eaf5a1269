//! `photonix diff`: compares a render with a reference (relMSE, RMSE, per-channel mean ratio)
//! and optionally writes an error heatmap.

use std::path::PathBuf;

use anyhow::{bail, Result};

use photonix::io::metrics::{downsample, error_heatmap, mean_ratio, rel_mse, rmse};
use photonix::io::{check_output_path, read_exr, write_image};

#[derive(clap::Args)]
pub struct DiffArgs {
    /// The image to check (EXR, linear radiance)
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
    }
    let test = read_exr(&args.test)?;
    let mut reference = read_exr(&args.reference)?;
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
