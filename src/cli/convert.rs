//! `photonix convert scene.pov -o scene.toml` (or `scene.glb`, `scene.gltf`, `scene.xml`): the
//! POV-Ray, glTF or Mitsuba scene in Photonix's own format, to inspect and edit (docs/pov-ray.md,
//! docs/gltf.md, docs/mitsuba.md). The TOML is checked by loading it before it is written.

use std::path::PathBuf;

use anyhow::{bail, Result};

use photonix::io::image::{same_file, write_atomically};
use photonix::scene::pov::{is_pov_path, load_pov, options_for, translate_file, Given};
use photonix::scene::{gltf_scene, mitsuba};

#[derive(clap::Args)]
pub struct ConvertArgs {
    /// POV-Ray scene file (.pov), glTF 2.0 scene (.gltf, .glb) or Mitsuba scene (.xml)
    scene: PathBuf,
    /// The TOML scene to write
    #[arg(short, long)]
    output: PathBuf,
    /// Image size as WIDTHxHEIGHT: for a POV-Ray scene POV-Ray's +W +H (the scene reads it as image_width, image_height; default 320x240); for a glTF scene the camera's resolution (default: 360 rows, the width by the camera's aspect ratio)
    #[arg(long)]
    resolution: Option<String>,
    /// POV-Ray's clock (+K) [default: the frame's, from the .ini beside the scene, else 0]
    #[arg(long)]
    clock: Option<f64>,
    /// POV-Ray's frame number (frame_number) [default: the .ini's Initial_Frame, else 0]
    #[arg(long)]
    frame: Option<i64>,
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
    let given = args.resolution.as_deref();
    let resolution = given.unwrap_or("320x240");
    let Some((w, h)) =
        resolution.split_once('x').and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
    else {
        bail!("--resolution {resolution}: give WIDTHxHEIGHT, e.g. 320x240");
    };
    let max_side = photonix::limits::MAX_IMAGE_SIDE;
    if w == 0 || h == 0 || w > max_side || h > max_side || w as u64 * h as u64 > photonix::limits::MAX_PIXELS {
        bail!(
            "--resolution {resolution}: width and height must be 1 to {max_side}, at most {} pixels in all (docs/limits.md)",
            photonix::limits::MAX_PIXELS
        );
    }
    if gltf {
        return convert_gltf(&args, given.map(|_| (w, h)));
    }
    if xml {
        return convert_mitsuba(&args);
    }
    // The .ini beside the scene (size, frames, clock) under the flags given.
    let given = Given { frame: args.frame, clock: args.clock, resolution: given.map(|_| (w, h)) };
    let options = options_for(&args.scene, given)?;
    // Load once so that a scene Photonix would refuse is reported at its .pov line, not later.
    let scene = load_pov(&args.scene, &options)?;
    for warning in &scene.warnings {
        note!("warning: {warning}");
    }
    let t = translate_file(&args.scene, &options)?;
    write_toml(&args.output, &t.toml, &scene, &scene.inputs)
}

/// A glTF scene as TOML; the TOML names the glTF file relative to its own folder when it can
/// (the same folder), else by its absolute path.
fn convert_gltf(args: &ConvertArgs, resolution: Option<(u32, u32)>) -> Result<()> {
    let folder = |p: &std::path::Path| {
        let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
        parent.canonicalize().ok()
    };
    let model_file = match (folder(&args.scene), folder(&args.output)) {
        (Some(a), Some(b)) if a == b => None,
        _ => Some(std::path::absolute(&args.scene)?.display().to_string()),
    };
    let t = gltf_scene::translate_file_at(&args.scene, model_file.as_deref(), resolution)?;
    // Load the TOML as it will be read from its own place, so a refusal is reported now.
    let mut scene = photonix::scene::parse_scene(&t.toml, &args.output)?;
    let mut warnings = t.warnings.clone();
    warnings.extend(scene.warnings.drain(..).filter(|w| !gltf_scene::is_camera_note(w)));
    for warning in &warnings {
        note!("warning: {warning}");
    }
    // The translation was loaded as the output itself, which is then among the inputs: not that
    // one (its buffers and images stay).
    let own = args.output.canonicalize().ok();
    let inputs: Vec<PathBuf> = scene.inputs.iter().filter(|p| Some(*p) != own.as_ref()).cloned().collect();
    write_toml(&args.output, &t.toml, &scene, &inputs)
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
    write_toml(&args.output, &t.toml, &scene, &scene.inputs)
}

/// Writes the translation `toml` to `output` (whole or not at all) and says what it holds.
/// Never over a file of `inputs` (an include, a height field, a buffer).
fn write_toml(output: &std::path::Path, toml: &str, scene: &photonix::scene::Scene, inputs: &[PathBuf]) -> Result<()> {
    photonix::io::image::check_not_input(output, inputs)?;
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
