//! `photonix convert scene.pov -o scene.toml` (or `scene.glb`, `scene.gltf`, `scene.xml`): the
//! POV-Ray, glTF or Mitsuba scene in Photonix's own format, to inspect and edit (docs/pov-ray.md,
//! docs/gltf.md, docs/mitsuba.md). The TOML is checked by loading it before it is written.

use std::path::PathBuf;

use anyhow::{bail, Result};

use photonix::io::image::{same_file, write_atomically};
use photonix::scene::pov::{is_pov_path, load_pov, translate_file, PovOptions};
use photonix::scene::{gltf_scene, mitsuba};

#[derive(clap::Args)]
pub struct ConvertArgs {
    /// POV-Ray scene file (.pov), glTF 2.0 scene (.gltf, .glb) or Mitsuba scene (.xml)
    scene: PathBuf,
    /// The TOML scene to write
    #[arg(short, long)]
    output: PathBuf,
    /// POV-Ray scenes: image size as WIDTHxHEIGHT, as POV-Ray's +W +H (the scene reads it as image_width, image_height); a glTF scene's follows its camera
    #[arg(long, default_value = "320x240")]
    resolution: String,
    /// POV-Ray's clock (+K)
    #[arg(long, default_value_t = 0.0)]
    clock: f64,
}

pub fn run(args: ConvertArgs) -> Result<()> {
    let gltf = gltf_scene::is_gltf_path(&args.scene);
    let xml = mitsuba::is_mitsuba_path(&args.scene);
    if !is_pov_path(&args.scene) && !gltf && !xml {
        bail!(
            "{}: photonix convert reads POV-Ray, glTF and Mitsuba scenes; give a file ending in .pov, .gltf, .glb or .xml",
            args.scene.display()
        );
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
    if gltf {
        return convert_gltf(&args);
    }
    if xml {
        return convert_mitsuba(&args);
    }
    let options = PovOptions { width: w, height: h, clock: args.clock, ..PovOptions::default() };
    // Load once so that a scene Photonix would refuse is reported at its .pov line, not later.
    let scene = load_pov(&args.scene, &options)?;
    for warning in &scene.warnings {
        note!("warning: {warning}");
    }
    let t = translate_file(&args.scene, &options)?;
    write_toml(&args.output, &t.toml, &scene)
}

/// A glTF scene as TOML; the TOML names the glTF file relative to its own folder when it can
/// (the same folder), else by its absolute path.
fn convert_gltf(args: &ConvertArgs) -> Result<()> {
    let folder = |p: &std::path::Path| {
        let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
        parent.canonicalize().ok()
    };
    let model_file = match (folder(&args.scene), folder(&args.output)) {
        (Some(a), Some(b)) if a == b => None,
        _ => Some(std::path::absolute(&args.scene)?.display().to_string()),
    };
    let t = gltf_scene::translate_file(&args.scene, model_file.as_deref())?;
    // Load the TOML as it will be read from its own place, so a refusal is reported now.
    let mut scene = photonix::scene::parse_scene(&t.toml, &args.output)?;
    let mut warnings = t.warnings.clone();
    warnings.extend(scene.warnings.drain(..).filter(|w| !gltf_scene::is_camera_note(w)));
    for warning in &warnings {
        note!("warning: {warning}");
    }
    write_toml(&args.output, &t.toml, &scene)
}

/// A Mitsuba scene as TOML. Its file names are relative to the scene's folder, so the TOML
/// must be written there.
fn convert_mitsuba(args: &ConvertArgs) -> Result<()> {
    let folder = |p: &std::path::Path| {
        let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
        parent.canonicalize().ok()
    };
    if folder(&args.scene) != folder(&args.output) {
        bail!(
            "{}: write the TOML into the folder of {} (the meshes and textures it names are relative to it)",
            args.output.display(),
            args.scene.display()
        );
    }
    // Load once so that a scene Photonix would refuse is reported at its XML line.
    let scene = mitsuba::load_mitsuba(&args.scene)?;
    for warning in &scene.warnings {
        note!("warning: {warning}");
    }
    let t = mitsuba::translate_file(&args.scene)?;
    write_toml(&args.output, &t.toml, &scene)
}

/// Writes the translation `toml` to `output` (whole or not at all) and says what it holds.
fn write_toml(output: &std::path::Path, toml: &str, scene: &photonix::scene::Scene) -> Result<()> {
    write_atomically(output, |tmp| std::fs::write(tmp, toml).map_err(|e| e.to_string()))?;
    note!(
        "wrote {} ({} shapes, {} lights, {} materials)",
        output.display(),
        scene.shapes.len(),
        scene.lights.len(),
        scene.materials.len()
    );
    Ok(())
}
