//! `photonix export`: the scene's geometry as glTF 2.0 binary, the same file as the editor's
//! *Download glTF* (`photonix::editor::gltf`).

use std::path::PathBuf;

use anyhow::{anyhow, bail, Result};

use photonix::editor::gltf::scene_glb;
use photonix::editor::SceneDocument;
use photonix::io::image::{check_not_input, same_file, write_atomically};

#[derive(clap::Args)]
pub struct ExportArgs {
    /// Scene file (TOML, see docs/scene-format.md)
    scene: PathBuf,
    /// The glTF binary to write (.glb): shapes and area lights as meshes, materials, the camera
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(args: ExportArgs) -> Result<()> {
    // Refuse a wrong output before reading the scene.
    let glb = args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if !glb {
        bail!("{}: photonix export writes glTF binary; give an output ending in .glb", args.output.display());
    }
    if args.output.is_dir() {
        bail!("{} is a folder; give a file name ending in .glb", args.output.display());
    }
    if same_file(&args.output, &args.scene) {
        bail!("{} is the scene file itself; give another output name", args.output.display());
    }
    let doc = SceneDocument::load_unconfined(&args.scene).map_err(|e| anyhow!("{e}"))?;
    check_not_input(&args.output, &doc.scene().inputs)?;
    for warning in &doc.scene().warnings {
        note!("warning: {warning}");
    }
    let bytes = scene_glb(&doc).map_err(|e| anyhow!("{}: {e}", args.scene.display()))?;
    write_atomically(&args.output, |tmp| std::fs::write(tmp, &bytes).map_err(|e| e.to_string()))?;
    note!("wrote {} ({} KiB)", args.output.display(), bytes.len().div_ceil(1024));
    Ok(())
}
