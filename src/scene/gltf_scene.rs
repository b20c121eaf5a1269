//! Whole glTF 2.0 scenes: `photonix render scene.glb` (or `.gltf`), `photonix convert`,
//! `photonix serve`. Like the POV-Ray front-end (`pov`), the file becomes a scene in Photonix's
//! own TOML format, which the TOML loader then reads, so every check, default and the editor's
//! save are shared:
//!
//! - `[camera]`: the file's first camera (perspective with its `yfov` and `aspectRatio`, or
//!   orthographic with `ymag`), placed by its node; a file without one gets a camera that frames
//!   the meshes' bounding box, with a warning.
//! - `[[shapes]]`: one `mesh` entry naming the file itself, with `lights = false`: the model
//!   importer (`model::gltf`) reads the node hierarchy (transforms composed), the triangle
//!   meshes and the materials with their textures.
//! - `[[lights]]`: one entry per KHR_lights_punctual light, converted from the file's photometric
//!   units (`light_entry`), so each can be edited on its own.
//!
//! Features and extensions Photonix does not read are named in warnings. docs/gltf.md describes
//! every mapping choice.

use std::fmt::Write;
use std::path::Path;

use glam::Vec3;

use super::model::{self, Model, ModelCamera, ModelLight, ModelProjection};
use super::SceneError;

/// Lumens per watt at 555 nm: the glTF spec's candela and lux become W/sr and W/m^2 by this
/// factor (KHR_lights_punctual; the SI definition of the candela).
pub const LUMENS_PER_WATT: f32 = 683.0;

/// The image height of the translated camera; the width follows the camera's aspect ratio.
pub const IMAGE_HEIGHT: u32 = 360;

/// Aspect ratio when the camera gives none (glTF leaves it to the viewport).
const DEFAULT_ASPECT: f32 = 16.0 / 9.0;

/// The first words of every translation (a saved translation keeps them).
pub const HEADER: &str = "# Translated from the glTF scene";

/// Extensions this front-end reads (the rest are named in a warning).
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// A glTF scene as TOML text.
#[derive(Clone, Debug)]
pub struct Translation {
    pub toml: String,
    pub warnings: Vec<String>,
}

/// True when `path` names a glTF file (extension `.gltf` or `.glb`, any case).
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Loads a glTF scene: translates it and loads the TOML as `load_scene` loads a file.
pub fn load_gltf(path: &Path) -> Result<super::Scene, SceneError> {
    let t = translate_file(path, None)?;
    let mut scene = super::parse_scene(&t.toml, path)?;
    let mut warnings = t.warnings;
    warnings.extend(scene.warnings.drain(..).filter(|w| !is_camera_note(w)));
    scene.warnings = warnings;
    Ok(scene)
}

/// The mesh importer's note that a model's cameras are not used: in a translation (text starting
/// with `HEADER`) the scene's `[camera]` is the file's own, so the note would mislead.
pub fn is_camera_note(warning: &str) -> bool {
    warning.ends_with("camera(s) are not used; the scene's [camera] applies")
}

/// Reads a glTF file and writes it as TOML. `model_file` is how the TOML names the glTF file
/// (relative to the TOML's folder); `None`: its file name, for a TOML beside it.
pub fn translate_file(path: &Path, model_file: Option<&str>) -> Result<Translation, SceneError> {
    translate_file_at(path, model_file, None)
}

/// `translate_file` with the image size `resolution` (`convert --resolution`) in place of the
/// one the camera's aspect ratio gives.
pub fn translate_file_at(
    path: &Path,
    model_file: Option<&str>,
    resolution_override: Option<(u32, u32)>,
) -> Result<Translation, SceneError> {
    let to_error = |e: model::ModelError| {
        if e.not_found {
            SceneError::Read {
                path: path.to_path_buf(),
                cause: std::io::Error::new(std::io::ErrorKind::NotFound, "file not found"),
            }
        } else {
            SceneError::Syntax { location: e.location(), message: e.message }
        }
    };
    let bytes = model::read_model_file(path).map_err(to_error)?;
    let model = model::gltf::parse_gltf(&bytes, path).map_err(to_error)?;
    let location = crate::limits::printable_message(&path.display().to_string());
    let mut warnings: Vec<String> = Vec::new();
    let info = document_info(&bytes);
    for w in &info.notes {
        warnings.push(format!("{location}: {w}"));
    }

    let file_name = match model_file {
        Some(f) => f.to_string(),
        None => path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
    };
    let mut toml = String::new();
    let _ = writeln!(toml, "{HEADER} {} by Photonix (docs/gltf.md).\n", crate::limits::printable(&file_name));

    // Camera
    let (lo, hi) = bounds(&model);
    match model.cameras.first() {
        Some(camera) => {
            if model.cameras.len() > 1 {
                warnings.push(format!(
                    "{location}: the file has {} cameras; the first (\"{}\") is used",
                    model.cameras.len(),
                    crate::limits::printable(&camera.name)
                ));
            }
            camera_entry(&mut toml, camera, lo, hi, resolution_override).map_err(|message| SceneError::Syntax {
                location: format!("{location}: camera \"{}\"", crate::limits::printable(&camera.name)),
                message,
            })?;
        }
        None => {
            warnings.push(format!(
                "{location}: the file has no camera; one is placed to frame the scene's bounding box (export the \
                 camera too, e.g. Blender's \"Include > Cameras\")"
            ));
            framing_camera(&mut toml, lo, hi, resolution_override);
        }
    }

    // Meshes: the importer reads the node hierarchy and the materials.
    let _ = writeln!(
        toml,
        "[[shapes]]\nname = {}\ntype = \"mesh\"\nfile = {}\nlights = false   # the file's lights are the [[lights]] below\n",
        quoted(&file_name),
        quoted(&file_name)
    );

    // Lights
    for (i, light) in model.lights.iter().enumerate() {
        let name = model.light_names.get(i).filter(|n| !n.is_empty()).cloned().unwrap_or_else(|| format!("light {i}"));
        if let ModelLight::Spot { inner_deg, outer_deg, .. } = *light {
            if !(outer_deg > 0.0 && outer_deg <= 90.0 && inner_deg >= 0.0 && inner_deg < outer_deg) {
                warnings.push(format!(
                    "{location}: light \"{}\": innerConeAngle {} and outerConeAngle {} degrees are outside glTF's \
                     range (0 <= inner < outer <= 90 degrees); the angles are clamped to it",
                    crate::limits::printable(&name),
                    crate::limits::fmt_f32(inner_deg),
                    crate::limits::fmt_f32(outer_deg)
                ));
            }
        }
        light_entry(&mut toml, &name, light);
    }
    for (name, range) in &info.light_ranges {
        warnings.push(format!(
            "{location}: light \"{}\": `range` {range} is ignored; the light falls off with the inverse square of \
             the distance without a cutoff",
            crate::limits::printable(name)
        ));
    }
    Ok(Translation { toml, warnings })
}

/// A number as TOML reads it (finite: the importer checked every number).
fn num(v: f32) -> String {
    let v = if v == 0.0 { 0.0 } else { v };
    format!("{v}")
}

fn vec3(v: Vec3) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

/// A TOML basic string.
fn quoted(s: &str) -> String {
    toml_edit::Value::from(s).to_string().trim().to_string()
}

/// The bounding box of the model's meshes, in the file's world space.
fn bounds(model: &Model) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for mesh in &model.meshes {
        for &p in &mesh.positions {
            let w = mesh.model_from_mesh.transform_point3(p);
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    if lo.x > hi.x {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (lo, hi)
    }
}

/// Image size for an aspect ratio (width over height).
fn resolution(aspect: Option<f32>) -> (u32, u32) {
    let aspect = aspect.filter(|a| a.is_finite() && *a > 0.0).unwrap_or(DEFAULT_ASPECT).clamp(0.05, 20.0);
    ((IMAGE_HEIGHT as f32 * aspect).round().max(1.0) as u32, IMAGE_HEIGHT)
}

/// The file's camera: glTF cameras look down their node's -z with +y up.
fn camera_entry(
    toml: &mut String,
    camera: &ModelCamera,
    lo: Vec3,
    hi: Vec3,
    resolution_override: Option<(u32, u32)>,
) -> Result<(), String> {
    // `look_at` only sets the direction: a point at the scene's distance keeps it well away
    // from the camera in 32-bit floats.
    let reach = ((hi - lo).length() * 0.5).max((0.5 * (lo + hi) - camera.position).length()).max(1e-3);
    let look_at = camera.position + camera.forward * reach;
    let (w, h) = resolution_override.unwrap_or_else(|| resolution(camera.aspect));
    let _ = writeln!(toml, "[camera]");
    if !camera.name.is_empty() {
        let _ = writeln!(toml, "# glTF camera {}", quoted(&camera.name));
    }
    match camera.projection {
        ModelProjection::Perspective { yfov_deg } => {
            // glTF requires yfov > 0; Photonix's range is docs/limits.md's. A camera outside it
            // would render nothing like the file's, so it is refused, not clamped.
            let min = crate::limits::MIN_FOV_DEGREES as f32;
            if !(yfov_deg >= min && yfov_deg <= 180.0 - min) {
                return Err(format!(
                    "yfov is {} degrees ({} radians); a perspective camera's yfov is {} to {} degrees (docs/limits.md)",
                    crate::limits::fmt_f32(yfov_deg),
                    crate::limits::fmt_f32(yfov_deg.to_radians()),
                    crate::limits::fmt_f32(min),
                    crate::limits::fmt_f32(180.0 - min)
                ));
            }
            let _ = writeln!(toml, "fov = {}", num(yfov_deg));
        }
        ModelProjection::Orthographic { view_height } => {
            let _ = writeln!(toml, "type = \"orthographic\"\nview_height = {}", num(view_height.abs().max(1e-6)));
        }
    }
    let _ = writeln!(
        toml,
        "position = {}\nlook_at = {}\nup = {}\nresolution = [{w}, {h}]\n",
        vec3(camera.position),
        vec3(look_at),
        vec3(camera.up)
    );
    Ok(())
}

/// A perspective camera that sees the whole bounding box: 40 degrees vertically, from above and
/// to the front right (+x, +y, +z: glTF's front is +z), at the distance where the bounding
/// sphere fits the vertical field of view.
fn framing_camera(toml: &mut String, lo: Vec3, hi: Vec3, resolution_override: Option<(u32, u32)>) {
    let fov_deg: f32 = 40.0;
    let center = 0.5 * (lo + hi);
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let distance = radius / (0.5 * fov_deg.to_radians()).sin() * 1.05;
    let position = center + Vec3::new(0.6, 0.45, 1.0).normalize() * distance;
    let (w, h) = resolution_override.unwrap_or_else(|| resolution(None));
    let _ = writeln!(
        toml,
        "[camera]\n# no camera in the file: this one frames the scene's bounding box\nfov = {}\nposition = {}\nlook_at = \
         {}\nup = [0, 1, 0]\nresolution = [{w}, {h}]\n",
        num(fov_deg),
        vec3(position),
        vec3(center)
    );
}

/// A KHR_lights_punctual light as a `[[lights]]` entry. glTF gives point and spot lights in
/// candela and directional lights in lux; Photonix wants W/sr and W/m^2, so both are divided by
/// 683 lm/W. This inverts Blender's exporter exactly (its default "Standard" lighting mode,
/// gltf2_blender_gather_lights.py): a point or spot light of P watts is written as
/// P / (4 pi) * 683 cd and a sun of E W/m^2 as E * 683 lux.
fn light_entry(toml: &mut String, name: &str, light: &ModelLight) {
    let _ = writeln!(toml, "[[lights]]\nname = {}", quoted(name));
    match *light {
        ModelLight::Point { position, intensity } => {
            let _ = writeln!(
                toml,
                "type = \"point\"\nposition = {}\nintensity = {}   # W/sr: the file's candela / 683\n",
                vec3(position),
                vec3(intensity / LUMENS_PER_WATT)
            );
        }
        ModelLight::Spot { position, direction, intensity, inner_deg, outer_deg } => {
            let outer = outer_deg.clamp(0.01, 90.0);
            let inner = inner_deg.clamp(0.0, outer);
            let _ = writeln!(
                toml,
                "type = \"spot\"\nposition = {}\ndirection = {}\nintensity = {}   # W/sr: the file's candela / 683\n\
                 inner_angle = {}\nouter_angle = {}\n",
                vec3(position),
                vec3(direction.normalize_or(Vec3::NEG_Y)),
                vec3(intensity / LUMENS_PER_WATT),
                num(inner),
                num(outer)
            );
        }
        ModelLight::Directional { direction, irradiance } => {
            let _ = writeln!(
                toml,
                "type = \"distant\"\ndirection = {}\nirradiance = {}   # W/m^2: the file's lux / 683\n",
                vec3(direction.normalize_or(Vec3::NEG_Y)),
                vec3(irradiance / LUMENS_PER_WATT)
            );
        }
    }
}

/// What the document says beyond the model: who wrote it, and what Photonix leaves out.
#[derive(Default)]
struct DocumentInfo {
    /// Warnings naming what is not read.
    notes: Vec<String>,
    /// (light name, range) of lights with a `range`.
    light_ranges: Vec<(String, f32)>,
}

fn document_info(bytes: &[u8]) -> DocumentInfo {
    let mut info = DocumentInfo::default();
    let Ok(gltf) = ::gltf::Gltf::from_slice(bytes) else { return info };
    let doc = &gltf.document;
    let unsupported: Vec<&str> = doc.extensions_used().filter(|e| !SUPPORTED_EXTENSIONS.contains(e)).collect();
    if !unsupported.is_empty() {
        info.notes.push(format!(
            "extensions not supported, ignored: {}",
            unsupported.iter().map(|e| crate::limits::printable(e)).collect::<Vec<_>>().join(", ")
        ));
    }
    let count = |n: usize, what: &str, why: &str| (n > 0).then(|| format!("{n} {what} ignored ({why})"));
    let morphs = doc.meshes().filter(|m| m.primitives().any(|p| p.morph_targets().next().is_some())).count();
    let skins = doc.skins().count();
    let lines = doc
        .meshes()
        .flat_map(|m| m.primitives())
        .filter(|p| {
            !matches!(
                p.mode(),
                ::gltf::mesh::Mode::Triangles | ::gltf::mesh::Mode::TriangleStrip | ::gltf::mesh::Mode::TriangleFan
            )
        })
        .count();
    let extra_scenes = doc.scenes().count().saturating_sub(1);
    info.notes.extend(
        [
            count(doc.animations().count(), "animation(s)", "the scene renders as it stands, unanimated"),
            count(skins, "skin(s)", "skinned meshes render in their bind pose"),
            count(morphs, "mesh(es) with morph targets", "the base shape renders, weights are not applied"),
            count(lines, "point or line primitive(s)", "they have no surface"),
            count(extra_scenes, "further scene(s)", "only the default scene is read"),
        ]
        .into_iter()
        .flatten(),
    );
    for m in doc.materials() {
        let name = crate::limits::printable(m.name().unwrap_or("unnamed"));
        if m.transmission().is_some_and(|t| t.transmission_factor() > 0.0) && m.volume().is_some() {
            info.notes.push(format!(
                "material \"{name}\": KHR_materials_volume's attenuation is not read; its transmission renders as \
                 clear glass"
            ));
        }
    }
    if let Some(lights) = doc.lights() {
        for l in lights {
            if let Some(range) = l.range() {
                info.light_ranges.push((l.name().unwrap_or("unnamed").to_string(), range));
            }
        }
    }
    info
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gltf_paths_are_recognised_in_any_case() {
        assert!(is_gltf_path(Path::new("a/scene.glb")));
        assert!(is_gltf_path(Path::new("scene.GLTF")));
        assert!(!is_gltf_path(Path::new("scene.toml")));
    }

    #[test]
    fn resolution_follows_the_aspect_ratio() {
        assert_eq!(resolution(Some(16.0 / 9.0)), (640, 360));
        assert_eq!(resolution(Some(1.0)), (360, 360));
        assert_eq!(resolution(None), (640, 360));
    }

    #[test]
    fn point_light_candela_become_watts_per_steradian() {
        let mut toml = String::new();
        let light = ModelLight::Point { position: Vec3::ZERO, intensity: Vec3::splat(683.0) };
        light_entry(&mut toml, "bulb", &light);
        assert!(toml.contains("intensity = [1, 1, 1]"), "{toml}");
    }

    #[test]
    fn sun_lux_become_watts_per_square_metre() {
        let sun = ModelLight::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::splat(2.0 * 683.0) };
        let mut toml = String::new();
        light_entry(&mut toml, "sun", &sun);
        assert!(toml.contains("irradiance = [2, 2, 2]"), "{toml}");
    }
}
