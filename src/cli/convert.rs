//! `photonix convert scene.pov -o scene.toml`: the POV-Ray scene in Photonix's own format, to
//! inspect and edit (docs/pov-ray.md). The TOML is checked by loading it before it is written.

use std::path::PathBuf;

use anyhow::{bail, Result};

use photonix::io::image::{same_file, write_atomically};
use photonix::scene::pov::{is_pov_path, load_pov, translate_file, PovOptions};

#[derive(clap::Args)]
pub struct ConvertArgs {
    /// POV-Ray scene file (.pov)
    scene: PathBuf,
    /// The TOML scene to write
    #[arg(short, long)]
    output: PathBuf,
    /// Image size as WIDTHxHEIGHT, as POV-Ray's +W +H (the scene reads it as image_width, image_height)
    #[arg(long, default_value = "320x240")]
    resolution: String,
    /// POV-Ray's clock (+K)
    #[arg(long, default_value_t = 0.0)]
    clock: f64,
}

pub fn run(args: ConvertArgs) -> Result<()> {
    if !is_pov_path(&args.scene) {
        bail!("{}: photonix convert reads POV-Ray scenes; give a file ending in .pov", args.scene.display());
    }
    let toml_out = args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if !toml_out {
        bail!("{}: photonix convert writes TOML; give an output ending in .toml", args.output.display());
    }
    if same_file(&args.output, &args.scene) {
        bail!("{} is the scene file itself; give another output name", args.output.display());
    }
    let Some((w, h)) =
        args.resolution.split_once('x').and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
    else {
        bail!("--resolution {}: give WIDTHxHEIGHT, e.g. 320x240", args.resolution);
    };
    if w == 0 || h == 0 || w > 65536 || h > 65536 {
        bail!("--resolution {}: width and height must be 1 to 65536", args.resolution);
    }
    let options = PovOptions { width: w, height: h, clock: args.clock, ..PovOptions::default() };
    // Load once so that a scene Photonix would refuse is reported at its .pov line, not later.
    let scene = load_pov(&args.scene, &options)?;
    for warning in &scene.warnings {
        note!("warning: {warning}");
    }
    let t = translate_file(&args.scene, &options)?;
    write_atomically(&args.output, |tmp| std::fs::write(tmp, &t.toml).map_err(|e| e.to_string()))?;
    note!(
        "wrote {} ({} shapes, {} lights, {} materials)",
        args.output.display(),
        scene.shapes.len(),
        scene.lights.len(),
        scene.materials.len()
    );
    Ok(())
}
